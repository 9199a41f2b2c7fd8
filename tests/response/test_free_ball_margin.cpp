// SPDX-License-Identifier: MIT
// The rounding margin of the backtracking step's free balls (response/particle_step.hpp,
// free_ball_at's shrink): a particle just above a tilted triangle at coordinates near 2^20 (2^8 in
// float), moving straight at it by a leg that ends just behind it. The free ball's radius is a
// distance rounded at the coordinates' scale, which can exceed the exact distance; without the
// margin a leg inside it skips the ray cast and the particle ends behind the surface. Each
// configuration kept is one where the leg's segment meets the triangle exactly, and the chord the
// particle travels must not (the tests' exact arithmetic, support/exact_triangle.hpp).
#include "impact/response/particle_step.hpp"
#include "support/exact_triangle.hpp"
#include "support/random.hpp"

#include <gtest/gtest.h>

#include "support/sanitizer.hpp"

namespace impact {
namespace {

template <class S> class FreeBallMargin : public ::testing::Test {};
using Scalars = ::testing::Types<float, double>;
TYPED_TEST_SUITE(FreeBallMargin, Scalars);

TYPED_TEST(FreeBallMargin, NearTouchingLegsAtLargeCoordinatesAreCast) {
  using S = TypeParam;
  test::Rng rng(std::is_same_v<S, float> ? 51 : 52);
  const S big = std::ldexp(S(1), std::is_same_v<S, float> ? 8 : 20);
  const int n = (IMPACT_TEST_SANITIZED ? 100 : 400);
  int kept = 0;
  for (int k = 0; k < n; ++k) {
    const Vec3<S> c = (rng.vec(0.5, 1) * double(big)).cast<S>();
    TriangleMesh<S> m;
    m.V.resize(3, 3);
    for (int i = 0; i < 3; ++i) m.V.row(i) = (c + (rng.vec(-4, 4)).cast<S>()).transpose();
    m.F.resize(1, 3);
    m.F << 0, 1, 2;
    const Triangle<S> tri = m.triangle(0);
    const Vec3<S> nrm = tri.normal();
    if (!(nrm.squaredNorm() > S(0.5))) continue;
    const MeshBvh<Aabb<S>> bvh(m);
    ColliderSet<S> cs;
    cs.meshes.emplace_back(bvh, ColliderSide::TwoSided, Material<S>{S(0), S(0)});
    // a point of the triangle (rounded: near its plane), a particle a height h above it
    const Vec3<S> on = (tri.a + tri.b + tri.c) / S(3);
    const S h = S(1) / S(64);
    const Vec3<S> x = on + nrm * h;
    // a leg along -n ending behind the plane by a few ulps of the coordinates
    const S ulp = std::ldexp(std::numeric_limits<S>::epsilon(), std::ilogb(big));
    const Vec3<S> e = x - nrm * (h + S(rng.index(4)) * ulp);
    // keep only legs whose segment meets the triangle exactly
    if (!test::triangles_intersect_exact(tri, Triangle<S>(x, e, e))) continue;
    ++kept;
    std::vector<Particle<S>> ps(1);
    ps[0].position = x;
    const S dt = S(1);
    ps[0].velocity = e - x;
    StepOptions<S> opt;
    opt.threads = 1;
    step_particles(ps, cs, dt, opt);
    EXPECT_FALSE(test::triangles_intersect_exact(tri, Triangle<S>(x, ps[0].position, ps[0].position))) << "configuration " << k;
  }
  EXPECT_GT(kept, n / 10);
}

}  // namespace
}  // namespace impact
