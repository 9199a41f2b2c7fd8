// SPDX-License-Identifier: MIT
/// \file
/// Stepper's contact stages: proximity (the pairs near at x0 relaxed until none approaches), the
/// passes of CCD impulses, and the fail-safe (colliding pairs' movable vertices back at x0 until
/// the CCD finds nothing).
/// Part of cloth_collision_step's internals (stepper.hpp); not part of the interface.
#pragma once

#include "impact/cloth/detail/stepper.hpp"

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace impact::detail::cloth {

/// Stage 1: pairs within the proximity distance at x0 stop approaching (inelastic) with
/// friction: each pair's gap along its normal at x0 (closest points' weights at x0) may not
/// fall below its distance at x0. Relaxed in rounds (relax_contacts) until every pair meets
/// that to proximity_tolerance h, or proximity_rounds run out (the CCD stages take the rest).
template <class S>
void Stepper<S>::proximity_stage() {
  const auto t0 = Clock::now();
  contacts_.reserve(near_.size());
  for (const auto& q : near_)
    if (q.c.dist > 0) contacts_.push_back(constraint_of(q.p, q.c.a, q.c.n, q.c.dist));
  std::vector<std::uint8_t> acted(contacts_.size(), 0);
  const RelaxStats r = relax(opt_.proximity_rounds, &acted);
  stats_.proximity.passes += r.rounds;
  stats_.proximity_impulses += r.impulses;
  stats_.proximity_converged = r.converged;
  for (auto a : acted) stats_.proximity.collisions += a;
  stats_.proximity.ms += ms_since(t0);
}

/// Stage 2: passes of CCD impulses, earliest first.
template <class S>
void Stepper<S>::impulse_stage() {
  const auto t0 = Clock::now();
  precise_ = false;
  for (int pass = 0; pass < opt_.impulse_passes; ++pass) {
    const auto hits = detect();
    ++stats_.impulses.passes;
    if (hits.empty()) break;
    for (const auto& hit : hits) {
      ZoneConstraint k = constraint_at_hit(hit);
      if (apply_impulse(k)) ++stats_.impulses.collisions;
      if (opt_.impulse_relax_rounds > 0) contacts_.push_back(k);
    }
    // The hits join the contact set and it is relaxed again: an impulse that stops a landing
    // sheet pushes the sheet below it into the resting stack, which the proximity pairs carry
    // down to the floor (without it, those pairs are the next pass's and the zones' hits).
    if (opt_.impulse_relax_rounds > 0) stats_.impulse_relax_impulses += relax(opt_.impulse_relax_rounds, nullptr).impulses;
  }
  stats_.impulses.ms += ms_since(t0) - broad_ms_in_stage();
}

/// Stage 4: the fail-safe. Colliding pairs' movable vertices go back to x0 until the CCD finds
/// nothing (boxes only shrink, so the candidates of one gathering stay a superset).
template <class S>
void Stepper<S>::failsafe_stage() {
  const auto t0 = Clock::now();
  precise_ = true;
  auto hits = detect();
  ++stats_.failsafe.passes;
  while (!hits.empty()) {
    bool froze = false;
    for (const auto& hit : hits) {
      bool any = false;
      for (int j = 0; j < 4; ++j) {
        const std::int32_t v = hit.p.v[j];
        if (sys_.w[static_cast<std::size_t>(v)] > 0 && sys_.X1.row(v) != sys_.X0.row(v)) {
          sys_.X1.row(v) = sys_.X0.row(v);
          changed_[static_cast<std::size_t>(v)] = 1;
          ++stats_.frozen_vertices;
          froze = any = true;
        }
      }
      if (any) ++stats_.failsafe.collisions;
    }
    if (!froze) break;
    stats_.failsafe_used = true;
    hits = test_changed();
    ++stats_.failsafe.passes;
  }
  if (!hits.empty()) {
    stats_.collision_free = false;
    for (const auto& hit : hits) stats_.unresolved.push_back(to_pair(hit.p));
  }
  stats_.failsafe.ms += ms_since(t0) - broad_ms_in_stage();
}

}  // namespace impact::detail::cloth
