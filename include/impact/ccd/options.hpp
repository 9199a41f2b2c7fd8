// SPDX-License-Identifier: MIT
/// \file
/// Options and result of the continuous collision tests (vertex_face_ccd, edge_edge_ccd): the
/// minimum separation, the time window, the tolerance that bounds false positives and the work
/// budget go in; hit, a conservative time of impact, the contact parameters and flags come out.
#pragma once

#include <cstdint>

namespace impact {

/// Inputs of vertex_face_ccd and edge_edge_ccd. Lengths are in the units of the coordinates.
/// Every entry point (vertex_face_ccd, edge_edge_ccd, mesh_ccd, mesh_self_ccd) checks the ranges
/// given below in every build and throws InvalidInput with the reason otherwise: an out-of-range
/// option would void the meaning of hit == false.
///
/// Scale: the tests are scale-free. A query is scaled by a power of two (exact) before the search
/// and its rounding-error bounds are relative to its extent, so a query scaled by any power of
/// two gives the same result (hit, toi, u, v, iteration counts), and one translated by an exact
/// amount the same decisions; a user in millimetres and one in kilometres get the same quality.
/// The one length that stays absolute is min_separation, a physical distance.
struct CcdOptions {
  /// d >= 0 (finite): a contact is any time at which the two primitives come within distance d,
  /// in the units of the coordinates.
  double min_separation = 0.0;
  /// The tests look at t in [0, t_max], 0 < t_max <= 1 (t = 1 is the end of the step).
  double t_max = 1.0;
  /// Relative tolerance (finite, >= 0; unitless), which bounds the false positives of the search:
  /// with L the query's extent, the largest side of the axis-aligned box around its 8 points (the
  /// primitives at t = 0 and t = 1), the search reports a hit once it has found a time toi, with
  /// every earlier time excluded, at which the primitives are within min_separation +
  /// 2 tolerance L (up to rounding, about 1e-15 times L and the distance between the points).
  /// Smaller gives a later (tighter) toi and is slower; the re-check below then decides whether
  /// such a hit is a real contact. Never affects the no-false-negative guarantee. The default
  /// 1e-6 is a micrometre on a metre-sized query, or a millimetre on a kilometre-sized one.
  double tolerance = 1e-6;
  /// Work budget: the number of (t, u, v) boxes the search may examine. When it runs out the test
  /// reports a hit at the earliest time not yet excluded, with CcdResult::budget_exhausted set.
  /// A box costs about 0.1-0.5 us, so the default bounds a query to well under a millisecond; the
  /// query files of the benchmark need at most about 600 boxes at the default tolerance.
  /// In [1, 2^22] (the search's memory grows by at most one 56-byte box per iteration).
  std::int64_t max_iterations = 2000;
  /// Re-check of hits. A hit of the search is first tested for a proof of a real contact (a
  /// simple root of the contact equations inside the domain, proved in interval arithmetic: the
  /// usual transversal contact, a few microseconds). Otherwise it is searched again in
  /// double-double arithmetic (about 106 bits) without the tolerance, for at most this many
  /// boxes; when that search excludes every time, the answer becomes a miss. This removes the
  /// false positives of near misses closer than the tolerance, including those closer than
  /// double rounding can separate (about 1e-15 times the coordinates). A box costs about 1 us,
  /// so an unproved hit (a contact exactly on an edge or vertex, tangential or coplanar, or a
  /// near miss) costs up to about 0.5 ms more by default; misses cost nothing more. 0 disables
  /// the re-check (the double search alone). In [0, 2^22].
  std::int64_t recheck_iterations = 400;
};

/// Output of vertex_face_ccd and edge_edge_ccd.
/// - hit == false guarantees that for every t in [0, t_max] the two primitives (closed triangle,
///   closed segments) are farther apart than min_separation: no false negatives, ever.
/// - hit == true: toi is never later than the first time at which the primitives come within
///   min_separation (if they do at all), and at time toi the primitives are within
///   min_separation + 2 tolerance L of each other (L the query's extent, see
///   CcdOptions::tolerance; except when budget_exhausted, which only
///   promises that no contact happens before toi). Near misses closer than that are hits only
///   when the re-check (CcdOptions::recheck_iterations) can neither prove the contact nor
///   exclude it within its budget.
template <class S>
struct CcdResult {
  bool hit = false;
  /// Conservative time of impact in [0, t_max]; t_max when there is no hit.
  S toi = S(1);
  /// Contact parameters at toi, meaningful only when hit. Vertex-face: the triangle point is
  /// (1-u-v) f0 + u f1 + v f2. Edge-edge: the points are a0 + u (a1 - a0) and b0 + v (b1 - b0).
  /// Unless budget_exhausted, the primitives' points at (toi, u, v) are within
  /// min_separation + 2 tolerance L of each other.
  S u = S(0), v = S(0);
  /// The search's budget ran out (and the re-check did not settle the query): toi is the earliest
  /// time not yet excluded, the hit may be false.
  bool budget_exhausted = false;
  /// Number of (t, u, v) boxes examined by the search, and by the re-check of a hit (0 when the
  /// hit was proved real or there was no hit).
  std::int64_t iterations = 0;
  std::int64_t recheck_iterations = 0;
};

}  // namespace impact
