// SPDX-License-Identifier: MIT
/// \file
/// One Newton step on an angle held as its cosine and sine, without trigonometric calls: the
/// curved-pair minimisations over a circle (circle_minimise in convex/cylinder_pair.hpp) and over a
/// cone's side normals (cone_side_newton in convex/local_certificate.hpp) iterate on an azimuth phi
/// and turn it by each Newton step.
///
/// The turn is the Cayley transform: a rotation by 2 atan(step / 2) = step - step^3 / 12 + ...,
/// whose cosine and sine are rational in the step, so Newton's next error stays O(step^3) (as fast
/// as Newton's own). The rotated pair keeps unit length up to rounding; one Newton step of 1 / sqrt
/// from 1 puts it back within rounding (no square root or division of the length in the loop's
/// dependent chain).
///
/// Numerical contract: APPROXIMATE (the turned pair has unit length within a few ulps).
/// Thread safety: pure function.
#pragma once

namespace impact::detail {

/// Turns (cos_phi, sin_phi) by the angle 2 atan(step / 2) and renormalises it.
template <class S>
inline void azimuth_turn(S step, S& cos_phi, S& sin_phi) {
  const S q = step * step / S(4), den = S(1) / (S(1) + q);
  const S cs = (S(1) - q) * den, sn = step * den;
  const S c2 = cos_phi * cs - sin_phi * sn, s2 = sin_phi * cs + cos_phi * sn;
  const S norm = (S(3) - (c2 * c2 + s2 * s2)) / S(2);
  cos_phi = c2 * norm;
  sin_phi = s2 * norm;
}

}  // namespace impact::detail
