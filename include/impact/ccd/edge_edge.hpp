// SPDX-License-Identifier: MIT
/// \file
/// edge_edge_ccd: do two moving segments come within a minimum separation during a time step,
/// and when first? Every end point moves linearly between its positions at t = 0 and t = 1.
/// Conservative: it never misses a contact (see CcdResult for the exact guarantee).
#pragma once

#include "impact/ccd/detail/inclusion.hpp"
#include "impact/ccd/options.hpp"
#include "impact/core/types.hpp"

namespace impact {

/// Continuous segment-segment test over linear motion.
/// Inputs: edge a = (a0, a1) and edge b = (b0, b1) at t = 0 (suffix _t0) and t = 1 (suffix _t1);
/// coordinates finite (any magnitude: the test is scale-free, see CcdOptions), options in the
/// ranges of CcdOptions (both checked in every build: InvalidInput otherwise). Any configuration is accepted: parallel or
/// collinear edges, shared end points, zero-length edges, no motion, coplanar motion.
/// Output (CcdResult): hit == false proves that for all t in [0, opt.t_max] the distance between
/// the closed segments is greater than opt.min_separation. hit == true comes with a toi no later
/// than the first contact, and (u, v) with the contact points a0 + u (a1 - a0), b0 + v (b1 - b0).
/// Method: best-first subdivision of (t, u, v) with an exact-range inclusion of the trilinear
/// F(t, u, v) = a0 + u (a1 - a0) - b0 - v (b1 - b0) and rigorous floating-point error bounds
/// (detail/inclusion.hpp); a hit is then either proved real (detail/contact_proof.hpp) or
/// re-checked in double-double arithmetic, which turns near misses into misses
/// (CcdOptions::recheck_iterations). float inputs are computed in double. Cost: at most
/// opt.max_iterations boxes (about 0.1 us each; on exhaustion a conservative hit is reported),
/// plus at most opt.recheck_iterations double-double boxes (about 1 us each) for a hit.
template <class S>
CcdResult<S> edge_edge_ccd(const Vec3<S>& a0_t0, const Vec3<S>& a1_t0, const Vec3<S>& b0_t0, const Vec3<S>& b1_t0,
                           const Vec3<S>& a0_t1, const Vec3<S>& a1_t1, const Vec3<S>& b0_t1, const Vec3<S>& b1_t1,
                           const CcdOptions& opt = {}) {
  static_assert(is_supported_scalar_v<S>, "edge_edge_ccd: S must be float or double");
  double a[4][3], b[4][3];
  detail::ccd_load(a0_t0, a1_t0, b0_t0, b1_t0, a);
  detail::ccd_load(a0_t1, a1_t1, b0_t1, b1_t1, b);
  detail::ccd_check(a, b, opt, "edge_edge_ccd");
  return detail::ccd_result_cast<S>(detail::ccd_query<false>(a, b, opt));
}

}  // namespace impact
