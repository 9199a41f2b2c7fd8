// SPDX-License-Identifier: MIT
/// \file
/// Advancing particles by one time step against a ColliderSet, with either overshooting strategy;
/// both share respond() (response.hpp).
///
/// Free flight is integrated exactly for a constant acceleration g: x += v dt + g dt^2 / 2,
/// v += g dt. The path of a step is tested as the chord from x to the end point.
///
/// Backtracking (Strategy::Backtrack, continuous):
///  1. cast the chord (a ray for point particles, a swept sphere for particles with a radius)
///     against every backtracking collider and keep the first hit, at fraction s of the chord;
///     the chord runs to the leg's end as it will be stored (x + d rounded: far from the origin
///     that rounding can exceed the leg) and the cast reaches the surface offset beyond it, so an
///     end is never behind a surface nor on one (a hit beyond the end backs off like the others);
///  2. move the particle to the hit, backed off along the chord so that it ends `offset` away
///     from the surface along the normal (or at the chord's start if that is nearer): the
///     particle only ever stands on the collision-free part of a chord, so it never enters a
///     surface, also at concave corners and seams;
///  3. respond with the velocity at the time of impact (the chord's hit time refined on the
///     free-flight parabola against the tangent plane at the hit, so bounces on planes are exact
///     up to rounding) and the collider's velocity there;
///  4. repeat for the rest of the step with the new velocity, at most `max_iterations` times.
///  Budget policy: when the budget runs out with time left, the particle stops at the last safe
///  point (the backed-off position of its last impact), keeps its post-response velocity, and the
///  rest of the step is dropped (StepStats::budget_exhausted counts it). It is never left inside.
///  Resting contact: an impact slower than the rest speed (response.hpp) with gravity pushing into
///  the surface makes the contact active for the rest of the step: the normal parts of the
///  velocity and of g are removed, Coulomb friction acts with the normal force |g . n| (static
///  when |g_t| <= mu |g . n| and the particle is still), so a settled particle has velocity zero.
///
/// Projection (Strategy::Project, quick and dirty): after the unconstrained step, each projection
/// collider reports whether the particle ended on the wrong side or within its radius; the
/// particle moves to the closest surface point + (radius + offset) along the normal, and its
/// velocity gets the same response. Repeated for up to `max_iterations` passes over the colliders.
/// Projection cannot see thin geometry crossed within one step: that is what backtracking is for.
///
/// Speed: legs that stay inside a particle's free ball (Particle::free_radius, a conservative
/// clearance from the colliders) skip the collision tests (StepOptions::free_ball_factor), and
/// step_particles() moves such a particle without setting up the full step; a DistanceGrid on a
/// mesh collider (query/distance_grid.hpp) makes the clearance O(1), rules out the legs that pass
/// beside the surface and starts the remaining ray casts deep in the tree; spatial_order() gives
/// a cache-friendly order for large particle sets.
///
/// The offset is scale-aware: offset_ulps * epsilon(S) * (|x|_inf + collider scale + |chord|_inf)
/// unless StepOptions::surface_offset gives it absolutely: 256 ulps is about 3e-5 of the scene's
/// size in float and 6e-14 in double, well above the rounding of a hit point and well below any
/// physical length.
#pragma once

#include "impact/bvh/traverse.hpp"
#include "impact/core/parallel.hpp"
#include "impact/detail/morton.hpp"
#include "impact/response/collider.hpp"
#include "impact/response/particle.hpp"
#include "impact/response/response.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <utility>
#include <type_traits>
#include <vector>

namespace impact {

/// Options of a particle step. The strategy is the system's default; a collider whose own
/// strategy is not Inherit overrides it.
template <class S> struct StepOptions {
  Strategy strategy = Strategy::Backtrack;
  Vec3<S> gravity = Vec3<S>::Zero();  ///< constant acceleration
  /// Backtracking: impacts handled per particle per step; projection: passes over the colliders.
  int max_iterations = 16;
  /// Resting threshold: rest speed = rest_speed + rest_speed_factor * |gravity| * dt.
  S rest_speed = S(0);
  S rest_speed_factor = S(2);
  /// Scale-aware surface offset in units of epsilon(S) (see the file comment).
  S offset_ulps = S(256);
  /// Absolute surface offset; used instead of offset_ulps when > 0.
  S surface_offset = S(0);
  /// Free-ball cache (Particle::free_radius) under backtracking, used when no collider moves and
  /// there is a mesh: when a leg leaves the particle's free ball, a new ball is found from lower
  /// bounds of the distance to every collider (free_ball_at): exact for planes, spheres and boxes,
  /// in O(1) from a mesh's distance grid when it has one (MeshCollider::distance_grid), else from
  /// the mesh's tree, at most free_ball_factor times the leg's length. With grids on every mesh the
  /// ball is first sought near the leg's end (around the centre of the grid cell holding it, the
  /// largest ball that cell's bound gives; it then also holds the legs that follow), else around
  /// its start; a leg is also clear of the meshes, or of the other colliders, when their
  /// balls around both of its ends (and, for grids, its midpoint) cover it. Legs inside the ball
  /// skip every collision test. Conservative (a test is skipped only when no surface is within
  /// the leg's reach); 0 disables it.
  S free_ball_factor = S(8);
  /// Threads of step_particles: <= 0 the hardware concurrency, 1 the serial loop. Particles are
  /// independent within a step, so the particles and the counters do not depend on it (bit for
  /// bit); sets of fewer than 512 particles are stepped serially.
  int threads = 0;
};

/// Counters of one or more particle steps.
struct StepStats {
  std::size_t impacts = 0;            ///< backtracking impacts handled
  std::size_t projections = 0;        ///< projections applied
  std::size_t particles_hit = 0;      ///< particle-steps with at least one impact or projection
  std::size_t budget_exhausted = 0;   ///< particle-steps that ran out of iterations
  void operator+=(const StepStats& o) {
    impacts += o.impacts;
    projections += o.projections;
    particles_hit += o.particles_hit;
    budget_exhausted += o.budget_exhausted;
  }
};

namespace detail {

/// The default leg observer: does nothing.
struct NoLegObserver {
  template <class V> void operator()(const V&, const V&) const {}
};

template <class S> inline S surface_offset(const StepOptions<S>& o, const Vec3<S>& x, S scale, const Vec3<S>& d) {
  if (o.surface_offset > S(0)) return o.surface_offset;
  return o.offset_ulps * std::numeric_limits<S>::epsilon() * (x.cwiseAbs().maxCoeff() + scale + d.cwiseAbs().maxCoeff()) +
         std::numeric_limits<S>::min();
}

/// How far beyond a leg's end the cast reaches (see step_particle_in): `reach`, the surface offset
/// (surface_offset's formula) and at least 8 ulps of m = |end|_inf + the colliders' largest scale
/// + |chord|_inf; and the cast's t_max, 1 + reach / |chord|_inf (at least `reach` beyond the end;
/// 1 for a zero chord).
template <class S> struct EndReach {
  S reach = S(0);
  S t_max = S(1);
};
template <class S> inline EndReach<S> end_reach(const StepOptions<S>& o, const Vec3<S>& end, const Vec3<S>& chord, S scale) {
  const S eps = std::numeric_limits<S>::epsilon();
  const S c_max = chord.cwiseAbs().maxCoeff();
  const S m = end.cwiseAbs().maxCoeff() + scale + c_max;
  EndReach<S> r;
  r.reach = o.surface_offset > S(0) ? std::max(o.surface_offset, S(8) * eps * m)
                                    : std::max(o.offset_ulps, S(8)) * eps * m + std::numeric_limits<S>::min();
  if (c_max > S(0)) r.t_max = S(1) + r.reach / c_max;
  return r;
}

/// Whether the backed-off point x + s c of a hit leg (0 < s < 1), once rounded, provably stays on
/// the particle's side of the hit's tangent plane when it was `delta` from it: each rounded
/// component is off by at most u (|s c_k| + |x_k + s c_k|) <= u (|x|_inf + 3 |c|_inf) (u = eps / 2,
/// two roundings), so the point moves by at most eps (|x|_inf + 3 |c|_inf) (sqrt(3) u < eps); at
/// least twice that leaves it delta / 2 or more from the plane. The scale-aware offset (256 eps
/// (|hit|_inf + scale + |c|_inf), with |x|_inf <= |hit|_inf + |c|_inf) always passes; only an
/// absolute StepOptions::surface_offset below the coordinates' rounding can fail it.
template <class S> inline bool backoff_rounding_clear(S delta, const Vec3<S>& x, const Vec3<S>& c) {
  return delta >= S(2) * std::numeric_limits<S>::epsilon() * (x.cwiseAbs().maxCoeff() + S(3) * c.cwiseAbs().maxCoeff());
}

inline Strategy effective(Strategy own, Strategy system) { return own == Strategy::Inherit ? system : own; }

/// First hit of the particle's chord x -> x + d, travelled during [tau0, tau0 + len] of the step,
/// against one collider; updates `best` (a contact whose time is the chord fraction) and `scale`.
template <class C, class S>
inline void first_hit_one(const C& c, int index, const Vec3<S>& x, const Vec3<S>& d, S r, S tau0, S len, S& best_t,
                          std::optional<Contact<S>>& best, S& scale) {
  std::optional<LocalHit<S>> h;
  if (!c.motion.moving()) {
    const RigidTransform<S>& P = c.motion.pose;
    h = c.local_first_hit(P.R.transpose() * (x - P.t), P.R.transpose() * d, r, best_t);
    if (!h || (best && h->t >= best_t)) return;
    Contact<S> k;
    k.time = h->t;
    k.point = P.apply(h->point);
    k.normal = P.R * h->normal;
    k.collider_velocity.setZero();
    k.material = c.material;
    k.collider = index;
    best = k;
  } else {
    const RigidTransform<S> P0 = c.motion.at(tau0), P1 = c.motion.at(tau0 + len);
    const Vec3<S> o = P0.R.transpose() * (x - P0.t);
    const Vec3<S> e = P1.R.transpose() * (x + d - P1.t);
    h = c.local_first_hit(o, e - o, r, best_t);
    if (!h || (best && h->t >= best_t)) return;
    const S tau = tau0 + h->t * len;
    const RigidTransform<S> Ph = c.motion.at(tau);
    Contact<S> k;
    k.time = h->t;
    k.point = Ph.apply(h->point);
    k.normal = Ph.R * h->normal;
    k.collider_velocity = c.motion.velocity_at(k.point, tau);
    k.material = c.material;
    k.collider = index;
    best = k;
  }
  best_t = h->t;
  scale = c.scale();
}

template <class C> struct IsMeshCollider : std::false_type {};
template <class BV> struct IsMeshCollider<MeshCollider<BV>> : std::true_type {};

/// The point x in the frame of pose P, for distance bounds (free balls): x itself when every
/// static backtracking collider's pose is the identity (StepContext::identity_poses), where the
/// product would only turn some zeros' signs.
template <class S> inline Vec3<S> bound_frame(const RigidTransform<S>& P, const Vec3<S>& x, bool identity) {
  if (identity) return x;
  return P.R.transpose() * (x - P.t);
}

/// A free ball around a centre: the radii within which the centre of a particle of the given
/// radius stays clear of the meshes and of the other backtracking colliders.
template <class S> struct FreeBallRefresh {
  bool cheap = true;                 ///< every mesh had a grid (the radii came in O(1))
  Vec3<S> center = Vec3<S>::Zero();  ///< the balls' centre
  S mesh_radius = S(0);              ///< clear of every backtracking mesh
  S other_radius = S(0);             ///< clear of every backtracking plane, sphere and box
};

/// min(R, a lower bound of the distance from the local point q to the mesh of c), from its tree:
/// the walk descends only into nodes whose box contains q; any other node bounds its triangles by
/// its box's distance, and the leaves that contain q give exact triangle distances. Out of line
/// (free_ball_at, small without it, is inlined into the grids' refreshes).
template <class BV, class S>
IMPACT_NOINLINE S tree_distance_bound(const MeshCollider<BV>& c, const Vec3<S>& q, S R) {
  traverse(
      c.mesh->tree(),
      [&](const BV& bv) {
        const S d2 = squared_distance_to_bv(q, bv);
        if (d2 >= R * R) return false;
        if (d2 > S(0)) {
          R = std::sqrt(d2);
          return false;
        }
        return true;
      },
      [&](std::int32_t k) {
        R = std::min(R, (q - closest_on_triangle(q, c.mesh->triangle(k)).point).norm());
        return true;
      });
  return R;
}

/// The free ball around x, for a leg of length len of a particle of the given radius, clear of
/// every backtracking collider (all static here). Planes, spheres and boxes give their exact
/// clearance (shrunk for rounding). A mesh with a distance grid (MeshCollider::distance_grid)
/// bounds it in O(1) from the grid, with no cap. Otherwise the radius is capped at
/// free_ball_factor * len and is a cheap lower bound of the distance: the walk descends only
/// into nodes whose box contains x; any other node bounds its triangles by its box's distance,
/// and the leaves that contain x give exact triangle distances. Conservative, O(depth) per mesh.
/// A mesh collider `known` of the set, when given, is bounded by known_bound instead (a lower
/// bound of the distance from x to it that the caller has already).
template <class S, class BV, class... X>
inline FreeBallRefresh<S> free_ball_at(const Vec3<S>& x, S len, S radius, const ColliderSet<S, BV, X...>& colliders,
                                       const StepOptions<S>& opt, const MeshCollider<BV>* known = nullptr,
                                       S known_bound = std::numeric_limits<S>::infinity(), bool identity = false) {
  FreeBallRefresh<S> out;
  out.center = x;
  const S eps = std::numeric_limits<S>::epsilon();
  S R = known_bound;  // bound on the distance of the centre to any mesh (`known`'s given)
  for (const auto& c : colliders.meshes) {
    if (effective(c.strategy, opt.strategy) != Strategy::Backtrack || &c == known) continue;
    const Vec3<S> q = bound_frame(c.motion.pose, x, identity);
    if (c.distance_grid) {
      R = std::min(R, c.distance_grid->lower_bound(q));
      continue;
    }
    out.cheap = false;
    R = tree_distance_bound(c, q, std::min(R, opt.free_ball_factor * len + radius));
  }
  // keep clear of rounding: shrink by a relative and a scale-aware absolute margin
  const S x_margin = S(64) * eps * x.cwiseAbs().maxCoeff();
  auto shrink = [&](S r) {
    r = (r - radius) * (S(1) - S(64) * eps) - x_margin;
    return r > S(0) ? r : S(0);
  };
  out.mesh_radius = shrink(R);
  S Ro = std::numeric_limits<S>::infinity();  // the same for planes, spheres and boxes
  auto simple = [&](const auto& c) {
    if (effective(c.strategy, opt.strategy) != Strategy::Backtrack) return;
    const Vec3<S> q = bound_frame(c.motion.pose, x, identity);
    Ro = std::min(Ro, c.clearance(q) * (S(1) - S(64) * eps) - S(64) * eps * (q.cwiseAbs().maxCoeff() + c.scale()));
  };
  for (const auto& c : colliders.planes) simple(c);
  for (const auto& c : colliders.spheres) simple(c);
  for (const auto& c : colliders.boxes) simple(c);
  colliders.for_each_extra(simple);
  out.other_radius = shrink(Ro);
  return out;
}

/// The clear radius of a refresh: the smaller of the meshes' and the other colliders'.
template <class S>
inline S clear_radius(const FreeBallRefresh<S>& f) {
  return std::min(f.mesh_radius, f.other_radius);
}

/// A free ball holding x, from the distance grids (every backtracking mesh has one): the ball
/// around the centre of the grid cell holding x (of the first such mesh, mapped to the world),
/// when it holds x, else the ball around x. A grid's bound at a point is its cell's value less
/// the distance to the cell's centre, so the ball around the centre holds the ball around any
/// point of the cell that its bound would give (for the meshes; the planes, spheres and boxes are
/// measured at the centre too): a larger ball, which more of the legs that follow stay in.
template <class S, class BV, class... X>
inline FreeBallRefresh<S> free_ball_near(const Vec3<S>& x, S len, S radius, const ColliderSet<S, BV, X...>& colliders,
                                         const StepOptions<S>& opt, bool identity = false) {
  for (const auto& c : colliders.meshes) {
    if (effective(c.strategy, opt.strategy) != Strategy::Backtrack || !c.distance_grid) continue;
    const RigidTransform<S>& P = c.motion.pose;
    S bound = S(0);
    const Vec3<S> centre = c.distance_grid->cell_bound(bound_frame(P, x, identity), bound);
    const Vec3<S> m = identity ? centre : P.apply(centre);
    if (m == x) break;
    // the bound at m: the one at the cell's centre when m maps back onto it (exactly, as under
    // the identity), else the grid's bound at the point m maps to
    const Vec3<S> qm = bound_frame(P, m, identity);
    const FreeBallRefresh<S> f =
        free_ball_at(m, len, radius, colliders, opt, &c, qm == centre ? bound : c.distance_grid->lower_bound(qm), identity);
    const S r = clear_radius(f);
    if ((x - m).squaredNorm() <= r * r) return f;
    break;
  }
  return free_ball_at(x, len, radius, colliders, opt, static_cast<const MeshCollider<BV>*>(nullptr), std::numeric_limits<S>::infinity(), identity);
}

/// The radius of a ball around y that the ball (center, r) holds (0 when it does not hold y):
/// r less the distance, less its rounding.
template <class S> inline S radius_within(const Vec3<S>& y, const Vec3<S>& center, S r) {
  const S eps = std::numeric_limits<S>::epsilon();
  const S q = r - (y - center).norm() * (S(1) + S(8) * eps) - S(8) * eps * (y.cwiseAbs().maxCoeff() + center.cwiseAbs().maxCoeff());
  return q > S(0) ? q : S(0);
}

/// True when every static backtracking mesh (each with a distance grid) provably keeps the
/// segment x -> e clear, given clear radii rx and re for the meshes at both ends (balls of
/// centres clear of every mesh): the two balls cover the segment (their radii add up to its
/// length), or the ball around the midpoint bridges the gap between them.
template <class S, class BV, class... X>
inline bool grids_clear_segment(S rx, S re, const Vec3<S>& x, const Vec3<S>& e, S len, S radius,
                                const ColliderSet<S, BV, X...>& colliders, const StepOptions<S>& opt, bool identity = false) {
  const S margin = S(64) * std::numeric_limits<S>::epsilon() * (len + x.cwiseAbs().maxCoeff() + e.cwiseAbs().maxCoeff());
  if (rx + re >= len + margin) return true;
  if (!(rx > S(0) && re > S(0))) return false;
  const Vec3<S> m = (x + e) / S(2);
  for (const auto& c : colliders.meshes) {
    if (effective(c.strategy, opt.strategy) != Strategy::Backtrack) continue;
    if (!c.distance_grid) return false;
    const S rm = c.distance_grid->lower_bound(bound_frame(c.motion.pose, m, identity)) - radius;
    if (!(rx + rm >= len / S(2) + margin && rm + re >= len / S(2) + margin)) return false;
  }
  return true;
}

/// Time of impact within a leg of length `left` starting at x with velocity v and acceleration
/// a, of a particle of radius r: the chord's hit fraction s refined on the parabola against the
/// tangent plane at the hit, which moves with the collider's velocity there and passes through
/// the contact point c.point at the chord's hit time s * left: the centre reaches distance r from
/// it when n . (x + v tau + a tau^2 / 2 - c.point - v_c (tau - s left)) = r (exact for planes;
/// second order otherwise), so that the velocity at impact follows free flight exactly. Falls back
/// to s * left when the refined root is not in [0, left].
/// (Before, the radius and the plane's motion before the hit were left out: a ball's impact came
/// r / v_n late, and the time in between was dropped from the step, so a collider moving towards
/// the ball ran into it by about its speed times r / v_n: 4.4e-3 in a rain of balls of radius 0.05
/// on a rising cone, tests/convex/test_convex_scene.cpp.)
template <class S>
inline S impact_time(const Vec3<S>& x, const Vec3<S>& v, const Vec3<S>& a, const Contact<S>& c, S s, S left, S r) {
  const S chord = s * left;
  const S c2 = a.dot(c.normal) / S(2);
  if (c2 == S(0)) return chord;
  const S vcn = c.collider_velocity.dot(c.normal);
  const S c0 = (x - c.point).dot(c.normal) + vcn * chord - r, c1 = v.dot(c.normal) - vcn;
  const S disc = c1 * c1 - S(4) * c2 * c0;
  if (!(disc >= S(0)) || !(c0 >= S(0))) return chord;
  const S sq = std::sqrt(disc);
  // the smaller non-negative root, computed without cancellation
  const S q = c1 >= S(0) ? -(c1 + sq) / S(2) : -(c1 - sq) / S(2);
  S r1 = q != S(0) ? c0 / q : std::numeric_limits<S>::infinity();
  S r2 = q / c2;
  if (r1 > r2) std::swap(r1, r2);
  const S tau = r1 >= S(0) ? r1 : r2;
  if (!(tau >= S(0) && tau <= left)) return chord;
  return tau;
}

}  // namespace detail

namespace detail {

/// A 64-bit digest of a sequence of values (their bit patterns), for StepContext::ball_key.
struct BallKeyHasher {
  std::uint64_t h = 0x6a09e667f3bcc909ull;
  void word(std::uint64_t w) {
    h ^= w + 0x9e3779b97f4a7c15ull + (h << 6) + (h >> 2);
    h *= 0xff51afd7ed558ccdull;
    h ^= h >> 32;
  }
  template <class S> void scalar(S x) {
    static_assert(sizeof(S) <= sizeof(std::uint64_t), "BallKeyHasher: scalar wider than 64 bits");
    std::uint64_t w = 0;
    std::memcpy(&w, &x, sizeof(S));
    word(w);
  }
  template <class M> void matrix(const M& m) {
    for (Eigen::Index i = 0; i < m.size(); ++i) scalar(m.data()[i]);
  }
  void pointer(const void* p) { word(static_cast<std::uint64_t>(reinterpret_cast<std::uintptr_t>(p))); }
};

/// The key of a particle's free ball (Particle::free_key) for a step whose collider digest is
/// `set_key`: the digest mixed with the particle's radius; never 0 (a particle's initial key).
template <class S> inline std::uint64_t particle_ball_key(std::uint64_t set_key, S radius) {
  std::uint64_t w = 0;
  std::memcpy(&w, &radius, sizeof(S));
  return (set_key ^ (w * 0x9e3779b97f4a7c15ull)) | 1u;
}

/// What a step computes once for every particle.
template <class S> struct StepContext {
  S rest = S(0);               ///< resting threshold
  bool moving = false;         ///< some collider moves (a particle at rest can still be hit)
  bool use_free_ball = false;  ///< the free-ball cache is in use
  bool any_projection = false;  ///< some collider uses projection
  bool all_grids = false;       ///< every backtracking mesh has a distance grid (free balls are O(1))
  bool identity_poses = false;  ///< every backtracking collider's pose is exactly the identity
  S scale = S(0);               ///< the largest scale() of the backtracking colliders (legs' end clearance)
  /// Digest of what the free balls depend on (Particle::free_key): every collider's effective
  /// strategy and pose, the shapes of planes, spheres and boxes, the sides, each mesh's address,
  /// triangle count, revision (MeshBvh::revision: set_vertices() changes it) and distance grid,
  /// each trailing-type collider's scale and clearance at seven points of its frame.
  std::uint64_t ball_key = 0;
  template <class BV, class... X> StepContext(const ColliderSet<S, BV, X...>& colliders, S dt, const StepOptions<S>& opt) {
    rest = opt.rest_speed + opt.rest_speed_factor * opt.gravity.norm() * dt;
    moving = colliders.any_moving();
    use_free_ball = opt.free_ball_factor > S(0) && !moving && !colliders.meshes.empty();
    colliders.for_each(
        [&](const auto& c, int) { any_projection = any_projection || effective(c.strategy, opt.strategy) == Strategy::Project; });
    all_grids = true;
    for (const auto& c : colliders.meshes)
      if (effective(c.strategy, opt.strategy) == Strategy::Backtrack && !c.distance_grid) all_grids = false;
    identity_poses = true;
    colliders.for_each([&](const auto& c, int) {
      if (effective(c.strategy, opt.strategy) == Strategy::Backtrack) scale = std::max(scale, c.scale());
      if (effective(c.strategy, opt.strategy) == Strategy::Backtrack && !(c.motion.pose.R == Mat3<S>::Identity() && c.motion.pose.t == Vec3<S>::Zero()))
        identity_poses = false;
    });
    if (use_free_ball) ball_key = set_key(colliders, opt);
  }

  template <class BV, class... X> static std::uint64_t set_key(const ColliderSet<S, BV, X...>& colliders, const StepOptions<S>& opt) {
    BallKeyHasher k;
    k.word(colliders.planes.size());
    k.word(colliders.spheres.size());
    k.word(colliders.boxes.size());
    k.word(colliders.meshes.size());
    k.word(colliders.size());
    colliders.for_each([&](const auto& c, int) {
      k.word(static_cast<std::uint64_t>(effective(c.strategy, opt.strategy)));
      k.matrix(c.motion.pose.R);
      k.matrix(c.motion.pose.t);
    });
    for (const auto& c : colliders.planes) {
      k.matrix(c.plane.normal);
      k.scalar(c.plane.offset);
    }
    for (const auto& c : colliders.spheres) {
      k.matrix(c.sphere.center);
      k.scalar(c.sphere.radius);
      k.word(static_cast<std::uint64_t>(c.side));
    }
    for (const auto& c : colliders.boxes) {
      k.matrix(c.box.center);
      k.matrix(c.box.axes);
      k.matrix(c.box.half);
      k.word(static_cast<std::uint64_t>(c.side));
    }
    for (const auto& c : colliders.meshes) {
      k.pointer(c.mesh);
      k.word(c.mesh ? static_cast<std::uint64_t>(c.mesh->num_triangles()) : 0u);
      k.word(c.mesh ? c.mesh->revision() : 0u);  // set_vertices() in place, at the same address
      k.pointer(c.distance_grid);
      k.word(static_cast<std::uint64_t>(c.side));
    }
    colliders.for_each_extra([&](const auto& c) {
      const S r = c.scale();
      k.scalar(r);
      k.scalar(c.clearance(Vec3<S>::Zero()));
      for (int a = 0; a < 3; ++a)
        for (const S sgn : {S(-1), S(1)}) k.scalar(c.clearance(Vec3<S>(Vec3<S>::Unit(a) * (sgn * r))));
    });
    return k.h;
  }
};

/// What free_flight needs of a step, computed once per call (the per-particle loop then reads
/// no options): whether free flights are possible at all, the step's displacement and velocity
/// change under gravity (the same products step_particle_in computes), the collider digest.
template <class S> struct FreeFlightStep {
  bool possible = false;
  S dt = S(0);
  Vec3<S> half_g_dt2 = Vec3<S>::Zero();  ///< (dt^2 / 2) g
  Vec3<S> g_dt = Vec3<S>::Zero();        ///< g dt
  std::uint64_t set_key = 0;
  FreeFlightStep(S dt_, const StepOptions<S>& opt, const StepContext<S>& ctx)
      : possible(ctx.use_free_ball && !ctx.any_projection && opt.max_iterations > 0 && dt_ > S(0)),
        dt(dt_),
        half_g_dt2((dt_ * dt_ / S(2)) * opt.gravity),
        g_dt(opt.gravity * dt_),
        set_key(ctx.ball_key) {}
};

/// The step of a particle whose whole flight stays inside its free ball: exactly what
/// step_particle_in does on that path (one all-clear leg), without its set-up. Returns false, with
/// the particle untouched, when the full step is needed.
template <class S>
inline bool free_flight(Particle<S>& p, const FreeFlightStep<S>& f) {
  if (!f.possible || !(p.free_radius > S(0)) || p.free_key != particle_ball_key(f.set_key, p.radius)) return false;
  const Vec3<S> d = p.velocity * f.dt + f.half_g_dt2;
  if (d.squaredNorm() == S(0)) return false;
  const S R2 = p.free_radius * p.free_radius;
  const Vec3<S> e = p.position + d;
  if (!((p.position - p.free_center).squaredNorm() <= R2 && (e - p.free_center).squaredNorm() <= R2)) return false;
  p.position = e;
  p.velocity += f.g_dt;
  return true;
}

/// Which colliders a leg provably stays clear of (their tests are skipped).
struct LegClearance {
  bool all = false;     ///< every collider
  bool meshes = false;  ///< every mesh
  bool others = false;  ///< every plane, sphere and box
};

/// The free-ball test of the leg x -> x + d of particle p (the free-ball cache is in use: every
/// collider is static): inside the particle's ball, every collider is clear; else the ball is
/// refreshed (StepOptions::free_ball_factor) and the meshes, or the rest, may still be clear.
template <class S, class BV, class... X>
LegClearance leg_clearance(Particle<S>& p, const Vec3<S>& x, const Vec3<S>& d, const ColliderSet<S, BV, X...>& colliders,
                           const StepOptions<S>& opt, const StepContext<S>& ctx) {
  LegClearance c;
  const Vec3<S> e = x + d;
  auto in_ball = [&](const Vec3<S>& y) { return (y - p.free_center).squaredNorm() <= p.free_radius * p.free_radius; };
  if (p.free_radius > S(0) && in_ball(x) && in_ball(e)) {
    c.all = true;
  } else if (p.free_radius < S(0) && in_ball(x)) {
    // cooling down: the last tree refresh here found a surface too near to help, do not retry yet
  } else {
    const S len = d.norm();
    // The particle's own ball around x (trees: centred there, found where the last leg ended;
    // grids: holding x, usually found where the last leg ended): both of its radii around x are
    // then at least free_radius less the distance to its centre.
    const bool own_at_x = p.free_radius >= S(0) && (p.free_center == x || (ctx.all_grids && in_ball(x)));
    S rx_mesh = own_at_x ? (p.free_center == x ? p.free_radius : radius_within(x, p.free_center, p.free_radius)) : S(0);
    S rx_other = rx_mesh;
    // First a ball near the leg's end (it holds the next legs too) when the grids make it O(1);
    // else, or when it does not hold the leg, a ball around x.
    FreeBallRefresh<S> fe;
    fe.cheap = false;
    if (ctx.all_grids) {
      fe = detail::free_ball_near(e, len, p.radius, colliders, opt, ctx.identity_poses);
      p.free_center = fe.center;  // near where the next leg starts, unless this one is hit
      p.free_radius = detail::clear_radius(fe);
      c.all = in_ball(x) && in_ball(e);
    }
    if (!c.all && !own_at_x) {
      const auto fx = detail::free_ball_at(x, len, p.radius, colliders, opt, static_cast<const MeshCollider<BV>*>(nullptr), std::numeric_limits<S>::infinity(), ctx.identity_poses);
      rx_mesh = fx.mesh_radius;
      rx_other = fx.other_radius;
      const S rx = detail::clear_radius(fx);
      c.all = (e - x).squaredNorm() <= rx * rx;
      if (!fe.cheap) {
        p.free_center = x;
        p.free_radius = rx;
        // trees: a surface is near, retry two legs away
        if (!fx.cheap && !c.all) p.free_radius = -S(2) * len;
      }
    }
    if (!c.all) {
      // the meshes, or the rest, alone may still be clear: the ball at x, or (grids) the balls
      // at both ends and the midpoint
      const S e2 = (e - x).squaredNorm();
      const S re_mesh = fe.cheap ? radius_within(e, fe.center, fe.mesh_radius) : S(0);
      const S re_other = fe.cheap ? radius_within(e, fe.center, fe.other_radius) : S(0);
      c.meshes = e2 <= rx_mesh * rx_mesh || (fe.cheap && detail::grids_clear_segment(rx_mesh, re_mesh, x, e, len, p.radius, colliders, opt, ctx.identity_poses));
      c.others = e2 <= rx_other * rx_other || (fe.cheap && rx_other + re_other >= len);
    }
  }
  return c;
}

/// The first hit of the chord x -> x + d (travelled during [tau0, tau0 + len] of the step) of a
/// particle of the given radius against every backtracking collider not known to be clear, as a
/// contact whose time is the chord fraction; `scale` gets the hit collider's scale.
template <class S, class BV, class... X>
std::optional<Contact<S>> first_hit(const ColliderSet<S, BV, X...>& colliders, const Vec3<S>& x, const Vec3<S>& d, S radius, S tau0,
                                    S len, const LegClearance& clear, const StepOptions<S>& opt, S& scale, S t_max = S(1)) {
  std::optional<Contact<S>> hit;
  S best_t = t_max;
  colliders.for_each([&](const auto& c, int index) {
    if constexpr (IsMeshCollider<std::decay_t<decltype(c)>>::value) {
      if (clear.meshes) return;
    } else {
      if (clear.others) return;
    }
    if (effective(c.strategy, opt.strategy) == Strategy::Backtrack)
      first_hit_one(c, index, x, d, radius, tau0, len, best_t, hit, scale);
  });
  return hit;
}

/// Projection at the end of a step (Strategy::Project colliders): a particle of the given radius
/// that moved from x_start to x and ended inside a collider, or within its radius, goes to the
/// closest surface point plus (radius + offset) along the normal, with the response on v; up to
/// max_iterations passes over the colliders. Returns whether it was moved.
template <class S, class BV, class... X>
bool project(S radius, const Vec3<S>& x_start, Vec3<S>& x, Vec3<S>& v, const ColliderSet<S, BV, X...>& colliders, S dt,
             const StepOptions<S>& opt, const ResponseOptions<S>& ropt, StepStats& st) {
  bool projected = false;
  for (int pass = 0; pass < opt.max_iterations; ++pass) {
    bool moved = false;
    colliders.for_each([&](const auto& c, int) {
      if (effective(c.strategy, opt.strategy) != Strategy::Project) return;
      const RigidTransform<S> P1 = c.motion.moving() ? c.motion.at(dt) : c.motion.pose;
      const RigidTransform<S>& P0 = c.motion.pose;
      const Vec3<S> q = P1.R.transpose() * (x - P1.t);
      const Vec3<S> q0 = P0.R.transpose() * (x_start - P0.t);
      const S delta = surface_offset(opt, x, c.scale(), Vec3<S>(x - x_start));
      const auto pen = c.local_penetration(q, q0, radius, delta);
      if (!pen) return;
      x = P1.apply(pen->target);
      const Vec3<S> n = P1.R * pen->normal;
      const Vec3<S> vc = c.motion.moving() ? c.motion.velocity_at(P1.apply(pen->point), dt) : Vec3<S>::Zero();
      v = respond(v, n, vc, c.material, ropt).velocity;
      ++st.projections;
      moved = true;
    });
    if (!moved) break;
    projected = true;
  }
  return projected;
}

/// step_particle with the per-step context computed by the caller.
template <class S, class BV, class... X, class LegObserver>
StepStats step_particle_in(Particle<S>& p, const ColliderSet<S, BV, X...>& colliders, S dt, const StepOptions<S>& opt, const StepContext<S>& ctx,
                           LegObserver& on_leg) {
  StepStats st;
  ResponseOptions<S> ropt;
  ropt.rest_speed = ctx.rest;
  const Vec3<S> x_start = p.position;
  Vec3<S> x = p.position, v = p.velocity;
  S tau_now = S(0), left = dt;
  Vec3<S> active[3];
  int n_active = 0;
  S mu_rest = S(0);
  const bool moving = ctx.moving;
  const bool use_free_ball = ctx.use_free_ball;
  if (use_free_ball) {  // a ball found for other colliders or another radius is dropped
    const std::uint64_t key = particle_ball_key(ctx.ball_key, p.radius);
    if (p.free_key != key) {
      p.free_radius = S(0);
      p.free_key = key;
    }
  }

  for (int it = 0;; ++it) {
    // acceleration and velocity constrained by the resting contacts of this step
    Vec3<S> a = opt.gravity;
    S fn = S(0);
    for (int pass = 0; pass < 2 && n_active > 0; ++pass)
      for (int k = 0; k < n_active; ++k) {
        const S an = a.dot(active[k]);
        if (an < S(0)) a -= an * active[k], fn -= an;
        const S vn = v.dot(active[k]);
        if (vn < S(0)) v -= vn * active[k];
      }
    if (n_active > 0 && mu_rest > S(0) && fn > S(0)) {
      const S vl = v.norm(), al = a.norm();
      if (vl == S(0)) {
        if (al <= mu_rest * fn) a.setZero();
        else a -= (mu_rest * fn / al) * a;
      } else {
        a -= (mu_rest * fn / vl) * v;
        if ((v + a * left).dot(v) < S(0)) a = -v / left;  // stops within the leg
      }
    }
    const Vec3<S> d = v * left + (left * left / S(2)) * a;
    if ((d.squaredNorm() == S(0) && !moving) || !(left > S(0))) {
      v += a * left;
      break;
    }
    if (it == opt.max_iterations) {
      ++st.budget_exhausted;  // policy: stay at the last safe point, drop the rest of the step
      break;
    }
    // which colliders the leg provably stays clear of
    const LegClearance clear = use_free_ball ? leg_clearance(p, x, d, colliders, opt, ctx) : LegClearance{};
    if (clear.all) {  // every collider is static when the free ball is in use
      on_leg(x, Vec3<S>(x + d));
      x += d;
      v += a * left;
      break;
    }
    // The leg's end as it will be stored (rounded) and the chord cast: from x to that end. Far from
    // the origin the rounding of x + d can exceed the leg (float near 2^20: a spacing of 1/16 for
    // legs of 1/100), and a cast of the unrounded chord left the stored end unchecked: it ended
    // behind triangles the chord missed. c = (x + d) - x is exact in each component where
    // |d_k| <= |x_k| (Fast2Sum), so the cast covers exactly the segment travelled; elsewhere (a leg
    // within its length of a coordinate plane through the origin) c is within half an ulp of
    // |c_k|, the order of the cast's own rounding of t.
    const Vec3<S> e = x + d;
    const Vec3<S> c = e - x;
    // The cast reaches `reach` beyond the end: an end that close to a surface ahead (the cast's t
    // is rounded, and an end exactly on a triangle could pass for a miss, the next leg then
    // leaving from the surface to either side) is a hit, backed off like the others. The reach is
    // the surface offset, and at least 8 ulps of the coordinates and colliders' scales (an
    // absolute StepOptions::surface_offset may be smaller than the casts' rounding).
    const EndReach<S> end = end_reach(opt, e, c, ctx.scale);
    const S reach = end.reach;
    S scale = S(0);
    const std::optional<Contact<S>> hit =
        c == Vec3<S>::Zero() && !moving ? std::nullopt : first_hit(colliders, x, c, p.radius, tau_now, left, clear, opt, scale, end.t_max);
    if (!hit) {
      on_leg(x, e);
      x = e;
      v += a * left;
      break;
    }
    // a hit beyond the end (s > 1, within `reach`) backs off by reach at least: to the end or before
    const S s = hit->time;
    const S dn = -c.dot(hit->normal);
    const S delta = s > S(1) ? std::max(reach, detail::surface_offset(opt, hit->point, scale, c)) : detail::surface_offset(opt, hit->point, scale, c);
    const S s_safe = dn > S(0) ? std::min(std::max(s - delta / dn, S(0)), S(1)) : S(0);
    const Vec3<S> x_leg = x;
    Vec3<S> x_new = x + s_safe * c;
    if (s_safe > S(0) && !backoff_rounding_clear(delta, x, c)) {
      // an absolute surface offset below the rounding at these coordinates: the stored point is
      // kept only when the segment to it, and `reach` beyond, crosses nothing
      const Vec3<S> c2 = x_new - x;
      S scale2 = S(0);
      if (c2 != Vec3<S>::Zero() && first_hit(colliders, x, c2, p.radius, tau_now, left, clear, opt, scale2, end_reach(opt, x_new, c2, ctx.scale).t_max))
        x_new = x;
    }
    const S s_time = std::min(s, S(1));  // the impact time within the leg
    on_leg(x, x_new);
    x = x_new;
    const S tau = detail::impact_time(x_leg, v, a, *hit, s_time, left, p.radius);
    const ResponseResult<S> r = respond(Vec3<S>(v + a * tau), hit->normal, hit->collider_velocity, hit->material, ropt);
    v = r.velocity;
    if (r.resting && opt.gravity.dot(hit->normal) < S(0) && n_active < 3) {
      active[n_active++] = hit->normal;
      mu_rest = std::max(mu_rest, hit->material.friction);
    }
    ++st.impacts;
    tau_now += tau;
    left -= tau;
  }
  const bool projected = ctx.any_projection && project(p.radius, x_start, x, v, colliders, dt, opt, ropt, st);
  if (st.impacts > 0 || projected) st.particles_hit = 1;
  p.position = x;
  p.velocity = v;
  return st;
}

}  // namespace detail

namespace detail {

/// Throws InvalidInput unless dt is finite, >= 0 and within CoordinateRange and the options are
/// usable: gravity finite (|g|_inf dt^2 within CoordinateRange),
/// max_iterations >= 0, rest_speed, rest_speed_factor, offset_ulps, surface_offset and
/// free_ball_factor finite and >= 0, the strategy Backtrack or Project.
template <class S> void validate_step_options(S dt, const StepOptions<S>& opt, const char* where) {
  validate_length(dt, where, "dt");
  validate_finite(opt.gravity, where, "options.gravity");
  require(opt.gravity.cwiseAbs().maxCoeff() * dt * dt <= CoordinateRange<S>::max, where,
          "options.gravity * dt^2 must be within CoordinateRange (core/validate.hpp)");
  validate_in_range(opt.max_iterations, 0, std::numeric_limits<int>::max(), where, "options.max_iterations");
  validate_nonnegative(opt.rest_speed, where, "options.rest_speed");
  validate_nonnegative(opt.rest_speed_factor, where, "options.rest_speed_factor");
  validate_nonnegative(opt.offset_ulps, where, "options.offset_ulps");
  validate_nonnegative(opt.surface_offset, where, "options.surface_offset");
  validate_nonnegative(opt.free_ball_factor, where, "options.free_ball_factor");
  require(opt.strategy == Strategy::Backtrack || opt.strategy == Strategy::Project, where,
          "options.strategy must be Backtrack or Project (Inherit is for colliders)");
}

/// Throws InvalidInput unless the particle's position and free-ball centre are finite and within
/// CoordinateRange (core/validate.hpp), its velocity finite with |v|_inf dt within it, its radius
/// finite, >= 0 and within it, and its free radius not NaN (the step itself stores +infinity when
/// no collider is in reach; negative: a cool-down). `index` names
/// it in the message. A few comparisons, no allocation unless it throws.
template <class S> IMPACT_NOINLINE void reject_particle(const Particle<S>& p, std::size_t index, S dt, const char* where);
template <class S> inline void validate_particle(const Particle<S>& p, std::size_t index, S dt, const char* where) {
  constexpr S lim = CoordinateRange<S>::max;
  // The rule of reject_particle's checks in branch-free comparisons, each false for NaN: |x| <= lim
  // holds only for finite x within the range, and |v| dt <= lim only for finite v (an infinite v
  // gives infinity, or NaN when dt = 0). It runs for every particle on every step_particles call.
  // (ints, not bools: & on bools is what clang's -Wbitwise-instead-of-logical rejects)
  int ok = int(p.radius >= S(0)) & int(p.radius <= lim) & int(p.free_radius == p.free_radius);
  for (int k = 0; k < 3; ++k)
    ok &= int(std::abs(p.position[k]) <= lim) & int(std::abs(p.free_center[k]) <= lim) & int(std::abs(p.velocity[k]) * dt <= lim);
  if (IMPACT_UNLIKELY(!ok)) reject_particle(p, index, dt, where);
}
/// validate_particle for every particle, in blocks of 64: a block passes at once when the sum of
/// the magnitudes of its positions, free-ball centres and radii is within CoordinateRange, the
/// sum of its velocities' magnitudes times dt too, no radius is negative and no free radius NaN
/// (the sums of non-negative terms, rounded, are at least each term, and are NaN or infinite when
/// a term is); else each of its particles is checked on its own, which throws for the first that
/// fails. The same rule as validate_particle's, in a few vector additions a particle.
template <class S> inline void validate_particles(const std::vector<Particle<S>>& ps, S dt, const char* where) {
  constexpr S lim = CoordinateRange<S>::max;
  constexpr std::size_t block = 64;
  for (std::size_t b = 0; b < ps.size(); b += block) {
    const std::size_t e = std::min(ps.size(), b + block);
    Vec3<S> sx = Vec3<S>::Zero(), sc = Vec3<S>::Zero(), sv = Vec3<S>::Zero();
    S sr = S(0), rmin = S(0);
    int nan = 0;
    for (std::size_t i = b; i < e; ++i) {
      const Particle<S>& p = ps[i];
      sx += p.position.cwiseAbs();
      sc += p.free_center.cwiseAbs();
      sv += p.velocity.cwiseAbs();
      sr += p.radius;
      rmin = std::min(rmin, p.radius);
      nan += int(p.free_radius != p.free_radius);
    }
    const S sum = (sx + sc).sum() + sr;
    if (IMPACT_LIKELY(sum <= lim && sv.sum() * dt <= lim && rmin >= S(0) && nan == 0)) continue;
    for (std::size_t i = b; i < e; ++i) validate_particle(ps[i], i, dt, where);
  }
}

/// The checks of validate_particle one by one, throwing for the first that fails.
template <class S> IMPACT_NOINLINE void reject_particle(const Particle<S>& p, std::size_t index, S dt, const char* where) {
  constexpr S lim = CoordinateRange<S>::max;
  const std::string n = "particle " + std::to_string(index);
  validate_coordinates(p.position, where, (n + " position").c_str());
  validate_finite(p.velocity, where, (n + " velocity").c_str());
  require(p.velocity.cwiseAbs().maxCoeff() * dt <= lim, where, n + " velocity * dt must be within CoordinateRange (core/validate.hpp)");
  validate_length(p.radius, where, (n + " radius").c_str());
  validate_coordinates(p.free_center, where, (n + " free_center").c_str());
  require(!std::isnan(p.free_radius), where, n + " free_radius must not be NaN");
  throw InvalidInput(std::string(where) + ": " + n + " is out of range");  // the two rules agree; never proceed
}

}  // namespace detail

/// Advances one particle by dt against the colliders (see the file comment). `on_leg(from, to)`
/// is called for every straight piece of path the particle actually travels during
/// backtracking, for audits and visualisation. Returns this particle-step's counters.
/// Throws InvalidInput, with nothing modified, for a non-finite particle, a negative radius, dt
/// NaN, infinite or negative, bad options (detail::validate_step_options) or an invalid collider
/// (ColliderSet::validate): checks of O(colliders) per call.
template <class S, class BV, class... X, class LegObserver = detail::NoLegObserver>
StepStats step_particle(Particle<S>& p, const ColliderSet<S, BV, X...>& colliders, S dt, const StepOptions<S>& opt,
                        LegObserver&& on_leg = {}) {
  detail::validate_step_options(dt, opt, "step_particle");
  colliders.validate("step_particle");
  detail::validate_particle(p, 0, dt, "step_particle");
  return detail::step_particle_in(p, colliders, dt, opt, detail::StepContext<S>(colliders, dt, opt), on_leg);
}

/// A permutation of the particles along a Morton (Z-order) curve over their bounding box, 21 bits
/// per axis. Stepping particles in this order makes consecutive queries touch the same tree nodes
/// (better cache use on large meshes); reorder every few steps, since particles drift apart.
/// O(n) (a radix sort of the codes). Throws InvalidInput for a particle with a NaN or infinite
/// position.
template <class S> std::vector<std::uint32_t> spatial_order(const std::vector<Particle<S>>& particles) {
  Aabb<S> box;
  for (std::size_t i = 0; i < particles.size(); ++i) {
    if (IMPACT_UNLIKELY(!all_finite(particles[i].position)))
      validate_finite(particles[i].position, "spatial_order", ("particle " + std::to_string(i) + " position").c_str());
    box.extend(particles[i].position);
  }
  const Vec3<S> ext = box.extent().cwiseMax(Vec3<S>::Constant(std::numeric_limits<S>::min()));
  std::vector<std::pair<std::uint64_t, std::uint32_t>> keys(particles.size());
  for (std::size_t i = 0; i < particles.size(); ++i) {
    std::uint64_t code = 0;
    for (int k = 0; k < 3; ++k) {
      const double t = double((particles[i].position[k] - box.min[k]) / ext[k]);
      // in [0, 1] for finite positions; a box wider than the largest double gives t = NaN, sent
      // to 0 (the cast of a NaN would be undefined)
      const auto q = static_cast<std::uint64_t>((t > 0.0 ? (t < 1.0 ? t : 1.0) : 0.0) * 2097151.0);
      code |= detail::spread_bits_3(q) << k;
    }
    keys[i] = {code, static_cast<std::uint32_t>(i)};
  }
  // LSD radix sort, 8 bits a pass (stable, so equal codes keep their index order, as a sort of
  // the (code, index) pairs would); passes where every key has the same digit are skipped
  std::vector<std::pair<std::uint64_t, std::uint32_t>> tmp(keys.size());
  for (int shift = 0; shift < 64; shift += 8) {
    std::size_t count[257] = {0};
    for (const auto& k : keys) ++count[((k.first >> shift) & 0xff) + 1];
    if (std::any_of(count + 1, count + 257, [&](std::size_t c) { return c == keys.size(); })) continue;
    for (int b = 0; b < 256; ++b) count[b + 1] += count[b];
    for (const auto& k : keys) tmp[count[(k.first >> shift) & 0xff]++] = k;
    keys.swap(tmp);
  }
  std::vector<std::uint32_t> order(particles.size());
  for (std::size_t i = 0; i < keys.size(); ++i) order[i] = keys[i].second;
  return order;
}

/// Advances every particle by dt, each independently, on opt.threads threads (chunks of 256
/// particles handed out dynamically; the colliders are only read). Returns the summed counters.
/// The particles and counters are the same, bit for bit, for every thread count. Throws
/// InvalidInput, before any particle moves, on the checks of step_particle (one pass over the
/// particles, then the colliders and options once).
template <class S, class BV, class... X>
StepStats step_particles(std::vector<Particle<S>>& particles, const ColliderSet<S, BV, X...>& colliders, S dt, const StepOptions<S>& opt) {
  detail::validate_step_options(dt, opt, "step_particles");
  colliders.validate("step_particles");
  detail::validate_particles(particles, dt, "step_particles");
  const detail::StepContext<S> ctx(colliders, dt, opt);
  const detail::FreeFlightStep<S> flight(dt, opt, ctx);
  const auto run = [&](std::size_t begin, std::size_t end) {
    StepStats st;
    detail::NoLegObserver none;
    for (std::size_t i = begin; i < end; ++i) {
      if (detail::free_flight(particles[i], flight)) continue;
      st += detail::step_particle_in(particles[i], colliders, dt, opt, ctx, none);
    }
    return st;
  };
  constexpr std::size_t grain = 256;
  const int threads = resolve_threads(opt.threads);
  if (threads <= 1 || particles.size() < 2 * grain) return run(0, particles.size());
  std::vector<StepStats> chunk_stats((particles.size() + grain - 1) / grain);
  parallel_for_ranges(particles.size(), grain, threads,
                      [&](std::size_t begin, std::size_t end) { chunk_stats[begin / grain] = run(begin, end); });
  StepStats st;
  for (const StepStats& c : chunk_stats) st += c;  // integer sums: the same for any chunk order
  return st;
}

}  // namespace impact
