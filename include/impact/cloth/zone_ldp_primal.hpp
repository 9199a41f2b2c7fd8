// SPDX-License-Identifier: MIT
/// \file
/// The primal sparse solver of a zone's least-distance programme (the problem:
/// cloth/zone_ldp.hpp), for zones with many more constraints than unknowns (m > 3 n: most
/// constraints redundant, as in dense self-contact where each round of the zone stage adds
/// constraints on the same vertices). An augmented Lagrangian on the primal y (the proximal
/// point method on the dual, as in cloth/zone_ldp_sparse.hpp, seen from the other side):
///  - outer loop: multipliers mu, penalty 1/eps with eps from 1e-2 down by 10 per iteration to
///    1e-6 (against the unit rows); lambda_i = max(0, c_i + eps mu_i - g_i . y) / eps;
///  - inner loop: y minimises phi(y) = |y|^2 / 2 + sum_i max(0, c_i + eps mu_i - g_i . y)^2 / (2 eps),
///    a strongly convex piecewise quadratic, by semismooth Newton steps: one sparse LDLT of
///    I + sum_{active} g_i g_i^T / eps (size 3 n, positive definite whatever the redundancy of
///    the rows), then an exact line search along the piecewise quadratic (breakpoints sorted).
///    It stops when the gradient y - G^T lambda moves no row's slack by more than an eighth of
///    its tolerance, or when a step stays on its piece (then it is exact);
///  - convergence, on the positions G^T lambda the caller builds: the same KKT test and the
///    same weak-duality infeasibility certificate as the dual solver.
/// Cost per iteration: the 3n x 3n system's non-zeros (a row adds its 4 x 4 blocks) and its
/// factorisation, plus products with G: linear in m for assembly, independent of m otherwise.
#pragma once

#include "impact/cloth/zone_ldp.hpp"

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace impact::detail {

struct PrimalLdpOptions {
  int max_factorizations = 500;  ///< budget of Newton steps (LDLT factorisations)
  double eps = 1e-6;             ///< the last penalty parameter (1 / penalty, against unit rows)
  double eps_start = 1e-2;       ///< ... of the first outer iteration
  double eps_factor = 0.1;       ///< ... times this per outer iteration, down to eps
  double far = 1e6;              ///< infeasible when every feasible y is at least far * max c_i long
};

/// Solves the LDP `P` (see the file comment). Failed when the budget runs out or a
/// factorisation breaks down; Infeasible with the certificate above; Solved when the KKT
/// conditions hold to a quarter of each row's tolerance.
inline LdpSolution solve_ldp_primal(const ZoneLdp& P, const PrimalLdpOptions& opt = {}) {
  LdpSolution out;
  const auto m = static_cast<Eigen::Index>(P.rows.size());
  const auto n = 3 * static_cast<Eigen::Index>(P.blocks);
  out.lambda = Eigen::VectorXd::Zero(m);
  if (m == 0 || !(P.c.maxCoeff() > 0)) {
    out.status = LdpStatus::Solved;
    return out;
  }
  double eps = opt.eps_start, inv_eps = 1 / eps;
  const double rounding = ldp_rounding(P);
  Eigen::VectorXd mu = Eigen::VectorXd::Zero(m), lambda = Eigen::VectorXd::Zero(m), y = Eigen::VectorXd::Zero(n);
  Eigen::VectorXd r(m), s(m);
  std::vector<char> act(static_cast<std::size_t>(m), 0), prev(static_cast<std::size_t>(m), 2);
  std::vector<Eigen::Triplet<double>> trip;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower> ldlt;
  Eigen::SparseMatrix<double> K(n, n);
  int factorizations = 0;
  auto residuals = [&](const Eigen::VectorXd& yy) {  // r_i = c_i + eps mu_i - g_i . y
    r = P.c + eps * mu - (ldp_slack(P, yy) + P.c);
  };
  auto dot_rows = [&](const Eigen::VectorXd& d, Eigen::VectorXd& out_) {  // g_i . d
    out_ = ldp_slack(P, d) + P.c;
  };
  // One sub-problem, min phi(y) = |y|^2 / 2 + sum_i max(0, r_i(y))^2 / (2 eps), by Newton steps
  // with an exact line search, warm-started from y. Returns false on budget or breakdown.
  auto inner = [&]() -> bool {
    residuals(y);
    for (int it = 0;; ++it) {
      bool same = true;
      for (Eigen::Index i = 0; i < m; ++i) {
        act[static_cast<std::size_t>(i)] = r[i] > 0;
        same = same && act[static_cast<std::size_t>(i)] == prev[static_cast<std::size_t>(i)];
      }
      for (Eigen::Index i = 0; i < m; ++i) lambda[i] = act[static_cast<std::size_t>(i)] ? r[i] * inv_eps : 0.0;
      // Stationary to within the tolerances: the gradient y - G^T lambda moves no row's slack by
      // more than an eighth of its tolerance (the caller's positions come from lambda).
      const Eigen::VectorXd grad = y - ldp_primal(P, lambda);
      dot_rows(grad, s);
      bool small = true;
      for (Eigen::Index i = 0; i < m && small; ++i) small = std::abs(s[i]) <= 0.125 * P.tol[i];
      if (small || (same && it > 0)) return true;  // (or the last step stayed on its piece: exact)
      prev = act;
      if (++factorizations > opt.max_factorizations) return false;
      // Hessian I + sum_{active} g_i g_i^T / eps (lower triangle), gradient y - G^T lambda.
      trip.clear();
      for (Eigen::Index k = 0; k < n; ++k) trip.emplace_back(k, k, 1.0);
      for (Eigen::Index i = 0; i < m; ++i) {
        if (!act[static_cast<std::size_t>(i)]) continue;
        const LdpRow& row = P.rows[static_cast<std::size_t>(i)];
        for (int a = 0; a < row.nb; ++a)
          for (int b = 0; b < row.nb; ++b) {
            const Eigen::Index ra = 3 * static_cast<Eigen::Index>(row.blk[a]), cb = 3 * static_cast<Eigen::Index>(row.blk[b]);
            for (int u = 0; u < 3; ++u)
              for (int v = 0; v < 3; ++v)
                if (ra + u >= cb + v) trip.emplace_back(ra + u, cb + v, inv_eps * row.g[a][u] * row.g[b][v]);
          }
      }
      K.setFromTriplets(trip.begin(), trip.end());
      ldlt.compute(K);
      if (ldlt.info() != Eigen::Success) return false;
      const Eigen::VectorXd d = -ldlt.solve(grad);
      if (!d.allFinite()) return false;
      // Exact line search: phi'(t) = A + B t on each piece, rows switching at t = r_i / s_i.
      dot_rows(d, s);
      // phi'(0) = grad . d directly (the sum y . d - sum s_i r_i / eps cancels badly)
      double A = grad.dot(d), B = d.squaredNorm();
      std::vector<std::pair<double, Eigen::Index>> brk;
      for (Eigen::Index i = 0; i < m; ++i) {
        if (act[static_cast<std::size_t>(i)]) B += inv_eps * s[i] * s[i];
        if (s[i] != 0) {
          const double t = r[i] / s[i];
          if (t > 0) brk.emplace_back(t, i);
        }
      }
      if (!(A < 0)) return true;  // no descent left: y is the minimiser to rounding
      std::sort(brk.begin(), brk.end());
      double t = -A / B;
      for (const auto& [tb, i] : brk) {
        if (t <= tb) break;
        // row i switches at tb: active rows with s > 0 leave, inactive rows with s < 0 join
        const double sign = act[static_cast<std::size_t>(i)] ? -1.0 : 1.0;
        act[static_cast<std::size_t>(i)] = !act[static_cast<std::size_t>(i)];
        A -= sign * inv_eps * s[i] * r[i], B += sign * inv_eps * s[i] * s[i];
        t = B > 0 ? std::max(tb, -A / B) : tb;
      }
      if (!(t > 0) || !std::isfinite(t)) return false;
      y += t * d;
      residuals(y);
    }
  };
  for (int outer = 0; outer <= 200; ++outer) {
    const bool ok = inner();
    const Eigen::VectorXd yl = ldp_primal(P, lambda);  // the positions the caller will build
    out.iterations = factorizations;
    out.status = ldp_outer_verdict(P, lambda, yl, ok, rounding, opt.far);
    if (out.status == LdpStatus::Solved) out.lambda = lambda;
    if (out.status != LdpStatus::Failed || !ok) return out;
    mu = lambda;
    prev.assign(prev.size(), 2);
    eps = std::max(opt.eps, eps * opt.eps_factor);
    inv_eps = 1 / eps;
  }
  return out;  // Failed: the proximal iteration does not settle
}

}  // namespace impact::detail
