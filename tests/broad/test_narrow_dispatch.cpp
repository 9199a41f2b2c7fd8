// SPDX-License-Identifier: MIT
// The scene's narrow phase (broad/narrow_dispatch.hpp: mesh–mesh, sphere–mesh, box–mesh) and
// sphere trees refitted by merging (geometry/sphere.hpp merge) never miss an exact touching
// contact: collinear segment triangles that share exactly one endpoint with the other shape, the
// only contact, placed at large power-of-two translations and coordinates where the rounding of
// the relative pose (or of a merged sphere's centre) is far above the ulps of the small spheres'
// radii, or next to a sphere far larger than the triangle. The oracle is the tests' exact
// arithmetic on what the library tests (support/brute_force.hpp: B moved into A's frame as the
// library moves it; below, an exact rational point–triangle distance and an exact box–triangle
// test). Float and double.
#include "impact/broad/scene.hpp"
#include "impact/query/mesh_collide.hpp"
#include "support/brute_force.hpp"
#include "support/multiprecision.hpp"
#include "support/random.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>

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

using Rat = boost::multiprecision::cpp_rational;
using RVec = std::array<Rat, 3>;

/// x exactly as a rational (x finite).
Rat exact(double x) {
  int e = 0;
  const double f = std::frexp(x, &e);
  Rat r(static_cast<std::int64_t>(std::ldexp(f, 53)));
  e -= 53;
  const test::BigInt p = test::BigInt(1) << static_cast<unsigned>(e < 0 ? -e : e);
  return e < 0 ? Rat(r / p) : Rat(r * p);
}
template <class S> RVec exact(const Vec3<S>& v) { return {exact(double(v.x())), exact(double(v.y())), exact(double(v.z()))}; }
RVec rsub(const RVec& a, const RVec& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
Rat rdot(const RVec& a, const RVec& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
RVec rcross(const RVec& a, const RVec& b) { return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]}; }

/// Exact squared distance from p to the closed segment [a, b].
Rat segment_d2(const RVec& p, const RVec& a, const RVec& b) {
  const RVec d = rsub(b, a), ap = rsub(p, a);
  const Rat dd = rdot(d, d);
  Rat t = 0;
  if (dd != 0) t = rdot(ap, d) / dd;
  if (t < 0) t = 0;
  if (t > 1) t = 1;
  const RVec q = {ap[0] - t * d[0], ap[1] - t * d[1], ap[2] - t * d[2]};
  return rdot(q, q);
}

/// Exact: the closed ball (c, r) and the closed triangle t share a point. The distance is the
/// least of the three edges' and, when p projects into the triangle, of the plane's.
template <class S> bool ball_touches_triangle_exact(const Vec3<S>& c, S r, const Triangle<S>& t) {
  const RVec p = exact(c), a = exact(t.a), b = exact(t.b), cc = exact(t.c);
  Rat d2 = segment_d2(p, a, b);
  for (const Rat& x : {segment_d2(p, b, cc), segment_d2(p, cc, a)})
    if (x < d2) d2 = x;
  const RVec n = rcross(rsub(b, a), rsub(cc, a));
  const Rat nn = rdot(n, n);
  if (nn != 0) {
    const Rat s = rdot(n, rsub(p, a));
    const RVec q = {p[0] - s / nn * n[0], p[1] - s / nn * n[1], p[2] - s / nn * n[2]};
    const bool inside = rdot(n, rcross(rsub(b, a), rsub(q, a))) >= 0 && rdot(n, rcross(rsub(cc, b), rsub(q, b))) >= 0 &&
                        rdot(n, rcross(rsub(a, cc), rsub(q, cc))) >= 0;
    if (inside && s * s / nn < d2) d2 = s * s / nn;
  }
  const Rat rr = exact(double(r));
  return d2 <= rr * rr;
}

/// Exact: the closed triangle t meets the closed box [-h, h]: a vertex of t is inside, or t meets
/// one of the box's twelve boundary triangles (the tests' exact triangle–triangle arithmetic).
template <class S> bool box_touches_triangle_exact(const Vec3<S>& h, const Triangle<S>& t) {
  for (int k = 0; k < 3; ++k)
    if ((t[k].cwiseAbs().array() <= h.array()).all()) return true;
  const auto corner = [&](int i) { return Vec3<S>((i & 1) ? h.x() : -h.x(), (i & 2) ? h.y() : -h.y(), (i & 4) ? h.z() : -h.z()); };
  // each face: the corners with bit `axis` fixed, as two triangles
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) {
      const int o1 = 1 << ((axis + 1) % 3), o2 = 1 << ((axis + 2) % 3), base = side ? (1 << axis) : 0;
      const Vec3<S> p0 = corner(base), p1 = corner(base | o1), p2 = corner(base | o1 | o2), p3 = corner(base | o2);
      if (test::triangles_intersect_exact(t, Triangle<S>(p0, p1, p2)) || test::triangles_intersect_exact(t, Triangle<S>(p0, p2, p3))) return true;
    }
  return false;
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

// Sphere (and particle with a radius) against a mesh: the segment v -> v + e of the mesh touches
// the ball exactly at v and nowhere else. v lies at distance r from the library's image c' of the
// ball's centre in the mesh's frame (R^T (c - t), as narrow_dispatch computes it) along a
// Pythagorean direction p (|p| an integer q), e points further along it: the leaf's sphere is
// tangent to the ball from inside, at v, and the ball is m ~ 2^(digits / 2) times the segment (m
// random, so that the node test's squared distance is rounded). Poses rotate by
// signed permutations and every coordinate lies on a grid of 2^(k - digits + 4), so c' and v are
// exact; the mesh is posed at translations of magnitude 2^k and holds coordinates of that size.
TYPED_TEST(NarrowDispatchTouching, SphereMeshTouchingAtAVertex) {
  using S = TypeParam;
  test::Rng rng(std::is_same_v<S, float> ? 51 : 52);
  const int k_max = std::is_same_v<S, float> ? 16 : 40, digits = std::numeric_limits<S>::digits;
  static const int pyth[7][4] = {{3, 4, 0, 5}, {1, 2, 2, 3}, {2, 3, 6, 7}, {1, 4, 8, 9}, {4, 4, 7, 9}, {2, 6, 9, 11}, {6, 6, 7, 11}};
  int touching = 0, missed = 0;
  for (int k = 0; k <= k_max; k += 4) {
    for (int n = 0; n < 64 / kDivisor; ++n) {
      const S scale = std::ldexp(S(1), k), g = std::ldexp(S(1), std::max(k - digits + 4, -12));
      const auto on_grid = [&](double lo, double hi) {
        return Vec3<S>((rng.vec(lo, hi) * double(scale / g)).array().round().matrix().cast<S>() * g);
      };
      int perm[3] = {0, 1, 2};
      for (int i = 2; i > 0; --i) std::swap(perm[i], perm[rng.index(std::uint64_t(i + 1))]);
      Mat3<S> R = Mat3<S>::Zero();
      for (int i = 0; i < 3; ++i) R(i, perm[i]) = rng.index(2) ? S(1) : S(-1);
      if (R.determinant() < S(0)) R.row(0) *= S(-1);
      const RigidTransform<S> pm(R, on_grid(-1, 1));
      const Vec3<S> c = pm.apply(on_grid(-1, 1));
      const Vec3<S> lc = pm.R.transpose() * (c - pm.t);  // as sphere_mesh moves the centre
      const int* q = pyth[rng.index(7)];
      std::swap(perm[0], perm[rng.index(3)]);
      Vec3<S> dir;
      for (int i = 0; i < 3; ++i) dir[perm[i]] = S(q[i]) * (rng.index(2) ? S(1) : S(-1));
      const S m = std::ldexp(S(1), digits / 2) + S(rng.index(std::uint64_t(1) << (digits / 2)));
      const S r = S(q[3]) * g * m;
      const Vec3<S> v = lc + dir * (g * m), w = v + dir * g;
      const TriangleMesh<S> mesh = segment<S>(v, w);
      const Triangle<S> tri = mesh.triangle(0);
      ASSERT_TRUE(ball_touches_triangle_exact(lc, r, tri)) << "k " << k << " n " << n;
      // the contact is v alone: a slightly smaller ball misses the segment
      ASSERT_FALSE(ball_touches_triangle_exact(lc, std::nextafter(r, S(0)), tri));
      ++touching;
      const MeshBvh<Sphere<S>> tm(mesh);
      const RigidTransform<S> ps(Mat3<S>::Identity(), c);
      const bool got = shapes_intersect(Shape<S>::sphere(r), ps, Shape<S>::mesh_of(tm), pm);
      missed += !got;
      EXPECT_TRUE(got) << "k " << k << " n " << n;
      EXPECT_TRUE(shapes_intersect(Shape<S>::mesh_of(tm), pm, Shape<S>::particle(r), ps)) << "k " << k << " n " << n;
      // conservative only within rounding: a ball smaller by 2^10 ulps of its radius is apart
      EXPECT_FALSE(shapes_intersect(Shape<S>::sphere(r - std::ldexp(r, 11 - digits)), ps, Shape<S>::mesh_of(tm), pm)) << "k " << k << " n " << n;
      Scene<S> scene;
      scene.add(1, Shape<S>::sphere(r), ps);
      scene.add(2, Shape<S>::mesh_of(tm), pm);
      EXPECT_EQ(scene.collide().pairs.size(), 1u) << "k " << k << " n " << n;
    }
  }
  EXPECT_EQ(missed, 0) << "of " << touching;
}

// Box against a mesh: the segment v -> v + e, e along the box's x axis seen from the mesh, touches
// the box exactly at the library's image w of v (narrow_dispatch moves the mesh into the box's
// frame by relative_transform(box pose, mesh pose)): the box's x half extent is |w.x| and the
// segment's image leaves the face outwards, so the leaf's sphere is tangent to the face. The mesh's
// origin lies about 2^k away from the box (its coordinates near the box are of magnitude 2^k), so
// the moved node centres round at that scale.
TYPED_TEST(NarrowDispatchTouching, BoxMeshTouchingAtAVertex) {
  using S = TypeParam;
  test::Rng rng(std::is_same_v<S, float> ? 61 : 62);
  const int k_max = std::is_same_v<S, float> ? 16 : 40;
  int touching = 0, missed = 0, apart = 0;
  for (int k = 0; k <= k_max; k += 4) {
    for (int n = 0; n < 64 / kDivisor; ++n) {
      const S scale = std::ldexp(S(1), k);
      const RigidTransform<S> pb = random_rigid<S>(rng, (rng.vec(-1, 1) * double(scale)).cast<S>());
      const RigidTransform<S> pm = random_rigid<S>(rng, pb.t + (rng.vec(-1, 1) * double(scale)).cast<S>());
      const RigidTransform<S> m_to_b = relative_transform(pb, pm);  // as box_mesh moves the mesh
      const RigidTransform<S> b_to_m = m_to_b.inverse();
      const S side = rng.index(2) ? S(1) : S(-1);
      const Vec3<S> v = b_to_m.apply(Vec3<S>(side * S(rng.uniform(0.125, 0.5)), S(rng.uniform(-0.5, 0.5)), S(rng.uniform(-0.5, 0.5))));
      const Vec3<S> e = b_to_m.R * Vec3<S>(side * S(0.0625), S(0), S(0));
      const TriangleMesh<S> mesh = segment<S>(v, Vec3<S>(v + e));
      const Triangle<S> t0 = mesh.triangle(0);
      const Triangle<S> moved(m_to_b.apply(t0.a), m_to_b.apply(t0.b), m_to_b.apply(t0.c));
      const Vec3<S> w = moved.a;
      const Vec3<S> h(std::abs(w.x()), std::abs(w.y()) + S(1), std::abs(w.z()) + S(1));
      ASSERT_TRUE(side * w.x() > S(0) && side * (moved.b.x() - w.x()) > S(0));  // the image leaves the face outwards
      ASSERT_TRUE(box_touches_triangle_exact(h, moved));
      // the contact is w alone: a box thinner in x misses the segment
      ASSERT_FALSE(box_touches_triangle_exact(Vec3<S>(std::nextafter(h.x(), S(0)), h.y(), h.z()), moved));
      ++touching;
      const MeshBvh<Sphere<S>> tm(mesh);
      const bool got = shapes_intersect(Shape<S>::box(h), pb, Shape<S>::mesh_of(tm), pm);
      missed += !got;
      EXPECT_TRUE(got) << "k " << k << " n " << n;
      EXPECT_TRUE(shapes_intersect(Shape<S>::mesh_of(tm), pm, Shape<S>::box(h), pb)) << "k " << k << " n " << n;
      // conservative only within rounding at the mesh's coordinate scale: a box thinner by 2^10
      // ulps of that scale is apart (where that is below its half extent)
      const S gap = std::ldexp(std::max(scale, S(1)), 11 - std::numeric_limits<S>::digits);
      if (gap < h.x() / S(4)) {
        ++apart;
        EXPECT_FALSE(shapes_intersect(Shape<S>::box(Vec3<S>(h.x() - gap, h.y(), h.z())), pb, Shape<S>::mesh_of(tm), pm)) << "k " << k << " n " << n;
      }
      Scene<S> scene;
      scene.add(1, Shape<S>::box(h), pb);
      scene.add(2, Shape<S>::mesh_of(tm), pm);
      EXPECT_EQ(scene.collide().pairs.size(), 1u) << "k " << k << " n " << n;
    }
  }
  EXPECT_GE(apart, touching / 2);
  EXPECT_EQ(missed, 0) << "of " << touching;
}

// Sphere against sphere and sphere against box (a box thin as a segment, centred on the contact):
// the centres differ by (3m, 4m, 0) and the radii are 2m and 3m (or 5m against the box), m with
// digits - 4 significant bits and the centres on a grid so that every one of these is exact: the
// balls touch exactly (the tests' rational arithmetic checks it), but the squared distance and the
// squared radius sum are each rounded. Centres and radii of magnitude 2^k, k up to 40 (16 in float).
// Before the padding: 204 (float) and 210 (double) of 2,000 checks reported apart.
TYPED_TEST(NarrowDispatchTouching, SphereSphereAndSphereBoxTouching) {
  using S = TypeParam;
  test::Rng rng(std::is_same_v<S, float> ? 71 : 72);
  const int bits = std::numeric_limits<S>::digits - 4;
  int touching = 0, missed = 0;
  for (int n = 0; n < 1000 / kDivisor; ++n) {
    // every coordinate a multiple of 2^(k - bits) below 2^(k + 4): all exact
    const int k = int(rng.index(std::is_same_v<S, float> ? 16 : 40));
    const S m = std::ldexp(S(1) + std::ldexp(S(rng.index(std::uint64_t(1) << bits)), -bits), k);
    Vec3<S> ca;
    for (int i = 0; i < 3; ++i) ca[i] = std::ldexp(S(std::int64_t(rng.index(std::uint64_t(8) << bits)) - (std::int64_t(4) << bits)), k - bits);
    const Vec3<S> d(S(3) * m, S(4) * m, S(0));
    const Vec3<S> cb = ca + d;
    const RVec dd = rsub(exact(cb), exact(ca));
    ASSERT_EQ(rdot(dd, dd), exact(double(S(5) * m)) * exact(double(S(5) * m))) << n;  // an exact contact
    ++touching;
    const RigidTransform<S> pa(Mat3<S>::Identity(), ca), pb(Mat3<S>::Identity(), cb);
    const bool ss = shapes_intersect(Shape<S>::sphere(S(2) * m), pa, Shape<S>::sphere(S(3) * m), pb);
    const bool sb = shapes_intersect(Shape<S>::sphere(S(5) * m), pa, Shape<S>::box(Vec3<S>(0, 0, 1)), pb);
    missed += !ss + !sb;
    EXPECT_TRUE(ss) << n;
    EXPECT_TRUE(sb) << n;
    // apart by 2^10 ulps of the radius: apart
    const S apart = S(5) * m * (S(1) - std::ldexp(S(1), 10 - std::numeric_limits<S>::digits));
    EXPECT_FALSE(shapes_intersect(Shape<S>::sphere(apart), pa, Shape<S>::box(Vec3<S>(0, 0, 1)), pb)) << n;
  }
  EXPECT_EQ(missed, 0) << "of " << 2 * touching;
}

}  // namespace
}  // namespace impact
