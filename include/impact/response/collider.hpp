// SPDX-License-Identifier: MIT
/// \file
/// Colliders for particles: a plane (half-space), a sphere, a box (oriented, or axis-aligned
/// through the Aabb constructor) and a triangle mesh (a MeshBvh), each placed in the world by a
/// rigid pose that may move with a linear and an angular velocity, and each with its own
/// Material and strategy. ColliderSet holds them in one vector per type, so the step loops are
/// plain templated code with no virtual dispatch; further collider types join it as trailing
/// template parameters (convex/convex_collider.hpp: capsules, cylinders, cones, convex hulls).
///
/// Every collider answers two local-frame questions, used by particle_step.hpp:
///  - first hit: the first t in [0, t_max] at which a sphere of radius r >= 0 (a point for r = 0)
///    with centre o + t d touches the surface from the particle's side, with the unit normal
///    towards the particle. A particle touching the surface at t = 0 hits only when it moves into
///    it (d . n < 0), so starting on the surface neither sticks nor tunnels. Legs are never
///    validated (a slow particle's can be shorter than CoordinateRange::min_scale, where squared
///    norms underflow): every collider answers them on the same points with the direction scaled
///    by a power of two (detail::first_hit_any_leg);
///  - penetration (projection): whether a particle ended on the wrong side or within r of the
///    surface, the closest surface point, the normal towards the allowed side, and where to put
///    the centre (surface point + (r + offset) normal).
///
/// Sides. ColliderSide::Outside keeps particles outside a solid (plane: above it); Inside keeps
/// them inside a container (hollow sphere, hollow box, closed mesh); TwoSided (meshes only) keeps
/// each particle on the side it started the step on, which is what open meshes need. Backtracking
/// is side-agnostic (the ray only hits surfaces from the side it comes from); projection uses the
/// side to tell inside from outside: for meshes by the angle-weighted pseudo-normal of the closest
/// feature (Baerentzen and Aanaes 2005), which is exact for closed, consistently oriented meshes.
///
/// Moving colliders: the pose is the pose at the start of the step; during the step it moves
/// rigidly, x -> exp([w] tau) (x - t) + t + v tau. Hit tests map the particle's segment ends into
/// the collider's frame at the segment's start and end times (exact for translation, second order
/// in the step for rotation); the response uses the collider's velocity at the contact point.
/// Call ColliderSet::advance(dt) after each step to move the poses.
///
/// Thread safety: the queries on a ColliderSet and its colliders are const and read only (the
/// meshes, trees, compact and wide trees and grids they point to included), so any number of threads may
/// step particles against one set at once; step_particles does so itself (StepOptions::threads).
/// Editing the set (adding colliders, changing poses, advance()) or a mesh it points to
/// (set_vertices) must not overlap any query. After set_vertices, call MeshCollider::refresh() (the
/// steps throw InvalidInput until then) and rebuild its distance grid and wide tree.
#pragma once

#include "impact/geometry/aabb.hpp"
#include "impact/geometry/mesh_generators.hpp"
#include "impact/geometry/obb.hpp"
#include "impact/geometry/plane.hpp"
#include "impact/geometry/sphere.hpp"
#include "impact/geometry/transform.hpp"
#include "impact/query/closest_point_mesh.hpp"
#include "impact/query/distance_grid.hpp"
#include "impact/query/ray_mesh.hpp"
#include "impact/query/ray_wide_bvh.hpp"
#include "impact/query/swept_sphere_mesh.hpp"
#include "impact/response/contact.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <tuple>
#include <type_traits>
#include <unordered_map>
#include <vector>

namespace impact {

/// How overshooting is handled: backtracking to the time of impact (continuous) or projection
/// to the closest surface point after the step. Inherit takes the system's choice (StepOptions).
enum class Strategy : std::uint8_t { Inherit, Backtrack, Project };

/// Which side of a collider's surface particles are kept on. See the file comment.
enum class ColliderSide : std::uint8_t { Outside, Inside, TwoSided };

/// Rigid motion of a collider during a step: the pose at the step's start and constant linear
/// velocity (of the pose's origin) and angular velocity (world frame, about the pose's origin).
template <class S> struct ColliderMotion {
  RigidTransform<S> pose;                         ///< local -> world at the start of the step
  Vec3<S> linear_velocity = Vec3<S>::Zero();      ///< world units per time unit
  Vec3<S> angular_velocity = Vec3<S>::Zero();     ///< radians per time unit, world frame

  bool moving() const { return linear_velocity.squaredNorm() > S(0) || angular_velocity.squaredNorm() > S(0); }
  /// The pose after time tau.
  RigidTransform<S> at(S tau) const {
    RigidTransform<S> p = pose;
    const S w = angular_velocity.norm();
    if (w > S(0)) p.R = Eigen::AngleAxis<S>(w * tau, angular_velocity / w).toRotationMatrix() * pose.R;
    p.t = pose.t + linear_velocity * tau;
    return p;
  }
  /// Velocity of the collider's material point at world position x at time tau.
  Vec3<S> velocity_at(const Vec3<S>& x, S tau) const { return linear_velocity + angular_velocity.cross(x - (pose.t + linear_velocity * tau)); }
  /// Moves the pose forward by dt.
  void advance(S dt) { pose = at(dt); }
};

/// A hit in a collider's local frame (see the file comment).
template <class S> struct LocalHit {
  S t = S(0);
  Vec3<S> point = Vec3<S>::Zero();   ///< contact point on the surface
  Vec3<S> normal = Vec3<S>::UnitZ(); ///< unit, towards the particle
};

/// A penetration found by projection, in the collider's local frame.
template <class S> struct LocalPenetration {
  Vec3<S> point = Vec3<S>::Zero();   ///< closest surface point
  Vec3<S> normal = Vec3<S>::UnitZ(); ///< unit, towards the allowed side
  Vec3<S> target = Vec3<S>::Zero();  ///< where the particle's centre goes
};

namespace detail {
template <class S> inline S sq(S x) { return x * x; }

/// A collider's first hit for any leg o + s d, s in [0, t_max]: `in_range(o, d, t_max)` answers
/// legs whose direction has a component of at least CoordinateRange::min_scale; a shorter one (a
/// slow particle, whose squared norms and products underflow: the colliders read that as "no
/// motion, no hit", and the particle tunnelled) is answered on the same points with the direction
/// scaled up by a power of two (cast_short_ray: t scaled back exactly).
template <class S, class InRange>
std::optional<LocalHit<S>> first_hit_any_leg(const Vec3<S>& o, const Vec3<S>& d, S t_max, InRange&& in_range) {
  const S dmax = d.cwiseAbs().maxCoeff();
  if (IMPACT_LIKELY(dmax >= CoordinateRange<S>::min_scale)) return in_range(o, d, t_max);
  return cast_short_ray(Ray<S>(o, d, t_max), dmax, [&](const Ray<S>& leg) { return in_range(leg.origin, leg.direction, leg.t_max); });
}
}  // namespace detail

/// Half-space n . x <= d (in the local frame) as a solid: particles stay on the normal's side.
template <class S> struct PlaneCollider {
  Plane<S> plane;
  ColliderMotion<S> motion;
  Material<S> material;
  Strategy strategy = Strategy::Inherit;

  PlaneCollider() = default;
  explicit PlaneCollider(const Plane<S>& p, const Material<S>& m = {}) : plane(p), material(m) {}

  S scale() const { return std::abs(plane.offset); }
  /// Distance from the local point q to the surface when q is strictly on the allowed side, else
  /// 0 (up to rounding; the free ball of response/detail/free_ball.hpp shrinks it).
  S clearance(const Vec3<S>& q) const { return std::max(plane.signed_distance(q), S(0)); }

  std::optional<LocalHit<S>> local_first_hit(const Vec3<S>& o, const Vec3<S>& d, S r, S t_max) const {
    return detail::first_hit_any_leg(o, d, t_max, [&](const Vec3<S>& lo, const Vec3<S>& ld, S lt) { return first_hit_in_range(lo, ld, r, lt); });
  }
  std::optional<LocalPenetration<S>> local_penetration(const Vec3<S>& q, const Vec3<S>&, S r, S offset) const {
    const S s = plane.signed_distance(q);
    if (s >= r) return std::nullopt;
    const Vec3<S> p = q - s * plane.normal;
    return LocalPenetration<S>{p, plane.normal, p + (r + offset) * plane.normal};
  }

 private:
  std::optional<LocalHit<S>> first_hit_in_range(const Vec3<S>& o, const Vec3<S>& d, S r, S t_max) const {
    const S s0 = plane.signed_distance(o) - r;
    const S dn = plane.normal.dot(d);
    if (!(dn < S(0))) return std::nullopt;
    S t = S(0);
    if (s0 > S(0)) {
      t = s0 / (-dn);
      if (t > t_max) return std::nullopt;
    }
    return LocalHit<S>{t, o + t * d - (r + std::min(s0, S(0))) * plane.normal, plane.normal};
  }
};

/// A ball (side Outside) or a hollow sphere holding particles inside (side Inside).
template <class S> struct SphereCollider {
  Sphere<S> sphere;
  ColliderSide side = ColliderSide::Outside;
  ColliderMotion<S> motion;
  Material<S> material;
  Strategy strategy = Strategy::Inherit;

  SphereCollider() = default;
  SphereCollider(const Sphere<S>& s, ColliderSide sd = ColliderSide::Outside, const Material<S>& m = {}) : sphere(s), side(sd), material(m) {}

  S scale() const { return sphere.center.cwiseAbs().maxCoeff() + sphere.radius; }
  /// Distance from the local point q to the surface when q is strictly on the allowed side, else
  /// 0 (up to rounding; the free ball of response/detail/free_ball.hpp shrinks it).
  S clearance(const Vec3<S>& q) const {
    const S c = (q - sphere.center).norm() - sphere.radius;
    return std::max(side == ColliderSide::Inside ? -c : c, S(0));
  }

  std::optional<LocalHit<S>> local_first_hit(const Vec3<S>& o, const Vec3<S>& d, S r, S t_max) const {
    return detail::first_hit_any_leg(o, d, t_max, [&](const Vec3<S>& lo, const Vec3<S>& ld, S lt) { return first_hit_in_range(lo, ld, r, lt); });
  }
  std::optional<LocalPenetration<S>> local_penetration(const Vec3<S>& q, const Vec3<S>&, S r, S offset) const {
    const Vec3<S> m = q - sphere.center;
    const S len = m.norm();
    const Vec3<S> u = len > S(0) ? Vec3<S>(m / len) : Vec3<S>::UnitZ();
    if (side == ColliderSide::Inside) {
      if (len <= sphere.radius - r) return std::nullopt;
      const Vec3<S> p = sphere.center + sphere.radius * u;
      return LocalPenetration<S>{p, -u, p - (r + offset) * u};
    }
    if (len >= sphere.radius + r) return std::nullopt;
    const Vec3<S> p = sphere.center + sphere.radius * u;
    return LocalPenetration<S>{p, u, p + (r + offset) * u};
  }

 private:
  std::optional<LocalHit<S>> first_hit_in_range(const Vec3<S>& o, const Vec3<S>& d, S r, S t_max) const {
    const Vec3<S> m = o - sphere.center;
    const S mm = m.squaredNorm(), md = m.dot(d), dd = d.squaredNorm();
    if (!(dd > S(0))) return std::nullopt;
    if (side == ColliderSide::Inside) {
      const S re = sphere.radius - r;
      if (!(re > S(0))) return std::nullopt;
      const S c = mm - re * re;
      if (c >= S(0)) {  // touching or beyond: hit now if moving outwards
        if (!(md > S(0))) return std::nullopt;
        const Vec3<S> n = -m / std::sqrt(mm);
        return LocalHit<S>{S(0), sphere.center - sphere.radius * n, n};
      }
      const S t = (-md + std::sqrt(std::max(md * md - dd * c, S(0)))) / dd;
      if (t > t_max) return std::nullopt;
      const Vec3<S> n = -(m + t * d) / re;
      return LocalHit<S>{t, sphere.center - sphere.radius * n, n};
    }
    const S re = sphere.radius + r;
    const S c = mm - re * re;
    if (c <= S(0)) {
      if (!(md < S(0))) return std::nullopt;
      const S len = std::sqrt(mm);
      const Vec3<S> n = len > S(0) ? Vec3<S>(m / len) : Vec3<S>(-d.normalized());
      return LocalHit<S>{S(0), sphere.center + sphere.radius * n, n};
    }
    if (!(md < S(0))) return std::nullopt;
    const S disc = md * md - dd * c;
    if (disc < S(0)) return std::nullopt;
    const S t = (-md - std::sqrt(disc)) / dd;
    if (t < S(0) || t > t_max) return std::nullopt;
    const Vec3<S> n = (m + t * d) / re;
    return LocalHit<S>{t, sphere.center + sphere.radius * n, n};
  }
};

/// An oriented box: solid (side Outside) or a hollow container (side Inside). Axis-aligned boxes
/// use the Aabb constructor.
template <class S> struct BoxCollider {
  Obb<S> box;
  ColliderSide side = ColliderSide::Outside;
  ColliderMotion<S> motion;
  Material<S> material;
  Strategy strategy = Strategy::Inherit;

  BoxCollider() = default;
  BoxCollider(const Obb<S>& b, ColliderSide sd = ColliderSide::Outside, const Material<S>& m = {}) : box(b), side(sd), material(m) { init(); }
  BoxCollider(const Aabb<S>& b, ColliderSide sd = ColliderSide::Outside, const Material<S>& m = {}) : side(sd), material(m) {
    box.center = b.center();
    box.axes.setIdentity();
    box.half = b.extent() / S(2);
    init();
  }

  S scale() const { return box.center.cwiseAbs().maxCoeff() + box.half.maxCoeff(); }
  /// Distance from the local point q to the surface when q is strictly on the allowed side, else
  /// 0 (up to rounding; the free ball of response/detail/free_ball.hpp shrinks it).
  S clearance(const Vec3<S>& qw) const {
    const Vec3<S> q = box.axes.transpose() * (qw - box.center);
    if (side == ColliderSide::Inside) return std::max((box.half - q.cwiseAbs()).minCoeff(), S(0));
    return (q - q.cwiseMax(-box.half).cwiseMin(box.half)).norm();
  }

  std::optional<LocalHit<S>> local_first_hit(const Vec3<S>& o, const Vec3<S>& d, S r, S t_max) const {
    return detail::first_hit_any_leg(o, d, t_max, [&](const Vec3<S>& lo, const Vec3<S>& ld, S lt) { return first_hit_in_range(lo, ld, r, lt); });
  }
  std::optional<LocalPenetration<S>> local_penetration(const Vec3<S>& qw, const Vec3<S>&, S r, S offset) const {
    const Vec3<S> q = box.axes.transpose() * (qw - box.center);
    std::optional<LocalPenetration<S>> p;
    if (side == ColliderSide::Inside) {
      // the allowed region is the box shrunk by r; fix the most violated axis (the step repeats
      // projection passes, so corners are fixed one axis at a time)
      int axis = -1;
      S worst = S(0);
      for (int i = 0; i < 3; ++i) {
        const S v = std::abs(q[i]) - (box.half[i] - r);
        if (v > worst || (axis < 0 && v >= S(0))) worst = v, axis = i;
      }
      if (axis < 0) return std::nullopt;
      const S sgn = q[axis] >= S(0) ? S(1) : S(-1);
      LocalPenetration<S> lp;
      lp.normal = Vec3<S>::Zero();
      lp.normal[axis] = -sgn;
      lp.point = q;
      lp.point[axis] = sgn * box.half[axis];
      lp.target = q;
      lp.target[axis] = sgn * (box.half[axis] - r - offset);
      p = lp;
    } else {
      const Vec3<S> c = q.cwiseMax(-box.half).cwiseMin(box.half);
      const Vec3<S> diff = q - c;
      const S dist = diff.norm();
      if (dist > S(0)) {
        if (dist >= r) return std::nullopt;
        const Vec3<S> n = diff / dist;
        p = LocalPenetration<S>{c, n, c + (r + offset) * n};
      } else {
        int axis = 0;
        S least = box.half[0] - std::abs(q[0]);
        for (int i = 1; i < 3; ++i)
          if (box.half[i] - std::abs(q[i]) < least) least = box.half[i] - std::abs(q[i]), axis = i;
        const S sgn = q[axis] >= S(0) ? S(1) : S(-1);
        LocalPenetration<S> lp;
        lp.normal = Vec3<S>::Zero();
        lp.normal[axis] = sgn;
        lp.point = q;
        lp.point[axis] = sgn * box.half[axis];
        lp.target = lp.point + (r + offset) * lp.normal;
        p = lp;
      }
    }
    p->point = box.center + box.axes * p->point;
    p->normal = box.axes * p->normal;
    p->target = box.center + box.axes * p->target;
    return p;
  }

 private:
  std::optional<LocalHit<S>> first_hit_in_range(const Vec3<S>& ow, const Vec3<S>& dw, S r, S t_max) const {
    const Vec3<S> o = box.axes.transpose() * (ow - box.center), d = box.axes.transpose() * dw;
    std::optional<LocalHit<S>> h = side == ColliderSide::Inside ? hit_inside(o, d, r, t_max) : hit_outside(o, d, r, t_max);
    if (h) {
      h->point = box.center + box.axes * h->point;
      h->normal = box.axes * h->normal;
    }
    return h;
  }
  void init() {
    const TriangleMesh<S> m = make_box<S>(box.half.cwiseMax(Vec3<S>::Constant(std::numeric_limits<S>::min())));
    for (int t = 0; t < 12; ++t) tris_[static_cast<std::size_t>(t)] = m.triangle(t);
  }
  // Ray from outside against the box (r = 0: slab test) or the rounded box (r > 0: its 12
  // triangles grown by r). A radius below the sweep's resolution at these coordinates
  // (detail::kSweptRadiusResolution, query/swept_sphere_mesh.hpp) is lost in the sweep's rounding
  // at the edges, corners and the faces' diagonals, where such a sphere went through or hit late
  // (42 and 84 of 530 legs aimed at them, r = 1e-18): the point's exact slab test runs too and the
  // earlier hit is kept (the sphere touches no later than its centre crosses).
  std::optional<LocalHit<S>> hit_outside(const Vec3<S>& o, const Vec3<S>& d, S r, S t_max) const {
    if (r > S(0)) {
      std::optional<LocalHit<S>> best;
      S tb = t_max;
      for (const auto& tri : tris_) {
        const auto h = detail::swept_sphere_triangle(o, d, r, tri, tb);
        if (h && (!best || h->t < tb)) {
          tb = h->t;
          best = LocalHit<S>{h->t, h->point, h->normal};
        }
      }
      const S reach = std::max({o.cwiseAbs().maxCoeff(), Vec3<S>(o + t_max * d).cwiseAbs().maxCoeff(), box.half.maxCoeff()});
      if (!(r >= detail::kSweptRadiusResolution<S> * reach)) {  // also when the leg's end is not finite
        const auto point = hit_outside(o, d, S(0), t_max);
        if (point && (!best || point->t < best->t)) best = point;
      }
      return best;
    }
    // inside or on the boundary: the face of least depth decides
    if ((o.cwiseAbs().array() <= box.half.array()).all()) {
      int axis = 0;
      S least = box.half[0] - std::abs(o[0]);
      for (int i = 1; i < 3; ++i)
        if (box.half[i] - std::abs(o[i]) < least) least = box.half[i] - std::abs(o[i]), axis = i;
      const S sgn = o[axis] >= S(0) ? S(1) : S(-1);
      if (!(d[axis] * sgn < S(0))) return std::nullopt;
      Vec3<S> n = Vec3<S>::Zero();
      n[axis] = sgn;
      Vec3<S> p = o;
      p[axis] = sgn * box.half[axis];
      return LocalHit<S>{S(0), p, n};
    }
    S t0 = S(0), t1 = t_max;
    int axis = -1;
    for (int i = 0; i < 3; ++i) {
      if (d[i] == S(0)) {
        if (std::abs(o[i]) > box.half[i]) return std::nullopt;
        continue;
      }
      S a = (-box.half[i] - o[i]) / d[i], b = (box.half[i] - o[i]) / d[i];
      if (a > b) std::swap(a, b);
      if (a > t0) t0 = a, axis = i;
      if (b < t1) t1 = b;
      if (t0 > t1) return std::nullopt;
    }
    if (axis < 0) return std::nullopt;
    Vec3<S> n = Vec3<S>::Zero();
    n[axis] = d[axis] > S(0) ? S(-1) : S(1);
    Vec3<S> p = o + t0 * d;
    p[axis] = n[axis] * box.half[axis];
    return LocalHit<S>{t0, p, n};
  }
  // Ray from inside the container (shrunk by r) to its walls.
  std::optional<LocalHit<S>> hit_inside(const Vec3<S>& o, const Vec3<S>& d, S r, S t_max) const {
    const Vec3<S> h = box.half.array() - r;
    if (!(h.array() > S(0)).all()) return std::nullopt;
    // on or beyond a wall: hit now if moving further out through it
    int axis = -1;
    S worst = S(0);
    for (int i = 0; i < 3; ++i) {
      const S v = std::abs(o[i]) - h[i];
      if (v >= S(0) && o[i] * d[i] > S(0) && (axis < 0 || v > worst)) worst = v, axis = i;
    }
    if (axis >= 0) {
      Vec3<S> n = Vec3<S>::Zero();
      n[axis] = o[axis] > S(0) ? S(-1) : S(1);
      Vec3<S> p = o;
      p[axis] = -n[axis] * box.half[axis];
      return LocalHit<S>{S(0), p, n};
    }
    S t = t_max;
    axis = -1;
    for (int i = 0; i < 3; ++i) {
      if (d[i] == S(0)) continue;
      const S ti = ((d[i] > S(0) ? h[i] : -h[i]) - o[i]) / d[i];
      if (ti <= t) t = ti, axis = i;
    }
    if (axis < 0) return std::nullopt;
    if (t < S(0)) t = S(0);
    Vec3<S> n = Vec3<S>::Zero();
    n[axis] = d[axis] > S(0) ? S(-1) : S(1);
    Vec3<S> p = o + t * d;
    p[axis] = -n[axis] * box.half[axis];
    return LocalHit<S>{t, p, n};
  }

  std::array<Triangle<S>, 12> tris_{};
};

/// A triangle mesh collider: a MeshBvh (not owned; it must outlive the collider) under the
/// collider's pose. Side Outside for closed solids, Inside for closed containers, TwoSided for
/// open meshes (the default). Construction precomputes the pseudo-normals used by projection.
template <class BV> struct MeshCollider {
  using S = typename BvTraits<BV>::Scalar;
  const MeshBvh<BV>* mesh = nullptr;
  ColliderSide side = ColliderSide::TwoSided;
  ColliderMotion<S> motion;
  Material<S> material;
  Strategy strategy = Strategy::Inherit;
  /// Optional distance bounds to this mesh in its local frame (not owned; must outlive the
  /// collider and match the mesh): backtracking then refreshes free balls in O(1) from it
  /// instead of walking the tree (StepOptions::free_ball_factor), and point particles' ray casts
  /// start from its start nodes, or are skipped when its slabs rule the leg out (same hits,
  /// shorter walks); projection skips the closest-point query of a particle the grid proves out
  /// of its reach (the same answer).
  const DistanceGrid<S>* distance_grid = nullptr;
  /// Optional cache-sized copy of the mesh's tree (not owned; must outlive the collider and be
  /// built from mesh->tree()): point particles' ray casts walk it instead (the same hits; see
  /// bvh/compact_bvh.hpp).
  const CompactBvh* compact_tree = nullptr;
  /// Optional 4-wide copy of the mesh (bvh/wide_bvh.hpp; not owned; must outlive the collider
  /// and be built from the mesh's current vertices): point particles' ray casts walk it instead
  /// of the binary or compact tree, about twice as fast (impact-ray-bench). Every crossing is
  /// decided by the same watertight test on the same coordinates, so the first hit's time is the
  /// same; where two triangles are hit at exactly that time (an edge or a vertex), which one's
  /// normal is reported may differ. The distance grid still rules legs out first.
  const WideBvh<S>* wide_tree = nullptr;

  MeshCollider() = default;
  explicit MeshCollider(const MeshBvh<BV>& m, ColliderSide sd = ColliderSide::TwoSided, const Material<S>& mat = {})
      : mesh(&m), side(sd), material(mat) {
    init();
  }

  S scale() const { return scale_; }
  /// The MeshBvh::revision of the mesh the pseudo-normals and scale were computed for: after
  /// mesh->set_vertices() they describe the old surface, and ColliderSet::validate (every step)
  /// throws InvalidInput until refresh() is called.
  std::uint64_t mesh_revision() const { return mesh_revision_; }
  /// Recomputes the pseudo-normals and scale from the mesh as it is now (after set_vertices; the
  /// distance grid and wide tree, which hold copies, must be rebuilt by the caller). O(triangles).
  void refresh() { init(); }

  /// The first hit of the sphere of radius r (a point for r = 0) moving along o + s d, s in
  /// [0, t_max], in the mesh's frame. A leg is never validated: a direction shorter than
  /// CoordinateRange::min_scale (a slow particle), whose squared norms underflow in the casts, is
  /// cast scaled up by a power of two (detail::cast_short_ray: the same points, the same hit).
  std::optional<LocalHit<S>> local_first_hit(const Vec3<S>& o, const Vec3<S>& d, S r, S t_max) const {
    return detail::first_hit_any_leg(o, d, t_max, [&](const Vec3<S>& lo, const Vec3<S>& ld, S lt) { return local_first_hit_in_range(lo, ld, r, lt); });
  }

  /// local_first_hit for a direction of at least CoordinateRange::min_scale in its largest component.
  std::optional<LocalHit<S>> local_first_hit_in_range(const Vec3<S>& o, const Vec3<S>& d, S r, S t_max) const {
    if (r > S(0)) {
      const auto h = detail::swept_sphere_mesh_first_hit_unchecked(*mesh, Ray<S>(o, d, t_max), r, RigidTransform<S>());
      if (!h) return std::nullopt;
      return LocalHit<S>{h->t, h->point, h->normal};
    }
    std::int32_t start = 0;
    if (distance_grid) {
      start = distance_grid->start_node(o, Vec3<S>(o + t_max * d));
      if (start == DistanceGrid<S>::kNoTriangle) return std::nullopt;
    }
    const auto h = wide_tree ? detail::ray_wide_first_hit_unchecked(*wide_tree, Ray<S>(o, d, t_max), static_cast<const RigidTransform<S>*>(nullptr), nullptr)
                 : compact_tree ? detail::ray_mesh_first_hit_unchecked(*mesh, *compact_tree, Ray<S>(o, d, t_max), RigidTransform<S>(), nullptr, start)
                                : detail::ray_mesh_first_hit_unchecked(*mesh, Ray<S>(o, d, t_max), RigidTransform<S>(), nullptr, start);
    if (!h) return std::nullopt;
    return LocalHit<S>{h->t, h->point, h->front_face ? h->normal : Vec3<S>(-h->normal)};
  }

  /// Angle-weighted pseudo-normal (unit) of the feature a closest-point query returned.
  Vec3<S> pseudo_normal(const ClosestPointMeshResult<S>& c) const {
    const auto row = static_cast<std::size_t>(c.triangle);
    if (is_vertex(c.feature)) return vertex_normals_[static_cast<std::size_t>(mesh->mesh().F(c.triangle, feature_index(c.feature)))];
    if (is_edge(c.feature)) return edge_normals_[3 * row + static_cast<std::size_t>(feature_index(c.feature))];
    return face_normals_[row];
  }
  /// +1 when q is on the outer side (the pseudo-normal's side) of the closest feature, -1 on the
  /// inner side, 0 on the surface; `c` is the closest-point result for q (local frame).
  int side_of(const Vec3<S>& q, const ClosestPointMeshResult<S>& c) const {
    const S s = (q - c.point).dot(pseudo_normal(c));
    return s > S(0) ? 1 : (s < S(0) ? -1 : 0);
  }

  std::optional<LocalPenetration<S>> local_penetration(const Vec3<S>& q, const Vec3<S>& q0, S r, S offset) const {
    const S travel = (q - q0).norm();
    ClosestPointOptions<S> opt;
    opt.max_distance = travel + r + offset;
    // the grid proves most particles farther than that from the surface (the query would find
    // nothing; the factor keeps well clear of its rounding)
    if (distance_grid && !(distance_grid->lower_bound(q) <= opt.max_distance * (S(1) + S(64) * std::numeric_limits<S>::epsilon())))
      return std::nullopt;
    const auto c = detail::closest_point_on_mesh_unchecked(*mesh, q, RigidTransform<S>(), opt);
    if (!c) return std::nullopt;
    int want = side == ColliderSide::Inside ? -1 : 1;
    if (side == ColliderSide::TwoSided) {
      ClosestPointOptions<S> o0;
      o0.max_distance = S(2) * travel + r + offset;
      const auto c0 = detail::closest_point_on_mesh_unchecked(*mesh, q0, RigidTransform<S>(), o0);
      if (c0) {
        const int s0 = side_of(q0, *c0);
        want = s0 == 0 ? 1 : s0;
      }
    }
    const int s = side_of(q, *c);
    if (s == want && c->distance >= r) return std::nullopt;
    Vec3<S> n;
    if (c->feature == TriangleFeature::Face || !(c->distance > S(0))) {
      n = (c->feature == TriangleFeature::Face ? face_normals_[static_cast<std::size_t>(c->triangle)] : pseudo_normal(*c)) * S(want);
    } else {
      n = (q - c->point) / c->distance;
      if (s != want) n = -n;
    }
    return LocalPenetration<S>{c->point, n, c->point + (r + offset) * n};
  }

 private:
  void init() {
    const auto& F = mesh->mesh().F;
    const auto& V = mesh->mesh().V;
    const std::size_t m = static_cast<std::size_t>(F.rows());
    face_normals_.resize(m);
    edge_normals_.assign(3 * m, Vec3<S>::Zero());
    vertex_normals_.assign(static_cast<std::size_t>(V.rows()), Vec3<S>::Zero());
    std::unordered_map<std::uint64_t, Vec3<S>> edges;
    auto key = [](int a, int b) {
      return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(std::min(a, b))) << 32) | static_cast<std::uint32_t>(std::max(a, b));
    };
    Aabb<S> bb;
    for (std::size_t t = 0; t < m; ++t) {
      const Triangle<S> tri = mesh->mesh().triangle(static_cast<int>(t));
      const Vec3<S> n = tri.normal();
      face_normals_[t] = n;
      for (int k = 0; k < 3; ++k) {
        bb.extend(tri[k]);
        const Vec3<S> e1 = tri[(k + 1) % 3] - tri[k], e2 = tri[(k + 2) % 3] - tri[k];
        const S l1 = e1.norm(), l2 = e2.norm();
        if (l1 > S(0) && l2 > S(0)) {
          const S cosang = std::max(S(-1), std::min(S(1), e1.dot(e2) / (l1 * l2)));
          vertex_normals_[static_cast<std::size_t>(F(static_cast<Eigen::Index>(t), k))] += std::acos(cosang) * n;
        }
        // try_emplace with an explicit zero: operator[] would leave a fresh Eigen vector uninitialised
        edges.try_emplace(key(F(static_cast<Eigen::Index>(t), k), F(static_cast<Eigen::Index>(t), (k + 1) % 3)), Vec3<S>::Zero())
            .first->second += n;
      }
    }
    for (std::size_t t = 0; t < m; ++t)
      for (int k = 0; k < 3; ++k) {
        const Vec3<S> e = edges.at(key(F(static_cast<Eigen::Index>(t), k), F(static_cast<Eigen::Index>(t), (k + 1) % 3)));
        const S len = e.norm();
        edge_normals_[3 * t + static_cast<std::size_t>(k)] = len > S(0) ? Vec3<S>(e / len) : face_normals_[t];
      }
    for (auto& n : vertex_normals_) {
      const S len = n.norm();
      if (len > S(0)) n /= len;
    }
    scale_ = bb.center().cwiseAbs().maxCoeff() + bb.half_diagonal();
    mesh_revision_ = mesh->revision();
  }

  std::vector<Vec3<S>> face_normals_, edge_normals_, vertex_normals_;
  S scale_ = S(0);
  std::uint64_t mesh_revision_ = 0;  // mesh_revision()
};

/// All colliders of a scene, one vector per type (planes, spheres, boxes, meshes, then one per
/// trailing type `Extra`). A contact's `collider` index counts through them in that order.
///
/// Extra collider types extend the set without the core knowing them (convex/convex_collider.hpp's
/// ConvexCollider: capsules, cylinders, cones, hulls); the step loops over them at compile time like
/// over the core's. Each is a solid that particles stay outside of, and provides: members
/// `motion`, `material` and `strategy`; `static constexpr const char* kind` (for messages);
/// `S scale() const`; `S clearance(q) const` (a lower bound of the distance from the local point q
/// to the surface, 0 inside); local_first_hit and local_penetration as above; and
/// `void validate(const char* where, const std::string& name) const` (throws InvalidInput for an
/// invalid shape).
template <class S, class BV = Aabb<S>, class... Extra> struct ColliderSet {
  std::vector<PlaneCollider<S>> planes;
  std::vector<SphereCollider<S>> spheres;
  std::vector<BoxCollider<S>> boxes;
  std::vector<MeshCollider<BV>> meshes;
  std::tuple<std::vector<Extra>...> extra;  ///< the trailing types' colliders, after the meshes

  /// The vector of colliders of the trailing type C.
  template <class C> std::vector<C>& extra_of() { return std::get<std::vector<C>>(extra); }
  template <class C> const std::vector<C>& extra_of() const { return std::get<std::vector<C>>(extra); }

  std::size_t size() const {
    std::size_t n = planes.size() + spheres.size() + boxes.size() + meshes.size();
    std::apply([&](const auto&... v) { ((n += v.size()), ...); }, extra);
    return n;
  }
  /// Calls f(collider, index) for every collider.
  template <class F> void for_each(F&& f) const {
    int i = 0;
    for (const auto& c : planes) f(c, i++);
    for (const auto& c : spheres) f(c, i++);
    for (const auto& c : boxes) f(c, i++);
    for (const auto& c : meshes) f(c, i++);
    for_each_extra([&](const auto& c) { f(c, i++); });
  }
  /// Calls f(collider) for every collider of the trailing types.
  template <class F> void for_each_extra(F&& f) const {
    std::apply([&](const auto&... v) { (..., [&](const auto& vec) { for (const auto& c : vec) f(c); }(v)); }, extra);
  }
  /// True when some collider moves.
  bool any_moving() const {
    bool m = false;
    for_each([&](const auto& c, int) { m = m || c.motion.moving(); });
    return m;
  }
  /// Throws InvalidInput unless every collider can be stepped against: a rigid pose
  /// (validate_pose) and finite velocities (the linear one within CoordinateRange), restitution in [0, 1], friction finite and >= 0, a
  /// strategy and side of the enum; planes with an offset within CoordinateRange and a unit normal (within
  /// rotation_tolerance), spheres with a centre and a radius (>= 0) within CoordinateRange, boxes
  /// with a centre (validate_pose), rotation axes and half extents (>= 0) within it; meshes with a mesh not
  /// edited since the collider was made or refreshed (MeshCollider::refresh), and a
  /// compact_tree and a wide_tree built from it when set (same triangle counts). `where` names the caller in the message. O(colliders).
  void validate(const char* where) const {
    // The usual call finds nothing wrong and builds no message: a first pass names nothing, and
    // only when it throws does a second pass, with the same checks, name the offending field
    // (step_particle validates on every call, and its step costs less than the strings did).
    try {
      validate_in(where, false);
    } catch (const InvalidInput&) {
      validate_in(where, true);
      throw;
    }
  }
  /// validate() with (named) or without the names of the fields in the messages.
  void validate_in(const char* where, bool named) const {
    int index = 0;
    auto name = [&](const char* kind, const char* field) {
      return named ? std::string(kind) + " collider " + std::to_string(index) + " " + field : std::string();
    };
    auto common = [&](const auto& c, const char* kind) {
      validate_pose(c.motion.pose, where, name(kind, "motion.pose").c_str());
      validate_coordinates(c.motion.linear_velocity, where, name(kind, "motion.linear_velocity").c_str());
      validate_finite(c.motion.angular_velocity, where, name(kind, "motion.angular_velocity").c_str());
      const S e = c.material.restitution;
      if (!(e >= S(0) && e <= S(1))) require(false, where, name(kind, "material.restitution") + " must be in [0, 1]");
      validate_nonnegative(c.material.friction, where, name(kind, "material.friction").c_str());
      if (!(c.strategy == Strategy::Inherit || c.strategy == Strategy::Backtrack || c.strategy == Strategy::Project))
        require(false, where, name(kind, "strategy") + " is not a Strategy");
    };
    auto side_ok = [](ColliderSide sd) {
      return sd == ColliderSide::Outside || sd == ColliderSide::Inside || sd == ColliderSide::TwoSided;
    };
    for (const auto& c : planes) {
      common(c, "plane");
      validate_length(std::abs(c.plane.offset), where, name("plane", "|plane.offset|").c_str());
      if (!(all_finite(c.plane.normal) && std::abs(c.plane.normal.norm() - S(1)) <= rotation_tolerance<S>()))
        require(false, where, name("plane", "plane.normal") + " must be a unit vector");
      ++index;
    }
    for (const auto& c : spheres) {
      common(c, "sphere");
      validate_coordinates(c.sphere.center, where, name("sphere", "sphere.center").c_str());
      validate_length(c.sphere.radius, where, name("sphere", "sphere.radius").c_str());
      if (!side_ok(c.side)) require(false, where, name("sphere", "side") + " is not a ColliderSide");
      ++index;
    }
    for (const auto& c : boxes) {
      common(c, "box");
      for (int k = 0; k < 3; ++k) validate_length(c.box.half[k], where, name("box", "box.half").c_str());
      validate_pose(RigidTransform<S>(c.box.axes, c.box.center), where, name("box", "box").c_str());
      if (!side_ok(c.side)) require(false, where, name("box", "side") + " is not a ColliderSide");
      ++index;
    }
    for (const auto& c : meshes) {
      common(c, "mesh");
      if (c.mesh == nullptr) require(false, where, name("mesh", "mesh") + " is null");
      if (c.mesh->revision() != c.mesh_revision())
        require(false, where, name("mesh", "mesh") + " was edited (set_vertices) after the collider was made: call refresh()");
      if (!side_ok(c.side)) require(false, where, name("mesh", "side") + " is not a ColliderSide");
      if (c.compact_tree && c.compact_tree->num_primitives() != static_cast<std::size_t>(c.mesh->num_triangles()))
        require(false, where, name("mesh", "compact_tree") + " was not built from its mesh's tree (primitive counts differ)");
      if (c.wide_tree && c.wide_tree->num_triangles() != c.mesh->num_triangles())
        require(false, where, name("mesh", "wide_tree") + " was not built from its mesh (triangle counts differ)");
      ++index;
    }
    for_each_extra([&](const auto& c) {
      using C = std::decay_t<decltype(c)>;
      common(c, C::kind);
      c.validate(where, name(C::kind, "shape"));
      ++index;
    });
  }
  /// Moves every collider's pose forward by dt (call after each step). Throws InvalidInput, with
  /// nothing moved, for dt NaN or infinite.
  void advance(S dt) {
    validate_finite(dt, "ColliderSet::advance", "dt");
    for (auto& c : planes) c.motion.advance(dt);
    for (auto& c : spheres) c.motion.advance(dt);
    for (auto& c : boxes) c.motion.advance(dt);
    for (auto& c : meshes) c.motion.advance(dt);
    std::apply([&](auto&... v) { (..., [&](auto& vec) { for (auto& c : vec) c.motion.advance(dt); }(v)); }, extra);
  }
};

}  // namespace impact
