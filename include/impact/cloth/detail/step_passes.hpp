// SPDX-License-Identifier: MIT
/// \file
/// Stepper's CCD passes: the primitive CCD of a pair, and each pass's test of the candidates with
/// a moved vertex (re-gathering first when a vertex left its envelope), proofs kept from earlier
/// passes skipped.
/// Part of cloth_collision_step's internals (stepper.hpp); not part of the interface.
#pragma once

#include "impact/cloth/detail/step_gathering.hpp"
#include "impact/cloth/detail/stepper.hpp"

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

namespace impact::detail::cloth {

template <class S>
CcdResult<S> Stepper<S>::ccd(const Prim& p, bool static_start) {
  ++stats_.ccd_tests;
  return ccd_at(p, static_start, /*coarse=*/false);
}

/// The primitive CCD of a pair (thread-safe: reads only). The start check, the zones and the
/// fail-safe use the options as given (coarse == false). The impulse passes only need a hit's time and
/// contact to within a fraction of h: each pushes its hit to (1 + separation_margin) h, so a
/// pair reported at h + band_ (band_ = separation_margin h / 2) is pushed as it should be, and a
/// false positive closer than that costs one harmless impulse. There each query gets the
/// tolerance that reports hits within h + band_ (tolerance = band_ / (2 L), L the query's
/// extent, at most 1e-2 and never below the given one) and no re-check. The zones do not take
/// it: a zone is detected again after each projection, and near misses within the band kept
/// zones growing and merging until the rounds ran out (a 2,000-step twisting run then needed
/// the fail-safe in 298 steps and ended one closer than h). Neither changes the CCD's
/// guarantee: hit == false still proves the pair stays farther apart than h.
template <class S>
CcdResult<S> Stepper<S>::ccd_at(const Prim& p, bool static_start, bool coarse) const {
  auto a = [&](int k) { return Vec3<S>(sys_.X0.row(p.v[k]).transpose()); };
  auto b = [&](int k) { return static_start ? Vec3<S>(sys_.X0.row(p.v[k]).transpose()) : Vec3<S>(sys_.X1.row(p.v[k]).transpose()); };
  CcdOptions o = ccd_;
  if (coarse && !static_start && band_ > 0) {
    Vec3<double> lo = p0(p.v[0]), hi = lo;
    for (int k = 0; k < 4; ++k) {
      lo = lo.cwiseMin(p0(p.v[k])).cwiseMin(p1(p.v[k]));
      hi = hi.cwiseMax(p0(p.v[k])).cwiseMax(p1(p.v[k]));
    }
    const double L = (hi - lo).maxCoeff();
    o.tolerance = std::max(o.tolerance, L > 0 ? std::min(band_ / (2 * L), 1e-2) : 1e-2);
    o.recheck_iterations = 0;
  }
  if (p.ee) return edge_edge_ccd(a(0), a(1), a(2), a(3), b(0), b(1), b(2), b(3), o);
  return vertex_face_ccd(a(0), a(1), a(2), a(3), b(0), b(1), b(2), b(3), o);
}

/// CCD over the pairs that may have changed: gathers again only when a moved vertex left its
/// envelope, then tests the candidates with a vertex moved since the last pass and the previous
/// hits.
template <class S>
std::vector<typename Stepper<S>::Hit> Stepper<S>::detect() {
  note_moves();
  if (escaped()) regather();
  return test_changed();
}

/// The candidates with a vertex moved since the last pass (changed_) and the last hits are
/// listed in increasing index order, less those whose proof from an earlier pass still holds
/// (kept); each listed one is proved apart by a bound or by sampling (its key noted), or else
/// tested, the CCD's search deciding unless sampling found a clear hit. Returns the hits,
/// earliest first (in the order of their primitive pairs, Prim's, among equal times).
template <class S>
std::vector<typename Stepper<S>::Hit> Stepper<S>::test_changed() {
  note_moves();
  // The candidates to test: by one scan of every candidate when many vertices moved (the last
  // hits marked first, so that the scan lists them in order too); else through the vertex ->
  // candidate index (the candidates appended since it was built by a scan of those), then
  // sorted, or listed by a scan of the stamps when many were marked (cheaper than sorting).
  std::vector<std::uint32_t>& todo = todo_;
  std::size_t moved = 0, listed = 0;
  for (auto c : changed_) moved += c;
  if (++stamp_now_ == 0) std::fill(stamp_.begin(), stamp_.end(), 0), stamp_now_ = 1;
  for (const auto& h : last_hits_) stamp_[h.c] = stamp_now_;
  auto touched = [&](const Prim& p) {
    return changed_[std::size_t(p.v[0])] || changed_[std::size_t(p.v[1])] || changed_[std::size_t(p.v[2])] || changed_[std::size_t(p.v[3])];
  };
  Appender<std::uint32_t> list(todo);  // fills todo (push_back inlined)
  if (moved * 8 >= changed_.size()) {
    for (std::size_t c = 0; c < cand_.size(); ++c)
      if (stamp_[c] == stamp_now_ || touched(cand_[c])) {
        ++listed;
        if (!kept(c)) list.push(static_cast<std::uint32_t>(c));
      }
    list.finish();
  } else {
    for (const auto& h : last_hits_) list.push(h.c);
    if (moved > 0) {
      if (inc_off_.empty() || 4 * (cand_.size() - inc_n_) > inc_n_) build_incidence();
      for (std::size_t v = 0; v < changed_.size(); ++v) {
        if (!changed_[v]) continue;
        for (std::uint32_t k = inc_off_[v]; k < inc_off_[v + 1]; ++k)
          if (stamp_[inc_[k]] != stamp_now_) stamp_[inc_[k]] = stamp_now_, list.push(inc_[k]);
      }
      for (std::size_t c = inc_n_; c < cand_.size(); ++c)
        if (stamp_[c] != stamp_now_ && touched(cand_[c])) list.push(static_cast<std::uint32_t>(c)), stamp_[c] = stamp_now_;
    }
    if (list.n() * 16 >= cand_.size()) {
      Appender<std::uint32_t> again(todo);
      for (std::size_t c = 0; c < cand_.size(); ++c)
        if (stamp_[c] == stamp_now_) again.push(static_cast<std::uint32_t>(c));
      again.finish();
    } else {
      list.finish();
      std::sort(todo.begin(), todo.end());
    }
    listed = todo.size();
    todo.erase(std::remove_if(todo.begin(), todo.end(), [&](std::uint32_t c) { return kept(c); }), todo.end());
  }
  stats_.ccd_kept += listed - todo.size();
  // First each listed candidate's bounds and sampling (status 1: the search decides, 2: sampling
  // found a clear hit at time toi[i]); then the search for status 1, with results stored for
  // the candidates of status 1 and 2 alone (a CcdResult per listed candidate was 56 bytes each
  // for millions of them, mostly proved apart).
  std::vector<std::uint8_t>& status = status_;
  status.assign(todo.size(), 0);
  std::vector<double>& toi = toi_;
  if (toi.size() < todo.size()) toi.clear(), toi.resize(todo.size() + todo.size() / 2);
  parallel_for(todo.size(), opt_.threads, [&](std::size_t i) {
    const std::size_t c = todo[i];
    if (is_excluded(cand_[c])) return;
    Measured known;
    const double bound = separation_bound(c, known);
    if (bound > -std::numeric_limits<double>::infinity()) {
      key_[c] = key_of(cand_[c], bound);
      return;
    }
    key_[c] = -1;
    // Clear hits and misses need no search (sample_pair); every other pair gets the CCD (coarse
    // in the impulse passes, as given in the zones and the fail-safe).
    double sampled_bound = 0;
    CcdResult<S> r;
    const Sampled sp = sample_pair(cand_[c], known, r, sampled_bound);
    if (sp == Sampled::miss) {
      key_[c] = key_of(cand_[c], sampled_bound);
      return;
    }
    if (sp == Sampled::hit) toi[i] = static_cast<double>(r.toi);
    status[i] = sp == Sampled::hit ? 2 : 1;
  });
  std::vector<std::uint32_t>& run = run_;
  run.clear();
  for (std::size_t i = 0; i < todo.size(); ++i)
    if (status[i]) run.push_back(static_cast<std::uint32_t>(i));
  if (res_.size() < run.size()) res_.resize(run.size());
  CcdResult<S>* res = res_.data();
  parallel_for(run.size(), opt_.threads, [&](std::size_t k) {
    const std::size_t i = run[k], c = todo[i];
    if (status[i] == 2) {
      res[k] = CcdResult<S>();  // as sample_pair's hit
      res[k].hit = true;
      res[k].toi = static_cast<decltype(res[k].toi)>(toi[i]);
    } else {
      res[k] = ccd_at(cand_[c], false, /*coarse=*/!precise_);
    }
  });
  stats_.ccd_tests += run.size();
  stats_.ccd_skipped += todo.size() - run.size();
  std::vector<Hit> hits;
  for (std::size_t k = 0; k < run.size(); ++k)
    if (res[k].hit) hits.push_back({cand_[todo[run[k]]], res[k], todo[run[k]]});
  std::fill(changed_.begin(), changed_.end(), 0);
  // Earliest first, equal times in the order of their vertices (not their candidate index, which
  // follows the tree's walk): the impulses, the relaxation and the zones take the hits in this
  // order, so the step's result does not depend on the tree.
  std::sort(hits.begin(), hits.end(), [](const Hit& x, const Hit& y) { return x.r.toi != y.r.toi ? x.r.toi < y.r.toi : x.p < y.p; });
  last_hits_ = hits;
  return hits;
}

}  // namespace impact::detail::cloth
