// SPDX-License-Identifier: MIT
/// \file
/// What a particle step computes once for all its particles (StepContext: the resting threshold,
/// whether colliders move, whether the free-ball cache is in use, the colliders' largest scale)
/// and the digest of everything a particle's free ball depends on (Particle::free_key), so that a
/// ball found for other colliders is never trusted. Used by response/particle_step.hpp.
#pragma once

#include "impact/core/types.hpp"
#include "impact/response/collider.hpp"
#include "impact/response/particle_step_options.hpp"

#include <algorithm>
#include <cstdint>
#include <cstring>

namespace impact {
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

}  // namespace detail
}  // namespace impact
