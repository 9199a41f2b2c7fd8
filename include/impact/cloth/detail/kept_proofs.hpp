// SPDX-License-Identifier: MIT
/// \file
/// The rule by which a candidate's proof (a lower bound L on its distance over the whole step,
/// L > need = h + margin) survives later moves of its vertices' end positions within the step,
/// so that the pair needs no re-test. Part of cloth_collision_step's internals (stepper.hpp,
/// step_bounds.hpp); not part of the interface.
///
/// Why it holds. At time t of the step a vertex is at (1 - t) x0 + t x1, so moving its end
/// position by e_k moves it by t e_k. For fixed barycentric weights a of the first primitive and
/// b of the second, the offset between the two points changes by t (sum_i a_i e_i - sum_j b_j
/// e_j), whose length is at most max_i |e_i| + max_j |e_j| <= sum_k |e_k| (convex
/// combinations, t <= 1). Every offset was at least L long, so the pair's distance stays above
/// L - sum_k |e_k| over the whole step, and above need while
///   sum_k |e_k| <= L - need  (the proof's slack).
/// |e_k| is at most the growth of vertex k's path length since the proof (the sum of the lengths
/// of its end position's moves; triangle inequality). With P_k the path lengths, the proof holds
/// while sum_k P_k(now) <= sum_k P_k(proof) + slack, so one number per candidate, its key
/// sum_k P_k(proof) + slack, decides.
#pragma once

namespace impact::detail::cloth {

/// The key of a proof made when its vertices' path lengths summed to `path_sum` (computed in
/// double: a sum of at most 1000 norms per path, four paths, relative error under 1e-12), with
/// slack = L - need > 0. The factor 1 - 1e-12 (and 1 + 1e-12 in proof_holds) covers the
/// rounding of the path lengths, so that a proof is kept only when the true path growth stays
/// within the slack.
inline double proof_key(double path_sum, double slack) { return path_sum * (1 - 1e-12) + slack; }

/// Whether a proof with this key still holds when its vertices' path lengths sum to `path_sum`.
inline bool proof_holds(double path_sum, double key) { return path_sum * (1 + 1e-12) <= key; }

}  // namespace impact::detail::cloth
