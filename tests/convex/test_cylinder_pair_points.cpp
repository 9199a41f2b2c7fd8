// SPDX-License-Identifier: MIT
// The lower bound of convex/cylinder_pair_points.hpp (points of b against cylinder a) and the
// cylinder–cone candidates it certifies (convex/cylinder_pair.hpp):
//   - the distance from a point inside an ellipse, or inside or outside an ellipse swept along its
//     short axis (signed), to the boundary is never above a fine long-double minimisation over
//     the boundary (or over the directions of the support function), and the ellipse's is tight;
//   - L(P) for 1-3 points inside or outside the cylinder is never above a fine long-double
//     minimisation over directions of max_p (h_A(n) - n . p) (the bound from the faces alone,
//     without the great circles between the points, is above it on some sets: the oracle sees
//     a wrong bound), and reaches it on many sets;
//   - on cylinder–cone poses the candidates certify through it, their depth agrees with EPA alone
//     within the tolerance and with a minimisation of the overlap over directions;
//   - on deep cylinder–cone and cone–cone poses, where the best candidate's upper bound is often
//     not the depth when the points' stages run, every certified depth agrees with EPA alone.
#include "impact/convex/cone_cone_pair.hpp"
#include "impact/convex/cylinder_pair.hpp"
#include "impact/convex/cylinder_pair_points.hpp"
#include "impact/convex/query.hpp"
#include "support/convex_oracle.hpp"
#include "support/random.hpp"
#include "support/sanitizer.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <type_traits>
#include <vector>

namespace {

using namespace impact;
using V3 = Eigen::Vector3d;
using LD = long double;

// min over t in [lo, hi] of f by 2000 samples and a golden-section refinement about the best
// (long double): an upper estimate of the minimum within about 1e-12 where f is smooth there.
LD min_1d(const std::function<LD(LD)>& f, LD lo, LD hi) {
  const int n = 2000;
  LD best = f(lo), bt = lo;
  for (int i = 1; i <= n; ++i) {
    const LD t = lo + (hi - lo) * i / n, v = f(t);
    if (v < best) {
      best = v;
      bt = t;
    }
  }
  LD l = std::max(lo, bt - (hi - lo) / n), h = std::min(hi, bt + (hi - lo) / n);
  const LD g = (std::sqrt(5.0L) - 1) / 2;
  for (int it = 0; it < 80; ++it) {
    const LD x1 = h - g * (h - l), x2 = l + g * (h - l);
    if (f(x1) < f(x2)) {
      h = x2;
    } else {
      l = x1;
    }
  }
  return std::min(best, f((l + h) / 2));
}

// min over unit n of F: a Fibonacci sphere of n directions, then a compass search about the
// best `starts` (long double; steps from 0.02 down to 1e-14): an upper estimate of the minimum.
LD min_sphere(const std::function<LD(LD, LD, LD)>& F, int n = 3000, int starts = 3) {
  std::vector<std::pair<LD, int>> v;
  const auto dir = [&](int i, LD& x, LD& y, LD& z) {
    z = 1 - (2 * i + 1.0L) / n;
    const LD r = std::sqrt(std::max(1 - z * z, 0.0L)), phi = i * 2.399963229728653L;
    x = r * std::cos(phi);
    y = r * std::sin(phi);
  };
  for (int i = 0; i < n; ++i) {
    LD x, y, z;
    dir(i, x, y, z);
    v.emplace_back(F(x, y, z), i);
  }
  std::partial_sort(v.begin(), v.begin() + starts, v.end());
  LD best = v[0].first;
  for (int s = 0; s < starts; ++s) {
    LD x, y, z;
    dir(v[s].second, x, y, z);
    LD f = v[s].first;
    int moves = 0;  // at most 64 moves per step length (a flat valley would let rounding walk it for long)
    for (LD step = 0.02L; step > 1e-14L;) {
      bool moved = false;
      for (int k = 0; k < 16; ++k) {  // 16 tangent directions
        LD tx = -y, ty = x, tz = 0;  // a tangent basis at (x, y, z)
        if (std::abs(z) > 0.9L) {
          tx = 0;
          ty = -z;
          tz = y;
        }
        LD tl = std::sqrt(tx * tx + ty * ty + tz * tz);
        tx /= tl, ty /= tl, tz /= tl;
        const LD ux = y * tz - z * ty, uy = z * tx - x * tz, uz = x * ty - y * tx;
        const LD c = std::cos(k * 0.39269908169872414L), sn = std::sin(k * 0.39269908169872414L);
        LD nx = x + step * (c * tx + sn * ux), ny = y + step * (c * ty + sn * uy), nz = z + step * (c * tz + sn * uz);
        const LD nl = std::sqrt(nx * nx + ny * ny + nz * nz);
        nx /= nl, ny /= nl, nz /= nl;
        const LD g = F(nx, ny, nz);
        if (g < f) {
          f = g;
          x = nx, y = ny, z = nz;
          moved = true;
        }
      }
      if (!moved || ++moves == 64) {
        step /= 2;
        moves = 0;
      }
    }
    best = std::min(best, f);
  }
  return best;
}

TEST(CylinderPairPoints, EllipseDistanceIsALowerBoundAndTight) {
  test::Rng rng(5);
  int tight = 0, n = 0;
  for (int i = 0; i < 150; ++i) {
    const double b = rng.uniform(0.2, 1.0), a = b * rng.uniform(0.05, 1.0);
    double u, v;
    do {
      u = rng.uniform(0, a);
      v = rng.uniform(0, b);
    } while (u * u / (a * a) + v * v / (b * b) > 1);
    const double lb = detail::ellipse_inner_distance(u, v, a, b);
    const LD truth = min_1d([&](LD t) { return std::hypot(a * std::cos(t) - u, b * std::sin(t) - v); }, 0, 2 * M_PI);
    EXPECT_LE(lb, truth + 1e-12) << a << " " << b << " " << u << " " << v;
    ++n;
    tight += lb >= truth - 1e-9;
  }
  std::printf("tight within 1e-9 on %d of %d\n", tight, n);
  EXPECT_GE(tight, n * 9 / 10);
}

TEST(CylinderPairPoints, SweptEllipseDistanceIsALowerBound) {
  test::Rng rng(6);
  int positive = 0;
  for (int i = 0; i < 150; ++i) {
    const double b = rng.uniform(0.2, 1.0), a = i % 10 == 0 ? 0.0 : b * rng.uniform(0.0, 1.0), hs = rng.uniform(0.0, 1.0);
    const double spread = i % 3 == 0 ? 1.6 : 1.0;  // a third reach outside (a signed distance below 0)
    const double q1 = spread * rng.uniform(-hs - a, hs + a), q2 = spread * rng.uniform(-b, b);
    const double lb = detail::swept_ellipse_inner_distance(q1, q2, a, b, hs);
    // min over directions of the support function minus the point: the signed distance to the boundary
    const LD truth = min_1d(
        [&](LD t) {
          const LD c = std::cos(t), s = std::sin(t);
          return std::sqrt(a * a * c * c + b * b * s * s) + hs * std::abs(c) - q1 * c - q2 * s;
        },
        0, 2 * M_PI);
    EXPECT_LE(lb, truth + 1e-12) << a << " " << b << " " << hs << " " << q1 << " " << q2;
    positive += lb > 0.5 * truth && truth > 0;
  }
  std::printf("above half the distance on %d of 150\n", positive);
  EXPECT_GE(positive, 50);
}

TEST(CylinderPairPoints, PointsBoundNeverAboveTheDepthOfTheirHull) {
  test::Rng rng(7);
  int reached = 0, positive = 0, faces_only_above = 0;
  for (int i = 0; i < 90; ++i) {
    const Cylinder<double> a{rng.uniform(0.2, 1.0), rng.uniform(0.2, 1.0)};
    const int np = 1 + i % 3;
    V3 P[3];
    for (int k = 0; k < np; ++k) P[k] = rng.vec(-1.3, 1.3).cwiseProduct(V3(a.radius, a.radius, a.half_length));
    if (i % 4 == 0) P[0] = rng.vec(-0.5, 0.5).cwiseProduct(V3(a.radius, a.radius, a.half_length));  // one inside
    const double L = detail::cylinder_points_lower(a, P, np);
    const auto F = [&](LD x, LD y, LD z) {
      LD m = -1e30L;
      for (int k = 0; k < np; ++k) m = std::max(m, a.radius * std::sqrt(x * x + y * y) + a.half_length * std::abs(z) - (x * P[k].x() + y * P[k].y() + z * P[k].z()));
      return m;
    };
    const LD truth = min_sphere(F);
    EXPECT_LE(L, truth + 1e-12) << i;
    if (truth > 0) {
      ++positive;
      reached += L >= truth - 1e-9;
    }
    // the faces alone (no great circles between the points): not a bound
    double faces = std::numeric_limits<double>::infinity();
    for (int k = 0; k < np; ++k) {
      const V3& p = P[k];
      const double rxy = std::hypot(p.x(), p.y());
      const V3 dirs[3] = {V3::UnitZ(), -V3::UnitZ(), V3(p.x() / rxy, p.y() / rxy, 0)};
      const double vals[3] = {a.half_length - p.z(), a.half_length + p.z(), a.radius - rxy};
      for (int d = 0; d < 3; ++d) {
        bool cell = true;
        for (int j = 0; j < np; ++j) cell = cell && !(dirs[d].dot(p) > dirs[d].dot(P[j]) + 1e-12);
        if (cell) faces = std::min(faces, vals[d]);
      }
    }
    faces_only_above += faces > truth + 1e-6;
  }
  std::printf("sets with a positive depth %d, bound within 1e-9 on %d; faces alone above it on %d\n", positive, reached, faces_only_above);
  EXPECT_GE(positive, 20);
  EXPECT_GE(reached, positive / 3);
  EXPECT_GE(faces_only_above, 20);  // the oracle sees a bound that leaves the great circles out
}

TEST(CylinderPairPoints, CylinderConeCandidatesCertifiedThroughThePointsAgreeWithEpa) {
  const auto& z = test::zoo();
  const Cylinder<double>& a = z.cylinder;
  const Cone<double>& b = z.cone;
  const auto poses = test::convex_poses(700, 0.9 * (shape_size(a) + shape_size(b)), 31);
  const double scale = detail::query_scale<double>(a, b), tol = 1e-10 * scale;
  ConvexQueryOptions<double> o;
  int through_points = 0;
  for (const auto& pose : poses) {
    const RigidTransform<double>& pa = pose.first;
    const RigidTransform<double>& pb = pose.second;
    const detail::PairFrame<double> f(pa, pb);
    ConvexContact<double> c;
    if (!detail::cylinder_cone_contact(a, b, f.R, f.t, tol, c)) continue;
    // did the points decide it? (the bound alone reaches the certified depth)
    const V3 n = c.normal;  // a's frame
    const auto sb = [&](const V3& d) { return V3(f.support_b(b, d)); };
    const V3 x = sb(V3(-n));
    int calls = 0;
    if (!(detail::inside_ball(a, x).rho >= 0 && detail::cylinder_points_bound(a, x, c.depth, tol, sb, calls) >= c.depth - tol)) continue;
    ++through_points;
    const ConvexContact<double> g = detail::general_penetration(a, pa, b, pb, o);
    ASSERT_TRUE(g.intersecting);
    EXPECT_NEAR(c.depth, g.depth, 2 * tol);
    EXPECT_LE(c.depth - c.depth_gap, g.depth + 1e-12);
    EXPECT_LE(g.depth - g.depth_gap, c.depth + 1e-12);
    // the overlap minimised over directions (an upper estimate of the depth): c.depth is not above it
    const LD truth = min_sphere([&](LD x1, LD y1, LD z1) {
      const V3 m = V3(double(x1), double(y1), double(z1)).normalized();
      return LD(test::overlap_along(a, pa, b, pb, m));
    }, 1500, 2);
    EXPECT_LE(c.depth, truth + 1e-9);
  }
  std::printf("certified through the points: %d of 700 poses\n", through_points);
  EXPECT_GE(through_points, 12);
}

// (its own namespace: the convex tests build as one unity source, beside test_cone_cone_pair.cpp)
namespace cone_points_test {

// Cone c's support function along n (its frame), long double.
LD cone_h(const Cone<double>& c, LD x, LD y, LD z) {
  return std::max(c.half_length * z, c.radius * std::sqrt(x * x + y * y) - c.half_length * z);
}

// The shadow bound of cone_shadow_distance against min over the great circle normal to v of
// h_C(n) - n . p (long double), for p's shadow inside the cone's (the bound is -infinity outside):
// never above it, and above half of it on most points. Checked to fail: the tangent line's value
// with its (apex - xt) term negated. Not caught: the apex's shadow at h s instead of 2h s from the
// ellipse's centre (a smaller shadow, so a lower bound that is still valid).
TEST(CylinderPairPoints, ConeShadowDistanceIsALowerBound) {
  test::Rng rng(9);
  int inside = 0, half = 0;
  for (int i = 0; i < 200; ++i) {
    const Cone<double> c{rng.uniform(0.2, 1.0), rng.uniform(0.2, 1.0)};
    V3 v = rng.vec(-1, 1).normalized();
    if (i % 10 == 0) v = V3(v.x(), v.y(), 1e-3 * v.z()).normalized();  // nearly normal to the axis: a thin ellipse
    const V3 p = rng.vec(-1, 1).cwiseProduct(V3(c.radius, c.radius, c.half_length));
    const double lb = detail::cone_shadow_distance(c, p, v);
    const V3 e1 = (std::abs(v.x()) < 0.6 ? V3::UnitX() : V3::UnitY()).cross(v).normalized(), e2 = v.cross(e1);
    const LD truth = min_1d(
        [&](LD t) {
          const LD x = std::cos(t) * e1.x() + std::sin(t) * e2.x(), y = std::cos(t) * e1.y() + std::sin(t) * e2.y(),
                   z = std::cos(t) * e1.z() + std::sin(t) * e2.z();
          return cone_h(c, x, y, z) - (x * p.x() + y * p.y() + z * p.z());
        },
        0, 2 * M_PI);
    EXPECT_LE(lb, truth + 1e-12) << i;
    if (lb > -1e300) ++inside;
    half += truth > 0 && lb > 0.5 * truth;
  }
  std::printf("cone shadow: shown inside %d of 200, above half the distance on %d\n", inside, half);
  EXPECT_GE(half, 60);
}

// cone_points_lower (the cone as the container) for 1-3 points inside or outside the cone: never
// above a fine minimisation over directions of max_p (h_C(n) - n . p) (the depth of the cone
// against the points' hull), and within 1e-9 of it on a good share of the sets with a positive
// depth. The bound from the faces alone (base, side at each point's azimuth; no great circles)
// is above it on some sets, so the oracle sees a bound that leaves the pairs out. Checked to fail:
// the side value of a point with the wrong sign of its radial term, and the pairs' great circles
// left out. Not caught: the in-cell test of the base with +z.
TEST(CylinderPairPoints, ConePointsBoundNeverAboveTheDepthOfTheirHull) {
  test::Rng rng(8);
  int reached = 0, positive = 0, faces_only_above = 0;
  for (int i = 0; i < 120; ++i) {
    const Cone<double> c{rng.uniform(0.2, 1.0), rng.uniform(0.2, 1.0)};
    const int np = 1 + i % 3;
    V3 P[3];
    for (int k = 0; k < np; ++k) P[k] = rng.vec(-1.3, 1.3).cwiseProduct(V3(c.radius, c.radius, c.half_length));
    if (i % 3 != 2) P[0] = V3(rng.uniform(-0.3, 0.3) * c.radius, rng.uniform(-0.3, 0.3) * c.radius, rng.uniform(-0.9, 0) * c.half_length);  // inside
    const double L = detail::cone_points_lower(c, P, np);
    const auto F = [&](LD x, LD y, LD z) {
      LD m = -1e30L;
      for (int k = 0; k < np; ++k) m = std::max(m, cone_h(c, x, y, z) - (x * P[k].x() + y * P[k].y() + z * P[k].z()));
      return m;
    };
    const LD truth = min_sphere(F);
    EXPECT_LE(L, truth + 1e-12) << i;
    if (truth > 0) {
      ++positive;
      reached += L >= truth - 1e-9;
    }
    double faces = std::numeric_limits<double>::infinity();
    const double len = std::sqrt(4 * c.half_length * c.half_length + c.radius * c.radius);
    for (int k = 0; k < np; ++k) {
      const V3& p = P[k];
      const double rxy = std::hypot(p.x(), p.y());
      const V3 dirs[2] = {-V3::UnitZ(), V3(2 * c.half_length * p.x() / (rxy * len), 2 * c.half_length * p.y() / (rxy * len), c.radius / len)};
      const double vals[2] = {c.half_length + p.z(), (c.radius * (c.half_length - p.z()) - 2 * c.half_length * rxy) / len};
      for (int d = 0; d < 2; ++d) {
        bool cell = true;
        for (int j = 0; j < np; ++j) cell = cell && !(dirs[d].dot(p) > dirs[d].dot(P[j]) + 1e-12);
        if (cell) faces = std::min(faces, vals[d]);
      }
    }
    faces_only_above += faces > truth + 1e-6;
  }
  std::printf("cone: sets with a positive depth %d, bound within 1e-9 on %d; faces alone above it on %d\n", positive, reached, faces_only_above);
  EXPECT_GE(positive, 30);
  EXPECT_GE(reached, positive / 3);
  EXPECT_GE(faces_only_above, 10);
}

// The overlap along unit n (a's frame) of cylinder a and cone b placed by R, t there, long double.
LD cylinder_cone_overlap(const Cylinder<double>& a, const Cone<double>& b, const Eigen::Matrix3d& R, const V3& t, const test::OracleDirection& n) {
  const test::OracleDirection m = -(R.cast<LD>().transpose() * n);
  return a.radius * std::sqrt(n.x() * n.x() + n.y() * n.y()) + a.half_length * std::abs(n.z()) - t.cast<LD>().dot(n) + cone_h(b, m.x(), m.y(), m.z());
}

// The depth by test::least_overlap: kink circles at a's equator and b's side normals, the axes
// and `extra` (the normal under test) as starts.
LD cylinder_cone_depth(const Cylinder<double>& a, const Cone<double>& b, const Eigen::Matrix3d& R, const V3& t, const V3& extra) {
  const auto f = [&](const test::OracleDirection& n) { return cylinder_cone_overlap(a, b, R, t, n); };
  const double side = b.radius / std::sqrt(4 * b.half_length * b.half_length + b.radius * b.radius);
  return test::least_overlap(f, {V3::UnitZ(), -V3::UnitZ(), R.col(2), -R.col(2), extra}, {{V3::UnitZ(), 0}, {R.col(2), -side}}).depth;
}

// Every certified cylinder–cone candidate (caps, rulings, rims, the side minimum, the points of
// either shape against the other, a cone's whole ruling against the cylinder) against the oracle:
// its lower bound below the oracle's depth and its depth within 1e-9 of the size of it, at the
// unit size, 1e-3 and 1e3 of it and 1e3 from the origin; float poses and shapes within float's
// tolerance of the double oracle of the same inputs. Deep poses (b's centre within 0.35 of the
// sizes of a's) so that the points and the rulings decide many. Checked to fail: the pairs' great
// circles left out of cone_points_lower (certified depths above the oracle's).
TEST(CylinderPairPoints, CylinderConeCertifiedAgainstTheOracle) {
  const double scales[4] = {1, 1e-3, 1e3, 1}, offsets[4] = {0, 0, 0, 1e3};
  int certified = 0, certified_float = 0;
  for (int s = 0; s < 4; ++s) {
    test::Rng rng(40 + static_cast<std::uint64_t>(s));
    for (int i = 0; i < (IMPACT_TEST_SANITIZED ? 10 : 40); ++i) {
      const double k = scales[s];
      const Cylinder<double> a{k * rng.uniform(0.2, 1.0), k * rng.uniform(0.2, 1.0)};
      const Cone<double> b{k * rng.uniform(0.2, 1.0), k * rng.uniform(0.2, 1.0)};
      const double reach = 0.35 * (shape_size(a) + shape_size(b));
      const RigidTransform<double> pa{rng.rotation(), Eigen::Vector3d(rng.vec(-k, k) + V3::Constant(offsets[s]))};
      const RigidTransform<double> pb{rng.rotation(), Eigen::Vector3d(pa.t + rng.vec(-reach, reach))};
      const double scale = detail::query_scale<double>(a, b), tol = 1e-10 * scale;
      const double slack = (1e-12 + 1e-15 * offsets[s]) * scale;
      const detail::PairFrame<double> f(pa, pb);
      ConvexContact<double> c;
      if (detail::cylinder_cone_contact(a, b, f.R, f.t, tol, c)) {
        ++certified;
        const double oracle = double(cylinder_cone_depth(a, b, f.R, f.t, c.normal));
        EXPECT_LE(c.depth - c.depth_gap, oracle + slack) << s << " " << i << ": lower bound above the depth";
        EXPECT_NEAR(c.depth, oracle, 1e-9 * scale + slack) << s << " " << i;
      }
      if (s != 0) continue;
      // float: shapes and poses rounded to float, the oracle on the rounded inputs
      const Cylinder<float> af(float(a.radius), float(a.half_length));
      const Cone<float> bf(float(b.radius), float(b.half_length));
      const RigidTransform<float> paf{pa.R.cast<float>(), pa.t.cast<float>()}, pbf{pb.R.cast<float>(), pb.t.cast<float>()};
      const detail::PairFrame<float> ff(paf, pbf);
      ConvexContact<float> cf;
      if (!detail::cylinder_cone_contact(af, bf, ff.R, ff.t, 1e-5f * float(scale), cf)) continue;
      ++certified_float;
      const Cylinder<double> ad(af.radius, af.half_length);
      const Cone<double> bd(bf.radius, bf.half_length);
      const detail::PairFrame<double> fd(RigidTransform<double>{paf.R.cast<double>(), paf.t.cast<double>()},
                                         RigidTransform<double>{pbf.R.cast<double>(), pbf.t.cast<double>()});
      const double oracle = double(cylinder_cone_depth(ad, bd, fd.R, fd.t, cf.normal.cast<double>()));
      EXPECT_LE(double(cf.depth - cf.depth_gap), oracle + 1e-5 * scale) << i << ": float lower bound above the depth";
      EXPECT_NEAR(double(cf.depth), oracle, 1e-4 * scale) << i;
    }
  }
  std::printf("cylinder-cone certified: %d double, %d float\n", certified, certified_float);
  EXPECT_GE(certified, IMPACT_TEST_SANITIZED ? 10 : 60);
  EXPECT_GE(certified_float, IMPACT_TEST_SANITIZED ? 2 : 10);
}

// The points' stages of both contacts (cylinder_cone_contact: cylinder_points_bound,
// cone_points_bound, the cone's whole ruling through cylinder_points_lower; cone_cone_contact: each
// cone's whole ruling through cone_points_lower, cone_points_bound both ways) raise the lower bound
// after the candidates, against the best candidate's upper bound. On deep poses of varied
// proportions (b's centre within 0.25 of the sizes of a's) that upper bound is often not the depth
// when they run (another direction overlaps less), so a bound above the depth there certifies a
// depth too large. Every certified depth within the tolerance of EPA alone, its lower bound below
// EPA's depth. (Those bounds are gated: they return -infinity unless they reach the upper bound
// less the tolerance, so a mutation that scales their result at the call leaves every depth as it
// is; the mutations that fail here scale the bound before the gate.) Checked to fail, each alone:
// each of the seven stages' bound times 1.5 before its gate (S(1.5) * f(..., want / S(1.5))).
TEST(CylinderPairPoints, PointsStagesCertifyOnlyTheDepth) {
  test::Rng rng(77);
  const ConvexQueryOptions<double> o;
  int certified[2] = {0, 0};
  const auto check = [&](const auto& a, const auto& b, const RigidTransform<double>& pa, const RigidTransform<double>& pb, int kind, int i) {
    const double scale = detail::query_scale<double>(a, b), tol = 1e-10 * scale;
    const detail::PairFrame<double> f(pa, pb);
    ConvexContact<double> c;
    bool ok;
    if constexpr (std::is_same_v<std::decay_t<decltype(a)>, Cylinder<double>>) {
      ok = detail::cylinder_cone_contact(a, b, f.R, f.t, tol, c);
    } else {
      ok = detail::cone_cone_contact(a, b, f.R, f.t, tol, c);
    }
    if (!ok) return;
    ++certified[kind];
    const ConvexContact<double> g = detail::general_penetration(a, pa, b, pb, o);
    ASSERT_TRUE(g.intersecting) << kind << " " << i;
    EXPECT_NEAR(c.depth, g.depth, 2 * tol) << kind << " " << i;
    EXPECT_LE(c.depth - c.depth_gap, g.depth + 1e-12 * scale) << kind << " " << i << ": lower bound above EPA's depth";
  };
  for (int i = 0; i < (IMPACT_TEST_SANITIZED ? 300 : 1500); ++i) {
    const double r1 = rng.uniform(0.1, 1.0), h1 = rng.uniform(0.1, 1.0), r2 = rng.uniform(0.1, 1.0), h2 = rng.uniform(0.1, 1.0);
    const RigidTransform<double> pa{rng.rotation(), rng.vec(-1, 1)};
    const Eigen::Matrix3d Rb = rng.rotation();
    const V3 d = rng.vec(-1, 1);
    const Cylinder<double> cyl(r1, h1);
    const Cone<double> ca(r1, h1), cb(r2, h2);
    check(cyl, cb, pa, RigidTransform<double>{Rb, V3(pa.t + 0.25 * (shape_size(cyl) + shape_size(cb)) * d)}, 0, i);
    check(ca, cb, pa, RigidTransform<double>{Rb, V3(pa.t + 0.25 * (shape_size(ca) + shape_size(cb)) * d)}, 1, i);
  }
  std::printf("certified: cylinder-cone %d, cone-cone %d\n", certified[0], certified[1]);
  EXPECT_GE(certified[0], IMPACT_TEST_SANITIZED ? 100 : 500);
  EXPECT_GE(certified[1], IMPACT_TEST_SANITIZED ? 100 : 500);
}

}  // namespace cone_points_test
}  // namespace
