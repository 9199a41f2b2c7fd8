// SPDX-License-Identifier: MIT
/// \file
/// vertex_face_ccd: does a moving point come within a minimum separation of a moving triangle
/// during a time step, and when first? Every point moves linearly between its positions at t = 0
/// and t = 1. Conservative: it never misses a contact (see CcdResult for the exact guarantee).
#pragma once

#include "impact/ccd/detail/inclusion.hpp"
#include "impact/ccd/options.hpp"
#include "impact/core/types.hpp"

namespace impact {

/// Continuous vertex-triangle test over linear motion.
/// Inputs: the point p and the triangle (f0, f1, f2) at t = 0 (suffix 0) and t = 1 (suffix 1);
/// coordinates finite (any magnitude: the test is scale-free, see CcdOptions), options in the
/// ranges of CcdOptions (both checked in every build: InvalidInput otherwise). Any configuration is accepted: degenerate
/// (collinear or zero-area) triangles, coincident points, no motion, coplanar motion.
/// Output (CcdResult): hit == false proves that for all t in [0, opt.t_max] the distance from
/// p(t) to the closed triangle is greater than opt.min_separation. hit == true comes with a toi
/// no later than the first contact, and (u, v) with the contact point (1-u-v) f0 + u f1 + v f2.
/// Method: best-first subdivision of (t, u, v) with an exact-range inclusion of the trilinear
/// F(t, u, v) = p - f0 - u (f1 - f0) - v (f2 - f0) and rigorous floating-point error bounds
/// (detail/inclusion.hpp); a hit is then either proved real (detail/contact_proof.hpp) or
/// re-checked in double-double arithmetic, which turns near misses into misses
/// (CcdOptions::recheck_iterations). float inputs are computed in double. Cost: at most
/// opt.max_iterations boxes (about 0.1 us each; on exhaustion a conservative hit is reported),
/// plus at most opt.recheck_iterations double-double boxes (about 1 us each) for a hit.
template <class S>
CcdResult<S> vertex_face_ccd(const Vec3<S>& p0, const Vec3<S>& f00, const Vec3<S>& f10, const Vec3<S>& f20, const Vec3<S>& p1,
                             const Vec3<S>& f01, const Vec3<S>& f11, const Vec3<S>& f21, const CcdOptions& opt = {}) {
  static_assert(is_supported_scalar_v<S>, "vertex_face_ccd: S must be float or double");
  double a[4][3], b[4][3];
  detail::ccd_load(p0, f00, f10, f20, a);
  detail::ccd_load(p1, f01, f11, f21, b);
  detail::ccd_check(a, b, opt, "vertex_face_ccd");
  return detail::ccd_result_cast<S>(detail::ccd_query<true>(a, b, opt));
}

}  // namespace impact
