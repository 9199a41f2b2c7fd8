// SPDX-License-Identifier: MIT
/// \file
/// The narrow phase of a scene, dispatched per pair of object kinds: the shapes a scene holds
/// (sphere, oriented box, mesh with its sphere tree, particle), each under a rigid pose, and
/// shapes_intersect(), which picks the test for the pair:
///   sphere/particle – sphere/particle   centre distance, padded for its rounding (conservative)
///   sphere – box                        closest point of the box, padded for its rounding
///                                       (conservative; the centre moved into the box's frame)
///   box – box                           separating axes (impact::overlap on Obb, conservative)
///   sphere – mesh, box – mesh           the mesh's tree walked with the other shape in the mesh's
///                                       frame, node tests padded for the rounding of that move
///                                       and of their comparisons; triangles tested by separating
///                                       axes with a bound of their rounding (sphere: normal, edge
///                                       and vertex directions, query/mesh_collide.hpp; box: 13
///                                       axes): conservative, never false for a touching triangle
///   mesh – mesh                         pair traversal of both trees under the relative pose
///                                       with the node test of query/mesh_collide.hpp (padded for
///                                       the pose's rounding), exact triangles_intersect
///                                       (narrow/triangle_triangle.hpp) at the leaves
/// Meshes are surfaces (as in FCL): a shape entirely inside a closed mesh does not touch it.
/// Every test counts touching as intersecting. A contact (point, unit normal from a towards b,
/// depth) is computed only when the caller passes somewhere to put it; for mesh pairs the depth is
/// the one of the first touching triangle found and is only indicative.
#pragma once

#include "impact/bvh/mesh_bvh.hpp"
#include "impact/bvh/traverse.hpp"
#include "impact/bvh/traverse_pair.hpp"
#include "impact/geometry/obb.hpp"
#include "impact/narrow/closest_point.hpp"
#include "impact/narrow/triangle_triangle.hpp"
#include "impact/query/mesh_collide.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

namespace impact {

/// The kinds of scene objects.
enum class ShapeKind : std::uint8_t { Sphere, Box, Mesh, Particle };

/// A scene object's shape in its own frame (the pose places it). Spheres and particles are centred
/// on the pose's origin; a box has half extents along the pose's axes; a mesh is shared by pointer
/// and must outlive every scene holding it.
template <class S>
struct Shape {
  using MeshType = MeshBvh<Sphere<S>>;

  ShapeKind kind = ShapeKind::Particle;
  S radius = S(0);                 ///< spheres and particles, >= 0
  Vec3<S> half = Vec3<S>::Zero();  ///< boxes, >= 0 per axis
  const MeshType* mesh = nullptr;  ///< meshes

  static Shape sphere(S r) {
    Shape s;
    s.kind = ShapeKind::Sphere;
    s.radius = r;
    return s;
  }
  static Shape box(const Vec3<S>& half_extents) {
    Shape s;
    s.kind = ShapeKind::Box;
    s.half = half_extents;
    return s;
  }
  /// `m` is not copied: it must outlive the shape's users.
  static Shape mesh_of(const MeshType& m) {
    Shape s;
    s.kind = ShapeKind::Mesh;
    s.mesh = &m;
    return s;
  }
  /// A point (radius 0) or a small ball.
  static Shape particle(S r = S(0)) {
    Shape s;
    s.kind = ShapeKind::Particle;
    s.radius = r;
    return s;
  }
  bool is_round() const { return kind == ShapeKind::Sphere || kind == ShapeKind::Particle; }
};

/// A contact between two shapes, in world coordinates. `normal` is a unit vector pointing from the
/// first shape towards the second; `depth` >= 0 is how far they interpenetrate along it.
template <class S>
struct ShapeContact {
  Vec3<S> point = Vec3<S>::Zero();
  Vec3<S> normal = Vec3<S>::UnitZ();
  S depth = S(0);
};

namespace detail {

/// Projection interval of n points on axis.
template <class S>
inline void project(const Vec3<S>* pts, int n, const Vec3<S>& axis, S& lo, S& hi) {
  lo = hi = pts[0].dot(axis);
  for (int i = 1; i < n; ++i) {
    const S d = pts[i].dot(axis);
    lo = std::min(lo, d);
    hi = std::max(hi, d);
  }
}

/// Separating-axis test of two convex point sets on the given candidate axes (zero axes are
/// skipped). Conservative: a relative slack keeps touching sets intersecting under rounding.
template <class S>
inline bool sat_overlap(const Vec3<S>* a, int na, const Vec3<S>* b, int nb, const Vec3<S>* axes, int n_axes) {
  for (int k = 0; k < n_axes; ++k) {
    const Vec3<S>& ax = axes[k];
    const S len2 = ax.squaredNorm();
    if (!(len2 > std::numeric_limits<S>::min())) continue;
    S alo, ahi, blo, bhi;
    project(a, na, ax, alo, ahi);
    project(b, nb, ax, blo, bhi);
    const S slack = S(16) * std::numeric_limits<S>::epsilon() *
                    (std::max({std::abs(alo), std::abs(ahi), std::abs(blo), std::abs(bhi)}) + std::sqrt(len2));
    if (ahi + slack < blo || bhi + slack < alo) return false;
  }
  return true;
}

/// Triangle against an axis-aligned box centred at the origin with half extents h (13 axes).
template <class S>
bool triangle_box_overlap(const Vec3<S>& a, const Vec3<S>& b, const Vec3<S>& c, const Vec3<S>& h) {
  const Vec3<S> tri[3] = {a, b, c};
  Vec3<S> corners[8];
  for (int i = 0; i < 8; ++i) corners[i] = Vec3<S>((i & 1) ? h.x() : -h.x(), (i & 2) ? h.y() : -h.y(), (i & 4) ? h.z() : -h.z());
  const Vec3<S> e[3] = {b - a, c - b, a - c};
  Vec3<S> axes[13];
  int n = 0;
  for (int i = 0; i < 3; ++i) axes[n++] = Vec3<S>::Unit(i);
  axes[n++] = e[0].cross(e[1]);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) axes[n++] = Vec3<S>::Unit(i).cross(e[j]);
  return sat_overlap(tri, 3, corners, 8, axes, n);
}

/// Does a sphere (centre c, radius r) meet the closed box centred at the origin with half extents h?
/// Conservative: c - q is exact or rounded once (relative u), so the squared distance and r^2 are
/// each within a relative 4u, which the comparison allows for.
template <class S>
inline bool sphere_box_local(const Vec3<S>& c, S r, const Vec3<S>& h) {
  const Vec3<S> q = c.cwiseMax(-h).cwiseMin(h);
  return (c - q).squaredNorm() <= r * r * (S(1) + S(8) * std::numeric_limits<S>::epsilon());
}

template <class S>
bool sphere_sphere(const Vec3<S>& ca, S ra, const Vec3<S>& cb, S rb, ShapeContact<S>* out) {
  const Vec3<S> d = cb - ca;
  const S r = ra + rb;
  const S d2 = d.squaredNorm();
  // each difference and the radius sum are rounded once (a relative u), the squares and sums
  // within a relative 4u: padded so that balls touching exactly are never reported apart (a plain
  // comparison missed about one exact contact in ten)
  if (d2 > r * r * (S(1) + S(8) * std::numeric_limits<S>::epsilon())) return false;
  if (out) {
    const S dist = std::sqrt(d2);
    out->normal = dist > S(0) ? Vec3<S>(d / dist) : Vec3<S>::UnitZ();
    out->depth = r - dist;
    out->point = ca + out->normal * (ra - out->depth / S(2));
  }
  return true;
}

/// Sphere a (centre c, radius r) against box b; normal from the sphere towards the box.
template <class S>
bool sphere_box(const Vec3<S>& c, S r, const Vec3<S>& half, const RigidTransform<S>& pb, ShapeContact<S>* out) {
  const Vec3<S> lc = pb.R.transpose() * (c - pb.t);
  const Vec3<S> q = lc.cwiseMax(-half).cwiseMin(half);
  const Vec3<S> d = lc - q;
  const S d2 = d.squaredNorm();
  if (d2 > r * r * (S(1) + S(8) * std::numeric_limits<S>::epsilon())) return false;  // padded as in sphere_sphere
  if (out) {
    if (d2 > S(0)) {
      const S dist = std::sqrt(d2);
      out->normal = pb.rotate(-d / dist);
      out->depth = r - dist;
      out->point = pb.apply(q);
    } else {  // centre inside the box: push out through the nearest face
      const Vec3<S> gap = half - lc.cwiseAbs();
      int k;
      gap.minCoeff(&k);
      Vec3<S> n = Vec3<S>::Zero();
      n[k] = lc[k] >= S(0) ? S(-1) : S(1);
      out->normal = pb.rotate(n);
      out->depth = r + gap[k];
      out->point = c;
    }
  }
  return true;
}

/// Box a against box b; contact by the axis of least overlap among the 15 SAT axes.
template <class S>
bool box_box(const Vec3<S>& ha, const RigidTransform<S>& pa, const Vec3<S>& hb, const RigidTransform<S>& pb,
             ShapeContact<S>* out) {
  Obb<S> a, b;
  a.center = pa.t;
  a.axes = pa.R;
  a.half = ha;
  b.center = pb.t;
  b.axes = pb.R;
  b.half = hb;
  if (!overlap(a, b)) return false;
  if (!out) return true;
  const Vec3<S> t = pb.t - pa.t;
  Vec3<S> axes[15];
  int n = 0;
  for (int i = 0; i < 3; ++i) axes[n++] = pa.R.col(i);
  for (int i = 0; i < 3; ++i) axes[n++] = pb.R.col(i);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) axes[n++] = pa.R.col(i).cross(pb.R.col(j));
  S best = std::numeric_limits<S>::infinity();
  Vec3<S> best_axis = Vec3<S>::UnitZ();
  for (int k = 0; k < n; ++k) {
    const S len = axes[k].norm();
    if (len < S(1e-3)) continue;  // near-parallel edges: their face axes decide
    const Vec3<S> ax = axes[k] / len;
    const S ra = (pa.R.transpose() * ax).cwiseAbs().dot(ha);
    const S rb = (pb.R.transpose() * ax).cwiseAbs().dot(hb);
    const S dist = ax.dot(t);
    const S depth = ra + rb - std::abs(dist);
    if (depth < best) {
      best = depth;
      best_axis = dist >= S(0) ? ax : Vec3<S>(-ax);
    }
  }
  out->normal = best_axis;
  out->depth = std::max(best, S(0));
  // Midpoint of the deepest point of each box along the normal.
  const Vec3<S> sa = pa.t + pa.R * (pa.R.transpose() * best_axis).cwiseSign().cwiseProduct(ha);
  const Vec3<S> sb = pb.t - pb.R * (pb.R.transpose() * best_axis).cwiseSign().cwiseProduct(hb);
  out->point = (sa + sb) / S(2);
  return true;
}

/// A round shape (centre c in world, radius r) against a mesh surface.
template <class S>
bool sphere_mesh(const Vec3<S>& c, S r, const MeshBvh<Sphere<S>>& m, const RigidTransform<S>& pm, bool flip,
                 ShapeContact<S>* out) {
  constexpr S u = std::numeric_limits<S>::epsilon() / S(2);
  // The centre is moved into the mesh's frame once; node and leaf tests both use this lc, so its
  // rounding does not matter to them. The node test is padded for its own rounding (each of the
  // squared distance and squared radius sum within a relative 4u): a plain comparison culled a
  // ball touching a small triangle exactly when the ball was much larger than the node's sphere
  // (whose padding is ulps of its own radius). The leaf test rejects a triangle only when the
  // separating-axis test of the mesh queries, with its complete set of axes, proves it apart: a
  // rounded closest-point distance alone missed exact contacts.
  const Vec3<S> lc = pm.R.transpose() * (c - pm.t);
  bool hit = false;
  traverse(
      m.tree(),
      [&](const Sphere<S>& bv) {
        const S rs = bv.radius + r;
        return (bv.center - lc).squaredNorm() <= rs * rs * (S(1) + S(16) * u);
      },
      [&](std::int32_t k) {
        const Triangle<S>& t = m.triangle(k);
        // a rounded closest point within r is accepted (conservative: it is within rounding of
        // touching); beyond it, only a proven separation rejects, tried first along the direction
        // from that closest point
        const auto cp = closest_point_on_triangle(lc, t);
        if (!(cp.squared_distance <= r * r)) {
          const Vec3<S> axis = lc - cp.point;
          if (!sphere_may_touch_triangle(lc, r, t, true, &axis)) return true;
        }
        hit = true;
        if (out) {
          const Vec3<S>& q = cp.point;
          const S dist = std::sqrt(cp.squared_distance);
          Vec3<S> n = dist > S(0) ? Vec3<S>((q - lc) / dist) : t.normal();  // sphere towards mesh
          if (n.squaredNorm() == S(0)) n = Vec3<S>::UnitZ();
          out->normal = pm.rotate(flip ? Vec3<S>(-n) : n);
          out->depth = std::max(r - dist, S(0));
          out->point = pm.apply(q);
        }
        return false;
      });
  return hit;
}

/// A box (half extents h at pose pb) against a mesh surface.
template <class S>
bool box_mesh(const Vec3<S>& h, const RigidTransform<S>& pb, const MeshBvh<Sphere<S>>& m, const RigidTransform<S>& pm, bool flip,
              ShapeContact<S>* out) {
  // Work in the box's frame: the mesh's nodes and triangles are moved by mesh -> box.
  const RigidTransform<S> m_to_b = relative_transform(pb, pm);
  // The node test is padded as the mesh queries pad B's spheres (query/mesh_collide.hpp, PosePad):
  // a node's centre and its triangles' vertices are each moved with rounding at the scale of the
  // mesh's coordinates and the relative translation, not of the node's radius, and the
  // comparison's own rounding (a relative 4u on each side) is covered too. Unpadded, touching
  // pairs were missed when the mesh's coordinates near the box were large.
  constexpr S u = std::numeric_limits<S>::epsilon() / S(2);
  const PosePad<S> pad(m_to_b, S(0), m.coordinate_bound());
  bool hit = false;
  traverse(
      m.tree(),
      [&](const Sphere<S>& bv) {
        if (pad.identity) return sphere_box_local(bv.center, bv.radius, h);
        return sphere_box_local(m_to_b.apply(bv.center), (pad.stretch * bv.radius + pad.b_abs) * (S(1) + S(8) * u), h);
      },
      [&](std::int32_t k) {
        const Triangle<S>& t = m.triangle(k);
        const Vec3<S> a = m_to_b.apply(t.a), b = m_to_b.apply(t.b), c = m_to_b.apply(t.c);
        if (!triangle_box_overlap(a, b, c, h)) return true;
        hit = true;
        if (out) {
          const Vec3<S> cen = (a + b + c) / S(3);
          Vec3<S> n = cen.squaredNorm() > S(0) ? Vec3<S>(cen.normalized()) : Vec3<S>::UnitZ();  // box towards mesh
          out->normal = pb.rotate(flip ? Vec3<S>(-n) : n);
          out->depth = S(0);
          out->point =
              pb.apply(closest_point_on_triangle(Vec3<S>::Zero().eval(), Triangle<S>(a, b, c)).point.cwiseMax(-h).cwiseMin(h));
        }
        return false;
      });
  return hit;
}

template <class S>
bool mesh_mesh(const MeshBvh<Sphere<S>>& ma, const RigidTransform<S>& pa, const MeshBvh<Sphere<S>>& mb,
               const RigidTransform<S>& pb, ShapeContact<S>* out) {
  const RigidTransform<S> b_to_a = relative_transform(pa, pb);
  bool hit = false;
  // The node test of the mesh queries (query/mesh_collide.hpp): spheres padded for the rounding of
  // the relative pose and of B's moved vertices (PosePad), and the leaf-triangle cull, so that no
  // pair the exact triangle test would report is culled (a plain sphere overlap under b_to_a
  // missed touching pairs at large translations).
  std::uint64_t node_tests = 0;
  const MeshNodeOverlap<Sphere<S>> overlap(ma, mb, b_to_a, &node_tests);
  traverse_pair_nodes(
      ma.tree(), mb.tree(), overlap,
      [&](std::int32_t i, std::int32_t j) {
        const Triangle<S>& ta = ma.triangle(i);
        const Triangle<S>& tb0 = mb.triangle(j);
        const Triangle<S> tb(b_to_a.apply(tb0.a), b_to_a.apply(tb0.b), b_to_a.apply(tb0.c));
        if (!triangles_intersect(ta, tb)) return true;
        hit = true;
        if (out) {
          Vec3<S> n = ta.normal();
          if ((tb.centroid() - ta.centroid()).dot(n) < S(0)) n = -n;
          if (n.squaredNorm() == S(0)) n = Vec3<S>::UnitZ();
          out->normal = pa.rotate(n);
          out->depth = S(0);
          out->point = pa.apply((ta.centroid() + tb.centroid()) / S(2));
        }
        return false;
      });
  return hit;
}

}  // namespace detail

/// True when shape a at pose pa and shape b at pose pb touch or intersect; fills *contact (normal
/// from a towards b) when contact is not null. Meshes are surfaces.
template <class S>
bool shapes_intersect(const Shape<S>& a, const RigidTransform<S>& pa, const Shape<S>& b, const RigidTransform<S>& pb,
                      ShapeContact<S>* contact = nullptr) {
  using detail::box_box;
  using detail::box_mesh;
  using detail::mesh_mesh;
  using detail::sphere_box;
  using detail::sphere_mesh;
  using detail::sphere_sphere;
  const auto flip = [&](bool hit) {
    if (hit && contact) contact->normal = -contact->normal;
    return hit;
  };
  if (a.is_round()) {
    if (b.is_round()) return sphere_sphere(pa.t, a.radius, pb.t, b.radius, contact);
    if (b.kind == ShapeKind::Box) return sphere_box(pa.t, a.radius, b.half, pb, contact);
    return sphere_mesh(pa.t, a.radius, *b.mesh, pb, false, contact);
  }
  if (a.kind == ShapeKind::Box) {
    if (b.is_round()) return flip(sphere_box(pb.t, b.radius, a.half, pa, contact));
    if (b.kind == ShapeKind::Box) return box_box(a.half, pa, b.half, pb, contact);
    return box_mesh(a.half, pa, *b.mesh, pb, false, contact);
  }
  // a is a mesh
  if (b.is_round()) return sphere_mesh(pb.t, b.radius, *a.mesh, pa, true, contact);
  if (b.kind == ShapeKind::Box) return box_mesh(b.half, pb, *a.mesh, pa, true, contact);
  return mesh_mesh(*a.mesh, pa, *b.mesh, pb, contact);
}

}  // namespace impact
