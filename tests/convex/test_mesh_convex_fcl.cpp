// SPDX-License-Identifier: MIT
// Mesh against convex shape (convex/mesh_convex.hpp) against FCL 0.7 on the same meshes, shapes and
// poses, FCL set up as its users do: fcl::BVHModel<OBBRSS> built with beginModel / addSubModel /
// endModel, the shapes as fcl::Sphere / Capsule / Cylinder / Cone / Box / Convex
// (tests/support/convex_fcl.hpp), fcl::collide and fcl::distance with default requests. Boolean
// answers must match wherever impact's answer is certified away from touching by more than 1e-6 of
// the shape's size (apart: the GJK distance, an upper bound within 1e-10; overlapping: the depth's
// certified lower bound, depth - depth_gap); separation distances must agree within FCL's accuracy
// (1e-3 of the size, as in test_convex_fcl.cpp) and never exceed FCL's by more than 1e-9 of it.
// Meshes: generated ones always, spot.obj from IMPACT_DATA_DIR when it is set (skipped otherwise).
#include "impact/convex/mesh_convex.hpp"
#include "impact/geometry/mesh_generators.hpp"
#include "support/convex_fcl.hpp"
#include "support/convex_oracle.hpp"
#include "support/data.hpp"
#include "support/fcl_oracle.hpp"
#include "support/obj_reader.hpp"
#include "support/sanitizer.hpp"

#include <fcl/geometry/bvh/BVH_model.h>
#include <fcl/math/bv/OBBRSS.h>

#include <gtest/gtest.h>

namespace impact_mesh_convex_fcl_test {

using namespace impact;
using impact::test::zoo;
using Pose = RigidTransform<double>;
using V3 = Eigen::Vector3d;

struct McfCounts {
  int apart = 0, overlapping = 0;
};

template <class Shape>
McfCounts mcf_compare(const char* name, const TriangleMesh<double>& m, const MeshBvh<Obb<double>>& tree,
                      const std::shared_ptr<fcl::BVHModel<fcl::OBBRSSd>>& model, const Shape& s, int n, std::uint64_t seed) {
  const auto shape = test::to_fcl_shape(s);
  const double size = shape_size(s);
  test::Rng rng(seed);
  McfCounts counts;
  for (int i = 0; i < n; ++i) {
    const Pose pm{rng.rotation(), rng.vec(-1, 1)};
    const V3 v = m.V.row(static_cast<Eigen::Index>(rng.index(std::uint64_t(m.V.rows())))).transpose();
    const Pose ps{rng.rotation(), pm.apply(v) + rng.vec(-1.5 * size, 1.5 * size)};
    fcl::CollisionRequestd creq;
    fcl::CollisionResultd cres;
    fcl::collide(model.get(), test::to_fcl(pm), shape.get(), test::to_fcl(ps), creq, cres);
    const bool theirs = cres.isCollision();
    const bool ours = mesh_convex_collides(tree, pm, s, ps);
    const auto d = mesh_convex_distance(tree, pm, s, ps);
    if (d.distance > 1e-6 * size) {
      ++counts.apart;
      EXPECT_FALSE(ours) << name;
      EXPECT_FALSE(theirs) << name << ": impact distance " << d.distance;
      fcl::DistanceRequestd dreq;
      fcl::DistanceResultd dres;
      fcl::distance(model.get(), test::to_fcl(pm), shape.get(), test::to_fcl(ps), dreq, dres);
      EXPECT_LE(d.distance, dres.min_distance + 1e-9 * size) << name;
      EXPECT_NEAR(d.distance, dres.min_distance, 1e-3 * size) << name;
      continue;
    }
    const auto c = mesh_convex_contacts(tree, pm, s, ps);
    EXPECT_TRUE(c.colliding) << name;
    double certified = 0;
    for (const auto& tc : c.contacts) certified = std::max(certified, tc.contact.depth - tc.contact.depth_gap);
    if (certified > 1e-6 * size) {
      ++counts.overlapping;
      EXPECT_TRUE(ours) << name;
      EXPECT_TRUE(theirs) << name << ": impact depth " << certified;
    }
  }
  return counts;
}

void mcf_run_all(const TriangleMesh<double>& m, int n, std::uint64_t seed) {
  const MeshBvh<Obb<double>> tree(m);
  const auto model = test::make_fcl_model<fcl::OBBRSSd>(m);
  const auto& z = zoo();
  const auto check = [&](const char* name, const auto& s, std::uint64_t k) {
    const McfCounts c = mcf_compare(name, m, tree, model, s, n, seed + k);
    if (!IMPACT_TEST_SANITIZED) {  // coverage (a sanitizer build's few poses may miss a case)
      EXPECT_GT(c.apart, n / 10) << name;
      EXPECT_GT(c.overlapping, n / 10) << name;
    }
  };
  check("sphere", z.sphere, 1);
  check("capsule", z.capsule, 2);
  check("cylinder", z.cylinder, 3);
  check("cone", z.cone, 4);
  check("box", z.box, 5);
  check("hull", z.hull, 6);
}

TEST(MeshConvexFcl, GeneratedMeshes) {
  TriangleMesh<double> bumpy = make_icosphere(1.5, 3);
  test::Rng rng(5150);
  for (Eigen::Index i = 0; i < bumpy.V.rows(); ++i) bumpy.V.row(i) *= rng.uniform(0.9, 1.1);
  mcf_run_all(bumpy, IMPACT_TEST_SANITIZED ? 8 : 40, 100);
  mcf_run_all(make_torus(1.5, 0.4, 40, 16), IMPACT_TEST_SANITIZED ? 8 : 40, 200);
}

TEST(MeshConvexFcl, SpotMesh) {
  IMPACT_REQUIRE_DATA(path, "meshes/spot.obj");
  mcf_run_all(test::read_obj<double>(path), IMPACT_TEST_SANITIZED ? 6 : 24, 300);
}

}  // namespace impact_mesh_convex_fcl_test
