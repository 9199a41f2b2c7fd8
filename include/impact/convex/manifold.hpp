// SPDX-License-Identifier: MIT
/// \file
/// Contact manifolds for a solver: up to four contact points with their own depths and the common
/// normal, from convex_penetration (convex/query.hpp) and, for shapes with flat faces (Box,
/// ConvexHull), face clipping: the reference face is the face of either shape most aligned with
/// the contact normal, the incident face the other shape's face most opposed to it; the incident
/// polygon is clipped by the side planes of the reference face (Sutherland–Hodgman) and its points
/// below the reference plane are the contacts, reduced to four (the deepest, the farthest from it,
/// then the two that enlarge the contact area most). Curved shapes (sphere, capsule, cylinder,
/// cone), and flat shapes touching on an edge or a vertex (no face within `face_angle` of the
/// normal), give one point: the penetration's.
///
/// Definitions: normal as in convex_penetration (unit, from a towards b); each point lies midway
/// between the reference face's plane and the incident feature, and its depth is their distance
/// along the normal (>= 0); the deepest point's depth equals the penetration depth up to the
/// solver's tolerance for face–face contacts.
#pragma once

#include "impact/convex/query.hpp"

#include <array>
#include <vector>

namespace impact {

template <class S>
struct ConvexManifold {
  int count = 0;                            ///< 0 (not touching) .. 4
  std::array<Vec3<S>, 4> points{};          ///< world contact points
  std::array<S, 4> depths{};                ///< penetration at each point, >= 0
  Vec3<S> normal = Vec3<S>::UnitZ();        ///< unit, from a towards b
  bool limit_reached = false;               ///< the penetration solver hit its iteration bound
};

struct ManifoldOptions {
  /// A face is used for clipping when its normal is within this angle (radians) of the contact
  /// normal; otherwise the contact is an edge or vertex contact with one point.
  double face_angle = 0.05;
};

namespace detail {

template <class T>
inline constexpr bool has_faces_v = false;
template <class S>
inline constexpr bool has_faces_v<Box<S>> = true;
template <class S>
inline constexpr bool has_faces_v<ConvexHull<S>> = true;

/// The face of a box or hull (world coordinates) whose outward normal is most aligned with d.
template <class S>
void best_face(const Box<S>& b, const RigidTransform<S>& p, const Vec3<S>& d, std::vector<Vec3<S>>& poly, Vec3<S>& n) {
  const Vec3<S> l = p.R.transpose() * d;
  int k;
  l.cwiseAbs().maxCoeff(&k);
  const S s = l[k] >= S(0) ? S(1) : S(-1);
  const int u = (k + 1) % 3, v = (k + 2) % 3;
  const Vec3<S>& h = b.half;
  poly.clear();
  // counter-clockwise seen from outside (from +s e_k)
  const S us[4] = {S(-1), S(1), S(1), S(-1)}, vs[4] = {S(-1), S(-1), S(1), S(1)};
  for (int i = 0; i < 4; ++i) {
    Vec3<S> x;
    x[k] = s * h[k];
    x[u] = us[i] * h[u];
    x[v] = (s > S(0) ? vs[i] : -vs[i]) * h[v];
    poly.push_back(p.apply(x));
  }
  Vec3<S> nl = Vec3<S>::Zero();
  nl[k] = s;
  n = p.rotate(nl);
}
template <class S>
void best_face(const ConvexHull<S>& h, const RigidTransform<S>& p, const Vec3<S>& d, std::vector<Vec3<S>>& poly, Vec3<S>& n) {
  const Vec3<S> l = p.R.transpose() * d;
  std::size_t best = 0;
  S best_dot = -std::numeric_limits<S>::infinity();
  for (std::size_t i = 0; i < h.faces.size(); ++i) {
    const S x = h.faces[i].normal.dot(l);
    if (x > best_dot) {
      best_dot = x;
      best = i;
    }
  }
  poly.clear();
  for (int v : h.faces[best].vertices) poly.push_back(p.apply(Vec3<S>(h.vertices.row(v).transpose())));
  n = p.rotate(h.faces[best].normal);
}

/// Keeps the points of poly on the inner side of the plane (n . x <= c).
template <class S>
void clip(std::vector<Vec3<S>>& poly, const Vec3<S>& n, S c, std::vector<Vec3<S>>& tmp) {
  tmp.clear();
  const std::size_t m = poly.size();
  for (std::size_t i = 0; i < m; ++i) {
    const Vec3<S>& x = poly[i];
    const Vec3<S>& y = poly[(i + 1) % m];
    const S dx = n.dot(x) - c, dy = n.dot(y) - c;
    if (dx <= S(0)) tmp.push_back(x);
    if ((dx < S(0) && dy > S(0)) || (dx > S(0) && dy < S(0))) tmp.push_back(x + (y - x) * (dx / (dx - dy)));
  }
  poly.swap(tmp);
}

}  // namespace detail

/// The contact manifold of shapes a (at pose_a) and b (at pose_b); count == 0 when they do not
/// touch. Throws InvalidInput like convex_penetration.
template <class S, class A, class B>
ConvexManifold<S> convex_manifold(const A& a, const RigidTransform<S>& pose_a, const B& b, const RigidTransform<S>& pose_b,
                                  const ConvexQueryOptions<S>& options = {}, const ManifoldOptions& manifold = {}) {
  ConvexManifold<S> m;
  if (!(manifold.face_angle >= 0 && manifold.face_angle < 1.5)) throw InvalidInput("convex_manifold: face_angle must be in [0, 1.5)");
  const ConvexContact<S> c = convex_penetration(a, pose_a, b, pose_b, options);
  m.limit_reached = c.limit_reached;
  if (!c.intersecting) return m;
  m.normal = c.normal;
  m.count = 1;
  m.points[0] = c.point;
  m.depths[0] = c.depth;
  if constexpr (detail::has_faces_v<A> && detail::has_faces_v<B>) {
    std::vector<Vec3<S>> fa, fb, tmp;
    Vec3<S> na, nb;
    detail::best_face(a, pose_a, c.normal, fa, na);
    detail::best_face(b, pose_b, Vec3<S>(-c.normal), fb, nb);
    const S align_a = na.dot(c.normal), align_b = -nb.dot(c.normal);
    const S cos_limit = S(std::cos(manifold.face_angle));
    if (std::max(align_a, align_b) < cos_limit) return m;  // edge or vertex contact
    // Reference: the better aligned face; its outward normal points into the other shape.
    const bool ref_is_a = align_a >= align_b;
    const std::vector<Vec3<S>>& ref = ref_is_a ? fa : fb;
    std::vector<Vec3<S>> inc = ref_is_a ? fb : fa;
    const Vec3<S> rn = ref_is_a ? na : nb;
    const std::size_t k = ref.size();
    for (std::size_t i = 0; i < k && !inc.empty(); ++i) {
      const Vec3<S> edge = ref[(i + 1) % k] - ref[i];
      const Vec3<S> side = edge.cross(rn);  // outward for a counter-clockwise face
      const S len = side.norm();
      if (!(len > S(0))) continue;
      detail::clip(inc, Vec3<S>(side / len), side.dot(ref[i]) / len, tmp);
    }
    const S plane = rn.dot(ref[0]);
    std::vector<std::pair<S, Vec3<S>>> pts;  // depth, point midway
    for (const Vec3<S>& x : inc) {
      const S depth = plane - rn.dot(x);  // below the reference face = penetrating
      if (depth < S(0)) continue;
      pts.push_back({depth, Vec3<S>(x + rn * (depth / S(2)))});
    }
    if (pts.empty()) return m;
    // Reduce to four: deepest, farthest from it, then the two adding the most area.
    std::array<std::size_t, 4> pick{};
    std::size_t n_pick = 0;
    std::size_t i0 = 0;
    for (std::size_t i = 1; i < pts.size(); ++i)
      if (pts[i].first > pts[i0].first) i0 = i;
    pick[n_pick++] = i0;
    if (pts.size() > 1) {
      std::size_t i1 = i0;
      S best = S(-1);
      for (std::size_t i = 0; i < pts.size(); ++i) {
        const S d2 = (pts[i].second - pts[i0].second).squaredNorm();
        if (d2 > best) {
          best = d2;
          i1 = i;
        }
      }
      if (best > S(0)) pick[n_pick++] = i1;
    }
    if (n_pick == 2) {
      const Vec3<S> p0 = pts[pick[0]].second, p1 = pts[pick[1]].second;
      std::size_t i2 = pick[0];
      S best = S(0);
      for (std::size_t i = 0; i < pts.size(); ++i) {
        const S area = std::abs((p1 - p0).cross(pts[i].second - p0).dot(rn));
        if (area > best) {
          best = area;
          i2 = i;
        }
      }
      if (best > S(0)) pick[n_pick++] = i2;
    }
    if (n_pick == 3) {
      // the point farthest outside the triangle's edges (largest added area)
      const Vec3<S> q[3] = {pts[pick[0]].second, pts[pick[1]].second, pts[pick[2]].second};
      const S orient = (q[1] - q[0]).cross(q[2] - q[0]).dot(rn) >= S(0) ? S(1) : S(-1);
      std::size_t i3 = pick[0];
      S best = S(0);
      for (std::size_t i = 0; i < pts.size(); ++i)
        for (int e = 0; e < 3; ++e) {
          const S area = -orient * (q[(e + 1) % 3] - q[e]).cross(pts[i].second - q[e]).dot(rn);
          if (area > best) {
            best = area;
            i3 = i;
          }
        }
      if (best > S(0)) pick[n_pick++] = i3;
    }
    m.count = static_cast<int>(n_pick);
    for (std::size_t i = 0; i < n_pick; ++i) {
      m.points[i] = pts[pick[i]].second;
      m.depths[i] = pts[pick[i]].first;
    }
    // The manifold's normal is the reference face's (oriented from a towards b).
    m.normal = ref_is_a ? rn : Vec3<S>(-rn);
  }
  return m;
}

}  // namespace impact
