// SPDX-License-Identifier: MIT
/// \file
/// Stepper's impact zones: rounds of CCD, zones merged over shared movable vertices, each zone
/// resolved by Harmon's projection or rigidly (Provot), and the zones' momentum error.
/// Part of cloth_collision_step's internals (stepper.hpp); not part of the interface.
#pragma once

#include "impact/cloth/detail/stepper.hpp"

#include <algorithm>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <numeric>
#include <vector>

namespace impact::detail::cloth {

/// Stage 3: impact zones (Harmon 2008 or rigid).
template <class S>
void Stepper<S>::zone_stage() {
  const auto t0 = Clock::now();
  precise_ = true;
  const std::size_t nv = sys_.w.size();
  // The positions each zone's resolution in a round starts from and stays closest to: the end
  // positions before that round (before the stage in round 0). A zone found again in a later
  // round (new hits, or merged with another zone) keeps every constraint it had and is
  // projected from where the last round left it, which already meets them: the solver meets
  // mostly the new constraints, where a projection from the positions before the stage would
  // solve the whole, grown zone again from scratch (at 10^5 vertices, a zone of 5,500
  // constraints three times over in one step). Every change is still W A^T lambda with
  // lambda >= 0 per round, so the zone's momentum is kept.
  Vertices<S> xhat;
  std::vector<std::int32_t> parent(nv);
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](std::int32_t v) {
    while (parent[static_cast<std::size_t>(v)] != v) {
      parent[static_cast<std::size_t>(v)] = parent[static_cast<std::size_t>(parent[static_cast<std::size_t>(v)])];
      v = parent[static_cast<std::size_t>(v)];
    }
    return v;
  };
  std::vector<ZoneConstraint> all;
  std::vector<std::int32_t> anchor;  // one movable vertex of each constraint (-1: none)
  for (int round = 0; round < opt_.max_zone_iterations; ++round) {
    const auto hits = detect();
    ++stats_.zones.passes;
    if (hits.empty()) break;
    xhat = sys_.X1;
    std::vector<std::int32_t> touched;
    for (const auto& hit : hits) {
      ZoneConstraint k = constraint_at_hit(hit);
      std::int32_t first = -1;
      for (int j = 0; j < k.count; ++j) {
        if (!(sys_.w[static_cast<std::size_t>(k.v[j])] > 0)) continue;
        if (first < 0) first = k.v[j];
        else parent[static_cast<std::size_t>(find(k.v[j]))] = find(first);
      }
      all.push_back(k);
      anchor.push_back(first);
      if (first >= 0) touched.push_back(first);
      ++stats_.zones.collisions;
    }
    // Zones touched in this round: every constraint of the zone, solved together.
    std::vector<std::int32_t> roots;
    for (auto v : touched) roots.push_back(find(v));
    std::sort(roots.begin(), roots.end());
    roots.erase(std::unique(roots.begin(), roots.end()), roots.end());
    std::vector<std::vector<std::size_t>> members(roots.size());
    for (std::size_t c = 0; c < all.size(); ++c) {
      if (anchor[c] < 0) continue;
      const auto it = std::lower_bound(roots.begin(), roots.end(), find(anchor[c]));
      if (it != roots.end() && *it == find(anchor[c])) members[static_cast<std::size_t>(it - roots.begin())].push_back(c);
    }
    for (std::size_t z = 0; z < roots.size(); ++z) resolve_zone(all, members[z], roots[z], xhat, parent, find);
  }
  stats_.zones.ms += ms_since(t0) - broad_ms_in_stage();
}

template <class S>
template <class Find>
void Stepper<S>::resolve_zone(const std::vector<ZoneConstraint>& all, const std::vector<std::size_t>& idx, std::int32_t root, const Vertices<S>& xhat,
                  const std::vector<std::int32_t>& parent, Find& find) {
  (void)parent;
  std::vector<ZoneConstraint> cons;
  cons.reserve(idx.size());
  bool immovable = false;
  for (auto c : idx) {
    cons.push_back(all[c]);
    for (int j = 0; j < all[c].count; ++j) immovable = immovable || !(sys_.w[static_cast<std::size_t>(all[c].v[j])] > 0);
  }
  // The zone's movable vertices: those of its constraints (only they are ever joined).
  std::vector<std::int32_t> verts;
  for (const auto& k : cons)
    for (int j = 0; j < k.count; ++j)
      if (sys_.w[static_cast<std::size_t>(k.v[j])] > 0) verts.push_back(k.v[j]);
  std::sort(verts.begin(), verts.end());
  verts.erase(std::unique(verts.begin(), verts.end()), verts.end());
  (void)root;
  (void)find;
  ++stats_.zone_count;
  stats_.largest_zone = std::max(stats_.largest_zone, verts.size());
  // The zone as a whole (every constraint it gathered so far) is solved from xhat, the
  // positions before this round.
  bool done = false;
  if (opt_.zone_method == ZoneMethod::Rigid && immovable) {
    // A rigid zone held by infinite-mass vertices that stay still is at rest with them (Provot,
    // Bridson: the zone's mass is infinite); held by moving ones it is projected like Harmon's.
    bool still = true;
    for (const auto& k : cons)
      for (int j = 0; j < k.count; ++j)
        if (!(sys_.w[static_cast<std::size_t>(k.v[j])] > 0)) still = still && sys_.X1.row(k.v[j]) == sys_.X0.row(k.v[j]);
    if (still) {
      for (auto v : verts) sys_.X1.row(v) = sys_.X0.row(v);
      ++stats_.rigid_zones;
      done = true;
    }
  }
  if (!done && (opt_.zone_method == ZoneMethod::Harmon || immovable)) {
    ZoneProjectionOptions po;
    po.max_iterations = opt_.max_projection_iterations;
    po.tolerance = static_cast<double>(opt_.projection_tolerance) * h_;
    // Reads every position from xhat (movable vertices outside this zone are not in its
    // constraints; immovable ones never change), writes only this zone's vertices.
    const auto r = project_zone(cons, sys_.w, xhat, sys_.X1, po);
    done = r.converged;
  }
  if (!done && !immovable) {
    for (auto v : verts) sys_.X1.row(v) = xhat.row(v);
    rigid_zone_motion(verts, sys_.w, sys_.X0, sys_.X1);
    ++stats_.rigid_zones;
    done = true;
  }
  if (done && !immovable) zone_momentum(verts, xhat);
  if (done)
    for (auto v : verts) changed_[static_cast<std::size_t>(v)] = 1;
  // A zone that could not be resolved stays as it is: the fail-safe takes it.
}

/// The momentum error of a resolved zone of finite-mass vertices only (nothing outside it pushes
/// it): the change of its linear momentum by the resolution, sum m (x1' - xhat), relative to
/// sum m |xhat - x0|; and of its angular momentum about its centre of mass at x0, sum m
/// (x0 - c) x (x1' - xhat), relative to sum m |x0 - c| |xhat - x0|. Kept as the step's largest.
template <class S>
void Stepper<S>::zone_momentum(const std::vector<std::int32_t>& verts, const Vertices<S>& xhat) {
  double mass = 0;
  Vec3<double> c = Vec3<double>::Zero();
  for (auto v : verts) {
    const double m = 1 / sys_.w[std::size_t(v)];
    mass += m;
    c += m * p0(v);
  }
  c /= mass;
  Vec3<double> dp = Vec3<double>::Zero(), dl = Vec3<double>::Zero();
  double ps = 0, ls = 0;
  for (auto v : verts) {
    const double m = 1 / sys_.w[std::size_t(v)];
    const Vec3<double> before = xhat.row(v).transpose().template cast<double>(), change = p1(v) - before, r = p0(v) - c;
    dp += m * change;
    dl += m * r.cross(change);
    ps += m * (before - p0(v)).norm();
    ls += m * r.norm() * (before - p0(v)).norm();
  }
  if (ps > 0) stats_.zone_momentum_error = std::max(stats_.zone_momentum_error, dp.norm() / ps);
  if (ls > 0) stats_.zone_angular_momentum_error = std::max(stats_.zone_angular_momentum_error, dl.norm() / ls);
}

}  // namespace impact::detail::cloth
