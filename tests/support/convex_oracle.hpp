// SPDX-License-Identifier: MIT
// Oracles and fixtures for the convex layer's tests and impact-convex-bench: the shapes of each
// tested pair, random poses, and the signed distance of two convex sets by a search over
// directions, independent of GJK, EPA, MPR and the closed forms:
//   f(n) = h_A(n) + h_B(-n)  (h: support value, n unit, from a towards b)
//   signed distance = -min_n f(n)  (the distance when > 0, minus the penetration depth when < 0),
// minimised over a Fibonacci sphere of directions, then refined by a shrinking random search. It
// reads the shapes only through their support functions (checked on their own against sampled
// points in test_shapes.cpp). least_overlap minimises a pair's overlap given in closed form (long
// double) for the certified candidates' tests (cylinder–box, cone–box, cone–cone, cylinder–hull).
#pragma once

#include "impact/convex/convex_hull.hpp"
#include "impact/convex/local_certificate.hpp"
#include "impact/convex/shapes.hpp"
#include "support/random.hpp"
#include "support/sanitizer.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <string>
#include <utility>
#include <vector>

namespace impact::test {

/// The value along w of a sum of overlap terms (detail::OverlapTerms, convex/local_certificate.hpp),
/// evaluated on its own from the definition: the linear part, then each term's coefficient times
/// |w . axis|, or for a disc term the length of w's part across its axis.
inline double overlap_terms_value(const detail::OverlapTerms<double>& terms, const Eigen::Vector3d& w) {
  double v = terms.linear.dot(w);
  for (int k = 0; k < terms.n; ++k) {
    const double d = terms.axis[k].dot(w);
    v += terms.coef[k] * (terms.disc[k] ? std::sqrt(std::max(w.squaredNorm() - d * d, 0.0)) : std::abs(d));
  }
  return v;
}

/// f(n) for unit n (see the file comment).
template <class A, class B>
double overlap_along(const A& a, const RigidTransform<double>& pa, const B& b, const RigidTransform<double>& pb, const Eigen::Vector3d& n) {
  return n.dot(support(a, pa, n)) + (-n).dot(support(b, pb, Eigen::Vector3d(-n)));
}

struct SignedDistance {
  double value = 0;             ///< > 0 distance, < 0 minus the penetration depth
  Eigen::Vector3d normal;       ///< the minimising direction, from a towards b
};

/// The signed distance by direction search: the best `starts` of `samples` Fibonacci directions,
/// each refined by nested grids on the sphere (21 x 21 directions over a cap of angular radius rho
/// about the best so far, rho shrinking threefold per level down to 1e-11). A grid is used rather
/// than a descent method because f has ridges (the supports jump between features) on which local
/// descent stalls; the grid's error at the last level is about the slope of f times 1e-12. `finest`
/// stops the refinement at a coarser cap (a cheaper oracle whose value is within about the slope
/// of f times `finest` of the grid's minimum).
template <class A, class B>
SignedDistance signed_distance_oracle(const A& a, const RigidTransform<double>& pa, const B& b, const RigidTransform<double>& pb,
                                      int samples = IMPACT_TEST_SANITIZED ? 1000 : 3000, int starts = IMPACT_TEST_SANITIZED ? 1 : 2,
                                      double finest = 1e-11) {
  std::vector<std::pair<double, Eigen::Vector3d>> coarse;
  coarse.reserve(static_cast<std::size_t>(samples));
  const double golden = M_PI * (3 - std::sqrt(5.0));
  for (int i = 0; i < samples; ++i) {
    const double z = 1 - (2 * i + 1.0) / samples;
    const double r = std::sqrt(1 - z * z);
    const Eigen::Vector3d n(r * std::cos(golden * i), r * std::sin(golden * i), z);
    coarse.emplace_back(overlap_along(a, pa, b, pb, n), n);
  }
  std::partial_sort(coarse.begin(), coarse.begin() + starts, coarse.end(),
                    [](const auto& x, const auto& y) { return x.first < y.first; });
  SignedDistance best;
  double fbest = std::numeric_limits<double>::infinity();
  for (int s = 0; s < starts; ++s) {
    Eigen::Vector3d n = coarse[static_cast<std::size_t>(s)].second;
    double fn = coarse[static_cast<std::size_t>(s)].first;
    for (double rho = 4.0 / std::sqrt(double(samples)); rho > finest; rho /= (IMPACT_TEST_SANITIZED ? 2.5 : 3)) {
      const Eigen::Vector3d u = (std::abs(n.x()) < 0.6 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY()).cross(n).normalized();
      const Eigen::Vector3d w = n.cross(u);
      Eigen::Vector3d bn = n;
      constexpr int g = IMPACT_TEST_SANITIZED ? 5 : 10;  // grid half width (fewer under sanitizers)
      for (int i = -g; i <= g; ++i)
        for (int j = -g; j <= g; ++j) {
          const Eigen::Vector3d c = (n + rho * (double(i) / g) * u + rho * (double(j) / g) * w).normalized();
          const double f = overlap_along(a, pa, b, pb, c);
          if (f < fn) {
            fn = f;
            bn = c;
          }
        }
      n = bn;
    }
    if (fn < fbest) {
      fbest = fn;
      best.normal = n;
    }
  }
  best.value = -fbest;
  return best;
}

/// Long-double directions for least_overlap.
using OracleDirection = Eigen::Matrix<long double, 3, 1>;

/// The least overlap found by least_overlap and the direction where it was found.
struct LeastOverlap {
  long double depth = 0;
  OracleDirection normal = OracleDirection::UnitZ();
};

/// The directions n with n . axis = cos_angle (a great circle when cos_angle = 0): where the
/// overlap of a pair has a kink (normal to a box's axis, to a cylinder's axis; a cone's side
/// normals, where its apex and base rim tie), so that a 2-D grid stalls in the valley along it.
struct KinkCircle {
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
  double cos_angle = 0;
};

/// The least of f(n) over unit directions n (f: long-double direction -> long double, the overlap
/// of a pair in closed form in the tests that use it: the penetration depth is its minimum), as
/// the least of two searches, for an independent check of certified candidates (their lower bound
/// lies below the true depth, and the value returned is at least the true depth, so a certificate
/// of a wrong, too large, depth shows as depth - depth_gap above it):
///   on each kink circle: 720 samples of the angle, then 21 samples about the best 3, shrinking
///   tenfold per level to 1e-15 rad (a 2-D grid misses minima in those valleys by about 1e-7);
///   on the sphere: `samples` Fibonacci directions, then about each of the 3 best and of `starts`
///   (the shapes' face and axis normals, the answer under test) a 5 x 5 grid over a cap, moved to
///   its best point while that improves (up to 32 times), then halved, down to 1e-12 rad.
template <class F>
LeastOverlap least_overlap(const F& f, const std::vector<Eigen::Vector3d>& starts, const std::vector<KinkCircle>& circles, int samples = 600) {
  using LD = long double;
  using V3L = OracleDirection;
  LeastOverlap best{f(V3L(V3L::UnitZ())), V3L::UnitZ()};
  const auto keep = [&](LD v, const V3L& n) {
    if (v < best.depth) best = {v, n};
  };
  for (const KinkCircle& circle : circles) {
    const V3L axis = circle.axis.cast<LD>().normalized();
    const V3L e1 = (std::abs(axis.x()) < LD(0.6) ? V3L(1, 0, 0) : V3L(0, 1, 0)).cross(axis).normalized(), e2 = axis.cross(e1);
    const LD c = circle.cos_angle, s = std::sqrt(std::max(1 - c * c, LD(0)));
    const auto at = [&](LD phi) { return V3L(c * axis + s * (std::cos(phi) * e1 + std::sin(phi) * e2)); };
    std::vector<std::pair<LD, LD>> around;
    for (int i = 0; i < 720; ++i) {
      const LD phi = 2 * LD(M_PI) * i / 720;
      around.emplace_back(f(at(phi)), phi);
    }
    std::partial_sort(around.begin(), around.begin() + 3, around.end());
    for (int k = 0; k < 3; ++k) {
      LD phi = around[static_cast<std::size_t>(k)].second, fp = around[static_cast<std::size_t>(k)].first;
      for (LD step = 2 * LD(M_PI) / 720; step > LD(1e-15); step /= 10) {
        const LD centre = phi;
        for (int i = -10; i <= 10; ++i) {
          const LD q = centre + step * i / 10, fq = f(at(q));
          if (fq < fp) {
            fp = fq;
            phi = q;
          }
        }
      }
      keep(fp, at(phi));
    }
  }
  std::vector<std::pair<LD, V3L>> start;
  const LD golden = LD(M_PI) * (3 - std::sqrt(LD(5)));
  for (int i = 0; i < samples; ++i) {
    const LD z = 1 - (2 * i + LD(1)) / samples, rr = std::sqrt(1 - z * z);
    const V3L n(rr * std::cos(golden * i), rr * std::sin(golden * i), z);
    start.emplace_back(f(n), n);
  }
  std::partial_sort(start.begin(), start.begin() + 3, start.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
  start.resize(3);
  for (const Eigen::Vector3d& n : starts) {
    const V3L m = n.normalized().cast<LD>();
    start.emplace_back(f(m), m);
  }
  for (const auto& st : start) {
    V3L n = st.second;
    LD fn = st.first;
    int moves = 0;
    for (LD cap = LD(0.1); cap > LD(1e-12);) {
      const V3L e1 = (std::abs(n.x()) < LD(0.6) ? V3L(1, 0, 0) : V3L(0, 1, 0)).cross(n).normalized(), e2 = n.cross(e1);
      V3L next = n;
      for (int i = -2; i <= 2; ++i) {
        for (int j = -2; j <= 2; ++j) {
          const V3L m = (n + (cap * i / 2) * e1 + (cap * j / 2) * e2).normalized();
          const LD fm = f(m);
          if (fm < fn) {
            fn = fm;
            next = m;
          }
        }
      }
      if (next == n || ++moves == 32) {
        cap /= 2;
        moves = 0;
      }
      n = next;
    }
    keep(fn, n);
  }
  return best;
}

/// The exit distance of the ray from the origin along unit u out of D = A - B (the origin inside D):
///   rho(u) = min over v orthogonal to u of g(v),  g(v) = h_D(u + v)
/// (the supporting plane with normal u + v meets the ray at h_D(u + v) / |u|^2; the least such is
/// the exit point). g is convex in v, so the ellipsoid method in the plane (centre and shape from
/// `v0` and radius `r0`) converges whatever the kinks of h_D; the value returned is the least g
/// evaluated, an upper bound of rho(u), hence of the penetration depth, whichever v it stops at.
/// `v_out` is the best v (a warm start for nearby u).
template <class A, class B>
double ray_exit_upper(const A& a, const RigidTransform<double>& pa, const B& b, const RigidTransform<double>& pb, const Eigen::Vector3d& u,
                      const Eigen::Vector2d& v0, double r0, Eigen::Vector2d* v_out = nullptr, int iterations = 360) {
  const Eigen::Vector3d e1 = (std::abs(u.x()) < 0.6 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY()).cross(u).normalized();
  const Eigen::Vector3d e2 = u.cross(e1);
  Eigen::Vector2d c = v0, best_v = v0;
  Eigen::Matrix2d P = Eigen::Matrix2d::Identity() * (r0 * r0);
  double best = std::numeric_limits<double>::infinity();
  for (int k = 0; k < iterations; ++k) {
    const Eigen::Vector3d m = u + c.x() * e1 + c.y() * e2;
    const Eigen::Vector3d sd = support(a, pa, m) - support(b, pb, Eigen::Vector3d(-m));
    const double g = m.dot(sd);
    if (g < best) {
      best = g;
      best_v = c;
    }
    const Eigen::Vector2d sub(e1.dot(sd), e2.dot(sd));
    const double den = std::sqrt(std::max(sub.dot(P * sub), 0.0));
    if (!(den > 1e-300)) break;
    const Eigen::Vector2d Pg = P * sub / den;
    c -= Pg / 3.0;
    P = (4.0 / 3.0) * (P - (2.0 / 3.0) * Pg * Pg.transpose());
    P = (P + P.transpose()).eval() / 2.0;
  }
  if (v_out) *v_out = best_v;
  return best;
}

/// A second upper bound of the penetration depth of intersecting A and B, by a search over ray
/// directions u of the exit distance rho(u) (ray_exit_upper): depth = min_u rho(u), and unlike the
/// overlap f(n) of signed_distance_oracle, rho has no valley along the edges of D at its minimum
/// (there the boundary of D is met by the largest ball about the origin, so it is smooth; edges
/// of D are ridges of rho), so a pattern search from a start near the minimum (the grid search's
/// normal) converges to it. Returns the least upper bound found and the direction in `u_out`.
template <class A, class B>
double ray_depth_upper(const A& a, const RigidTransform<double>& pa, const B& b, const RigidTransform<double>& pb, const Eigen::Vector3d& u0,
                       Eigen::Vector3d* u_out = nullptr) {
  const Eigen::Vector3d e1 = (std::abs(u0.x()) < 0.6 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY()).cross(u0).normalized();
  const Eigen::Vector3d e2 = u0.cross(e1);
  Eigen::Vector2d x = Eigen::Vector2d::Zero(), warm = Eigen::Vector2d::Zero();
  const auto rho = [&](const Eigen::Vector2d& p, Eigen::Vector2d* w) {
    const Eigen::Vector3d u = (u0 + p.x() * e1 + p.y() * e2).normalized();
    return ray_exit_upper(a, pa, b, pb, u, Eigen::Vector2d::Zero(), 4.0, w);
  };
  double best = rho(x, &warm);
  static const int dirs[8][2] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}, {1, 1}, {1, -1}, {-1, 1}, {-1, -1}};
  for (double step = 2e-2; step > 1e-10; step /= 4) {
    for (int moves = 0; moves < 40; ++moves) {
      double bv = best;
      Eigen::Vector2d bx = x;
      for (const auto& d : dirs) {
        const Eigen::Vector2d p = x + step * Eigen::Vector2d(d[0], d[1]);
        const double r = rho(p, nullptr);
        if (r < bv) {
          bv = r;
          bx = p;
        }
      }
      if (!(bv < best)) break;
      best = bv;
      x = bx;
    }
  }
  if (u_out) *u_out = (u0 + x.x() * e1 + x.y() * e2).normalized();
  return best;
}

/// Certified bracket of the distance of two separated convex sets by the ellipsoid method on the
/// convex function g(x) = h_A(x) + h_B(-x) over the unit ball (distance = -min g; a subgradient of
/// g at x is s_A(x) - s_B(-x), the difference of support points). `lower` and `upper` bound the
/// true distance (lower: -g at the best feasible centre, a separating direction; upper: the
/// ellipsoid's cut bound); for intersecting sets upper <= 0 within the width.
struct DistanceBracket {
  double lower = 0, upper = 0;
};
template <class A, class B>
DistanceBracket distance_bracket(const A& a, const RigidTransform<double>& pa, const B& b, const RigidTransform<double>& pb,
                                 int iterations = 1200) {
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  Eigen::Matrix3d P = Eigen::Matrix3d::Identity() * 1.0001;
  double gbest = std::numeric_limits<double>::infinity(), lb = -std::numeric_limits<double>::infinity();
  for (int k = 0; k < iterations; ++k) {
    Eigen::Vector3d sub;
    if (c.norm() > 1) {
      sub = c / c.norm();  // feasibility cut
    } else {
      const Eigen::Vector3d sa = support(a, pa, c), sb = support(b, pb, Eigen::Vector3d(-c));
      const double g = c.dot(sa) - c.dot(sb);
      sub = sa - sb;
      gbest = std::min(gbest, g);
      const double w = std::sqrt(std::max(sub.dot(P * sub), 0.0));
      lb = std::max(lb, g - w);
      if (w < 1e-14) break;
    }
    const double den = std::sqrt(std::max(sub.dot(P * sub), 0.0));
    if (!(den > 0)) break;
    const Eigen::Vector3d Pa = P * sub / den;
    c -= Pa / 4.0;
    P = (9.0 / 8.0) * (P - 0.5 * Pa * Pa.transpose());
    P = (P + P.transpose()).eval() / 2.0;
  }
  return {-gbest, -lb};
}

/// The penetration depth of two intersecting convex polytopes (boxes, hulls) exactly: the least
/// overlap f(n) over the candidate axes of their Minkowski difference (face normals of each, cross
/// products of edge directions). `normals` and `edges` are in world coordinates.
inline double polytope_depth(const std::vector<Eigen::Vector3d>& normals, const std::vector<Eigen::Vector3d>& edges_a,
                             const std::vector<Eigen::Vector3d>& edges_b, const std::function<double(const Eigen::Vector3d&)>& f) {
  double best = std::numeric_limits<double>::infinity();
  const auto consider = [&](Eigen::Vector3d n) {
    if (n.norm() < 1e-9) return;
    n.normalize();
    best = std::min({best, f(n), f(Eigen::Vector3d(-n))});
  };
  for (const auto& n : normals) consider(n);
  for (const auto& ea : edges_a)
    for (const auto& eb : edges_b) consider(ea.cross(eb));
  return best;
}
inline void polytope_features(const Box<double>& b, const RigidTransform<double>& p, std::vector<Eigen::Vector3d>& normals,
                              std::vector<Eigen::Vector3d>& edges) {
  (void)b;
  for (int i = 0; i < 3; ++i) {
    normals.push_back(p.R.col(i));
    edges.push_back(p.R.col(i));
  }
}
inline void polytope_features(const ConvexHull<double>& h, const RigidTransform<double>& p, std::vector<Eigen::Vector3d>& normals,
                              std::vector<Eigen::Vector3d>& edges) {
  for (Eigen::Index t = 0; t < h.triangles.rows(); ++t) {
    const Eigen::Vector3d x = h.vertices.row(h.triangles(t, 0)).transpose(), y = h.vertices.row(h.triangles(t, 1)).transpose(),
                          z = h.vertices.row(h.triangles(t, 2)).transpose();
    normals.push_back(p.R * (y - x).cross(z - x));
    for (int k = 0; k < 3; ++k) {  // each edge once (from the triangle where it runs upwards in index)
      const int u = h.triangles(t, k), v = h.triangles(t, (k + 1) % 3);
      if (u < v) edges.push_back(p.R * (h.vertices.row(v) - h.vertices.row(u)).transpose());
    }
  }
}

/// The tested shapes, one size each (about 1 across), and a hull of 40 points of an ellipsoid.
struct ConvexZoo {
  Sphere<double> sphere{Eigen::Vector3d::Zero(), 0.5};
  Capsule<double> capsule{0.3, 0.6};
  Cylinder<double> cylinder{0.4, 0.5};
  Cone<double> cone{0.5, 0.6};
  Box<double> box{Eigen::Vector3d(0.4, 0.3, 0.5)};
  ConvexHull<double> hull;
  ConvexZoo() {
    Rng rng(77);
    Vertices<double> p(40, 3);
    for (int i = 0; i < 40; ++i) {
      Eigen::Vector3d d = rng.vec(-1, 1);
      while (d.norm() < 0.1) d = rng.vec(-1, 1);
      d.normalize();
      p.row(i) = Eigen::Vector3d(0.5 * d.x(), 0.35 * d.y(), 0.45 * d.z()).transpose();
    }
    hull = convex_hull(p);
  }
};

/// One zoo for the whole test program (its hulls are built once).
inline const ConvexZoo& zoo() {
  static const ConvexZoo z;
  return z;
}

/// Poses of b about a at the origin: random rotations, b's translation uniform in the cube of
/// half side `reach` (a good share intersect, the rest are near).
inline std::vector<std::pair<RigidTransform<double>, RigidTransform<double>>> convex_poses(int n, double reach, std::uint64_t seed) {
  Rng rng(seed);
  std::vector<std::pair<RigidTransform<double>, RigidTransform<double>>> out;
  for (int i = 0; i < n; ++i) {
    RigidTransform<double> pa{rng.rotation(), Eigen::Vector3d::Zero()};
    RigidTransform<double> pb = random_pose(rng, Eigen::Vector3d::Constant(-reach), Eigen::Vector3d::Constant(reach));
    out.emplace_back(pa, pb);
  }
  return out;
}

}  // namespace impact::test
