// SPDX-License-Identifier: MIT
// The scene's mesh–mesh narrow phase (broad/narrow_dispatch.hpp) and sphere trees refitted by
// merging (geometry/sphere.hpp merge) never miss an exact touching contact: collinear segment
// triangles that share exactly one endpoint, the only contact, placed at large power-of-two
// translations where the rounding of the relative pose (or of a merged sphere's centre) is far
// above the ulps of the small spheres' radii. The oracle is the tests' exact arithmetic on the
// triangles the library tests (support/brute_force.hpp: B moved into A's frame as the library
// moves it). Float and double.
#include "impact/broad/scene.hpp"
#include "impact/query/mesh_collide.hpp"
#include "support/brute_force.hpp"
#include "support/random.hpp"

#include <gtest/gtest.h>

#include "support/sanitizer.hpp"

namespace impact {
namespace {

constexpr int kDivisor = IMPACT_TEST_SANITIZED ? 4 : 1;

template <class S> RigidTransform<S> random_rigid(test::Rng& rng, const Vec3<S>& t) {
  const Eigen::Matrix3d R = rng.rotation();
  Eigen::Quaternion<S> q(R.cast<S>());
  q.normalize();
  return {q.toRotationMatrix(), t};
}

/// One degenerate triangle (p, q, q): a segment.
template <class S> TriangleMesh<S> segment(const Vec3<S>& p, const Vec3<S>& q) {
  TriangleMesh<S> m;
  m.V.resize(2, 3);
  m.V.row(0) = p.transpose();
  m.V.row(1) = q.transpose();
  m.F.resize(1, 3);
  m.F << 0, 1, 1;
  return m;
}

template <class S> class NarrowDispatchTouching : public ::testing::Test {};
using Scalars = ::testing::Types<float, double>;
TYPED_TEST_SUITE(NarrowDispatchTouching, Scalars);

// B: the segment v -> v + e in its own frame, posed at a translation of magnitude 2^k. A: the
// segment w -> w + (w - w2) in its own frame, w and w2 the library's images of B's endpoints in
// A's frame: the two touch exactly at w and nowhere else. shapes_intersect and the scene (which
// tests a pair in the order of the ids) must report every such pair; the other order agrees with
// its own exact answer.
TYPED_TEST(NarrowDispatchTouching, MeshMeshUnderLargeTranslations) {
  using S = TypeParam;
  test::Rng rng(std::is_same_v<S, float> ? 31 : 32);
  const int k_max = std::is_same_v<S, float> ? 16 : 40;
  int touching = 0, missed = 0, touching_ba = 0;
  for (int k = 0; k <= k_max; k += 4) {
    for (int n = 0; n < 64 / kDivisor; ++n) {
      const S scale = std::ldexp(S(1), k), h = S(0.0625);
      const RigidTransform<S> pb = random_rigid<S>(rng, (rng.vec(-1, 1) * double(scale)).cast<S>());
      const RigidTransform<S> pa = random_rigid<S>(rng, pb.t + (rng.vec(-1, 1)).cast<S>());
      const Vec3<S> v = (rng.vec(-0.5, 0.5)).cast<S>(), e = (rng.vec(-1, 1) * double(h)).cast<S>();
      const TriangleMesh<S> mb = segment<S>(v, v + e);
      const RigidTransform<S> b_to_a = relative_transform(pa, pb);
      const Vec3<S> w = b_to_a.apply(v), w2 = b_to_a.apply(Vec3<S>(v + e));
      const TriangleMesh<S> ma = segment<S>(w, w + (w - w2));
      const bool exact = !test::brute_force_pairs(ma, pa, mb, pb).empty();
      ASSERT_TRUE(exact);  // w is a point of both, exactly
      ++touching;
      const MeshBvh<Sphere<S>> ta(ma), tb(mb);
      const bool got = shapes_intersect(Shape<S>::mesh_of(ta), pa, Shape<S>::mesh_of(tb), pb);
      missed += !got;
      EXPECT_TRUE(got) << "k " << k << " n " << n;
      // the other order moves A into B's frame, rounded otherwise: its own exact answer
      const bool exact_ba = !test::brute_force_pairs(mb, pb, ma, pa).empty();
      EXPECT_EQ(shapes_intersect(Shape<S>::mesh_of(tb), pb, Shape<S>::mesh_of(ta), pa), exact_ba) << "k " << k << " n " << n;
      touching_ba += exact_ba;
      Scene<S> scene;
      scene.add(1, Shape<S>::mesh_of(ta), pa);
      scene.add(2, Shape<S>::mesh_of(tb), pb);
      EXPECT_EQ(scene.collide().pairs.size(), 1u) << "k " << k << " n " << n;
    }
  }
  EXPECT_EQ(missed, 0) << "of " << touching << " (the other order: " << touching_ba << " touching)";
}

// Refit by merging (MeshBvh::set_vertices, RefitMode::Merge): a chain of collinear segments p_0 ->
// p_1 -> ... -> p_m along a diagonal, at coordinates of magnitude 2^k, and a second mesh, the
// segment p_m -> p_m + (p_m - p_{m-1}), touching it exactly at p_m (identity poses). The merged
// spheres must hold their children although their centres are rounded at the coordinate scale.
TYPED_TEST(NarrowDispatchTouching, RefitTreeUnderLargeCoordinates) {
  using S = TypeParam;
  test::Rng rng(std::is_same_v<S, float> ? 41 : 42);
  const int k_max = std::is_same_v<S, float> ? 16 : 40;
  int missed = 0, configurations = 0;
  for (int k = 0; k <= k_max; k += 4) {
    for (int n = 0; n < 32 / kDivisor; ++n) {
      const S scale = std::ldexp(S(1), k);
      const Vec3<S> base = (rng.vec(-1, 1) * double(scale)).cast<S>();
      const Vec3<S> step = (rng.vec(0.5, 1) * 0.0625).cast<S>();
      const int m = 2 + int(rng.index(7));
      TriangleMesh<S> chain;
      chain.V.resize(m + 1, 3);
      chain.F.resize(m, 3);
      for (int i = 0; i <= m; ++i) chain.V.row(i) = (base + S(i) * step).transpose();
      for (int i = 0; i < m; ++i) chain.F.row(i) << i, i + 1, i + 1;
      const Vec3<S> end = chain.V.row(m).transpose(), before = chain.V.row(m - 1).transpose();
      const TriangleMesh<S> tip = segment<S>(end, Vec3<S>(end + (end - before)));
      const RigidTransform<S> I;
      ASSERT_FALSE(test::brute_force_pairs(chain, I, tip, I).empty());
      MeshBvh<Sphere<S>> tc(chain);
      tc.set_vertices(chain.V, RefitMode::Merge);
      const MeshBvh<Sphere<S>> tt(tip);
      ++configurations;
      const bool got = collides(tc, I, tt, I);
      missed += !got;
      EXPECT_TRUE(got) << "k " << k << " n " << n;
      EXPECT_TRUE(shapes_intersect(Shape<S>::mesh_of(tc), I, Shape<S>::mesh_of(tt), I)) << "k " << k << " n " << n;
    }
  }
  EXPECT_EQ(missed, 0) << "of " << configurations;
}

}  // namespace
}  // namespace impact
