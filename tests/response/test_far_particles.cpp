// SPDX-License-Identifier: MIT
// Backtracking far from the origin, where the coordinates' spacing is as large as a step's motion
// or larger (float near 2^20: 1/16 for legs of 1/30): a torus translated far away (2^20 and
// (1e6, -5e5, 2.5e5) in float, 2^40 and 2^48 in double, and near the largest coordinates the
// library accepts, 2^27 in float and 2^199 in double, the torus scaled to span a few dozen
// spacings), particles inside a container box around it, and every leg a particle travels
// (step_particle's on_leg, the positions as stored) audited against every triangle in exact
// arithmetic (support/exact_triangle.hpp): no leg may meet a triangle. The particles start off
// the surface (checked exactly), so a leg meeting one either crossed it or ended on it. Before the
// step cast the chord to the stored (rounded) end, 1 to 130 legs a case crossed or ended on the
// torus. Projection on the same scenes: no throw, no NaN (it is documented to let particles
// through; not asserted here).
#include "impact/bvh/wide_bvh.hpp"
#include "impact/geometry/mesh_generators.hpp"
#include "impact/query/distance_grid.hpp"
#include "impact/response/particle_step.hpp"
#include "support/exact_triangle.hpp"
#include "support/random.hpp"
#include "support/sanitizer.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace impact {
namespace {

/// A far-away scene: the torus scaled by `scale` and moved by `offset` (computed in double, then
/// rounded to S, so the colliders and the audit see the same triangles).
template <class S> struct FarScene {
  TriangleMesh<S> mesh;
  Aabb<S> box;
  FarScene(const Eigen::Vector3d& offset, double scale) {
    const TriangleMesh<double> t = make_torus<double>(1.0, 0.4, 24, 12);
    mesh.F = t.F;
    mesh.V.resize(t.V.rows(), 3);
    for (Eigen::Index i = 0; i < t.V.rows(); ++i)
      for (int k = 0; k < 3; ++k) mesh.V(i, k) = S(t.V(i, k) * scale + offset[k]);
    for (int i = 0; i < mesh.num_vertices(); ++i) box.extend(mesh.vertex(i));
  }
  /// Whether the closed segment a -> b meets a triangle of the mesh (exact).
  bool touches(const Vec3<S>& a, const Vec3<S>& b) const {
    Aabb<S> sb;
    sb.extend(a);
    sb.extend(b);
    for (int t = 0; t < mesh.num_triangles(); ++t) {
      const Triangle<S> tri = mesh.triangle(t);
      Aabb<S> tb;
      tb.extend(tri.a);
      tb.extend(tri.b);
      tb.extend(tri.c);
      if (overlap(tb, sb) && test::triangles_intersect_exact(tri, Triangle<S>(a, b, b))) return true;
    }
    return false;
  }
};

/// Steps particles in the scene with backtracking (the mesh with a distance grid and a wide tree
/// when `accelerated`, else its binary tree alone; the scale-aware surface offset, or an absolute
/// one of a thousandth of the leg, far below the coordinates' rounding, when `tiny_offset`) and
/// returns the number of legs that met a triangle.
template <class S>
int touching_legs(const FarScene<S>& scene, bool accelerated, bool tiny_offset, std::uint64_t seed, int particles, int steps) {
  const MeshBvh<Aabb<S>> bvh(scene.mesh);
  const S diag = S(2) * scene.box.half_diagonal();
  const Aabb<S> container(Vec3<S>(scene.box.min.array() - S(0.05) * diag), Vec3<S>(scene.box.max.array() + S(0.05) * diag));
  ColliderSet<S> cs;
  cs.meshes.emplace_back(bvh, ColliderSide::TwoSided, Material<S>::elastic());
  cs.boxes.emplace_back(container, ColliderSide::Inside, Material<S>::elastic());
  DistanceGridConfig<S> gcfg;
  gcfg.resolution = 32;
  const DistanceGrid<S> grid = accelerated ? DistanceGrid<S>(bvh, gcfg) : DistanceGrid<S>();
  const WideBvh<S> wide = accelerated ? WideBvh<S>(scene.mesh) : WideBvh<S>();
  if (accelerated) {
    cs.meshes[0].distance_grid = &grid;
    cs.meshes[0].wide_tree = &wide;
  }
  const S dt = S(0.01);
  const double speed = 0.01 * double(diag) / double(dt);  // about 1 % of the diagonal a step
  StepOptions<S> opt;
  opt.threads = 1;
  opt.gravity = Vec3<S>(S(0), S(-speed / (50 * double(dt))), S(0));
  if (tiny_offset) opt.surface_offset = S(speed * double(dt) * 1e-3);
  test::Rng rng(seed);
  std::vector<Particle<S>> ps;
  while (int(ps.size()) < particles) {
    Particle<S> p;
    for (int k = 0; k < 3; ++k) p.position[k] = S(rng.uniform(double(scene.box.min[k]), double(scene.box.max[k])));
    if (scene.touches(p.position, p.position)) continue;  // start off the surface
    const Eigen::Vector3d dir = rng.vec(-1, 1).normalized();
    p.velocity = (dir * speed * rng.uniform(0.5, 1.5)).cast<S>();
    ps.push_back(p);
  }
  int bad = 0;
  for (int s = 0; s < steps; ++s)
    for (auto& p : ps)
      step_particle(p, cs, dt, opt, [&](const Vec3<S>& from, const Vec3<S>& to) { bad += scene.touches(from, to) ? 1 : 0; });
  return bad;
}

/// Projection on the same scene: every position stays finite.
template <class S> bool projection_finite(const FarScene<S>& scene, std::uint64_t seed) {
  const MeshBvh<Aabb<S>> bvh(scene.mesh);
  ColliderSet<S> cs;
  cs.meshes.emplace_back(bvh, ColliderSide::TwoSided, Material<S>::elastic());
  cs.meshes[0].strategy = Strategy::Project;
  const S diag = S(2) * scene.box.half_diagonal();
  const S dt = S(0.01);
  StepOptions<S> opt;
  opt.threads = 1;
  test::Rng rng(seed);
  std::vector<Particle<S>> ps(100);
  for (auto& p : ps) {
    for (int k = 0; k < 3; ++k) p.position[k] = S(rng.uniform(double(scene.box.min[k]), double(scene.box.max[k])));
    p.velocity = (rng.vec(-1, 1) * (double(diag) / double(dt) * 0.02)).cast<S>();
  }
  for (int s = 0; s < 20; ++s) step_particles(ps, cs, dt, opt);
  for (const auto& p : ps)
    if (!all_finite(p.position) || !all_finite(p.velocity)) return false;
  return true;
}

struct FarCase {
  Eigen::Vector3d offset;
  double scale;
};

template <class S> std::vector<FarCase> far_cases();
template <> std::vector<FarCase> far_cases<float>() {
  return {{Eigen::Vector3d::Constant(0x1p20), 1.0},
          {Eigen::Vector3d(1e6, -5e5, 2.5e5), 1.0},
          {Eigen::Vector3d(0x1p27, -0x1p27, 0x1.8p27), 0x1p27 * 0x1p-23 * 8}};
}
template <> std::vector<FarCase> far_cases<double>() {
  return {{Eigen::Vector3d::Constant(0x1p40), 1.0},
          {Eigen::Vector3d(0x1p48, -0x1p47, 0x1p46), 1.0},
          {Eigen::Vector3d(0x1p199, -0x1p199, 0x1.8p199), 0x1p199 * 0x1p-52 * 8}};
}

template <class S> class FarParticles : public ::testing::Test {};
using Scalars = ::testing::Types<float, double>;
TYPED_TEST_SUITE(FarParticles, Scalars);

TYPED_TEST(FarParticles, BacktrackingLegsNeverMeetTheSurface) {
  using S = TypeParam;
  const int particles = IMPACT_TEST_SANITIZED ? 30 : 100, steps = IMPACT_TEST_SANITIZED ? 10 : 30;
  std::uint64_t seed = 7;
  for (const FarCase& c : far_cases<S>()) {
    const FarScene<S> scene(c.offset, c.scale);
    for (const bool accelerated : {true, false})
      for (const bool tiny_offset : {false, true})
        EXPECT_EQ(touching_legs(scene, accelerated, tiny_offset, ++seed, particles, steps), 0)
            << "offset " << c.offset.transpose() << ", scale " << c.scale << (accelerated ? ", grid and wide tree" : ", binary tree")
            << (tiny_offset ? ", absolute surface offset" : "");
  }
}

TYPED_TEST(FarParticles, ProjectionStaysFinite) {
  using S = TypeParam;
  std::uint64_t seed = 70;
  for (const FarCase& c : far_cases<S>()) {
    const FarScene<S> scene(c.offset, c.scale);
    EXPECT_TRUE(projection_finite(scene, ++seed)) << "offset " << c.offset.transpose();
  }
}

}  // namespace
}  // namespace impact
