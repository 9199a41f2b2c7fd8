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
///
/// Parts: the options and counters (response/particle_step_options.hpp); what a step computes once
/// for all particles (response/detail/particle_step_context.hpp); the free-ball cache
/// (response/detail/free_ball.hpp); the surface offset and the reach beyond a leg's end
/// (response/detail/particle_offset.hpp). This file: the step of one particle (casts, back-off,
/// response, projection), validation, and the batch over many particles on threads.
#pragma once

#include "impact/core/parallel.hpp"
#include "impact/detail/morton.hpp"
#include "impact/response/collider.hpp"
#include "impact/response/detail/free_ball.hpp"
#include "impact/response/detail/particle_offset.hpp"
#include "impact/response/detail/particle_step_context.hpp"
#include "impact/response/particle.hpp"
#include "impact/response/particle_step_options.hpp"
#include "impact/response/response.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <optional>
#include <type_traits>
#include <utility>
#include <vector>

namespace impact {
namespace detail {

/// The default leg observer: does nothing.
struct NoLegObserver {
  template <class V> void operator()(const V&, const V&) const {}
};

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
