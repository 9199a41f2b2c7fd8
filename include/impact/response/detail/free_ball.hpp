// SPDX-License-Identifier: MIT
/// \file
/// The free-ball cache of backtracking particles (StepOptions::free_ball_factor; see
/// response/particle_step.hpp): a ball around a point whose every position keeps a particle
/// clear of the colliders (from the distance grids in O(1), else from a short walk of each mesh's
/// tree, exact for planes, spheres and boxes, shrunk for rounding), the test of a leg against a
/// particle's ball (which colliders it provably stays clear of), and the step of a particle whose
/// whole flight stays inside its ball.
#pragma once

#include "impact/bvh/traverse.hpp"
#include "impact/core/types.hpp"
#include "impact/response/collider.hpp"
#include "impact/response/detail/particle_step_context.hpp"
#include "impact/response/particle.hpp"
#include "impact/response/particle_step_options.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

namespace impact {
namespace detail {

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

}  // namespace detail
}  // namespace impact
