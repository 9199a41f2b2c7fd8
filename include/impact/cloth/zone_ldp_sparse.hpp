// SPDX-License-Identifier: MIT
/// \file
/// The sparse solver of a zone's least-distance programme (the problem: cloth/zone_ldp.hpp),
/// for zones of thousands of constraints. It works on the dual, a bound-constrained convex
/// quadratic programme in the multipliers:
///     min q(lambda) = 1/2 lambda^T H lambda - c^T lambda,  lambda >= 0,   H = G G^T,
/// whose gradient w = H lambda - c is the rows' slack g_i . y - c_i at y = G^T lambda (KKT:
/// lambda >= 0, w >= 0, lambda_i w_i = 0). H is sparse (rows couple only through shared
/// vertices; unit diagonal) and positive semi-definite: singular when rows are linearly
/// dependent (duplicate or redundant collisions, several collisions of one vertex).
///  - Proximal point (outer loop): q is minimised with eps/2 |lambda - mu|^2 added, mu the
///    previous multipliers (eps = 1e-6 against the unit diagonal): H + eps I is positive
///    definite, every sub-problem has one solution, and the outer iterations converge to a
///    solution of the unregularised problem (the proximal point method on the dual, an
///    augmented Lagrangian on the primal), usually in one or two iterations.
///  - Projected Newton (inner loop; Bertsekas 1982, "Projected Newton methods for optimization
///    problems with simple constraints"): the rows at (or within delta of) the bound with a
///    gradient pushing there are held at 0; one sparse LDLT of (H + eps I) on the others
///    (Eigen's SimplicialLDLT, AMD ordering) gives the minimiser on that face, and a projected
///    backtracking search (Armijo) towards it changes many bounds per iteration. The objective
///    decreases at every step, so there is no cycling; the factorisation is kept while the free
///    set does not change.
///  - Convergence is decided on the unregularised KKT conditions, row by row with the row's
///    tolerance t_i: lambda >= 0 (by construction), g_i . y - c_i >= -t_i / 4 for every row
///    (feasible), |g_i . y - c_i| <= t_i / 4 where lambda_i > 0 (complementary); stationarity
///    y = G^T lambda holds by construction.
///  - Infeasibility: for any lambda >= 0 and any y meeting every row to within t,
///    |y| >= (c . lambda - t . lambda) / |G^T lambda| (weak duality). At the optimum of a
///    feasible problem this bound equals |y*|; on an infeasible one the proximal iterates grow
///    like 1/eps and the bound with them. The problem is reported infeasible when the bound
///    exceeds 1e6 times the largest c_i (each row alone needs |y| >= c_i): no point within a
///    million times the largest single correction meets every row.
/// Cost per iteration: the sub-matrix's non-zeros and its sparse factorisation, plus products
/// with G and G^T; for cloth zones (a constraint meets a bounded number of others) close to
/// linear in the zone. The number of iterations is not bounded by a small constant: on zones
/// with many more constraints than unknowns (most of them redundant) it can exceed the dense
/// solver's count of active-set changes; project_zone gives such zones (m > 3n) to the primal
/// solver (cloth/zone_ldp_primal.hpp), whose system is 3n x 3n.
#pragma once

#include "impact/cloth/zone_ldp.hpp"

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace impact::detail {

struct SparseLdpOptions {
  int max_factorizations = 500;  ///< budget of Newton steps (LDLT factorisations or re-uses)
  double eps = 1e-6;             ///< proximal regularisation against the unit diagonal of H
  double far = 1e6;              ///< infeasible when every feasible y is at least far * max c_i long
};

/// Solves the LDP `P` (see the file comment). Failed when the budget runs out or a
/// factorisation breaks down; Infeasible with the certificate above; Solved when the KKT
/// conditions hold to a quarter of each row's tolerance.
template <class Ldp = ZoneLdp>
LdpSolution solve_ldp_sparse(const Ldp& P, const SparseLdpOptions& opt = {}) {
  LdpSolution out;
  const auto m = static_cast<Eigen::Index>(P.rows.size());
  out.lambda = Eigen::VectorXd::Zero(m);
  if (m == 0 || !(P.c.maxCoeff() > 0)) {
    out.status = LdpStatus::Solved;
    return out;
  }
  const double cmax = P.c.maxCoeff();
  // H = G G^T, both triangles, from the rows that share each block.
  Eigen::SparseMatrix<double> H(m, m);
  const double rounding = ldp_rounding(P);
  {
    std::vector<std::vector<std::pair<int, int>>> by_block(static_cast<std::size_t>(P.blocks));  // (row, slot)
    for (Eigen::Index i = 0; i < m; ++i)
      for (int q = 0; q < P.rows[static_cast<std::size_t>(i)].nb; ++q)
        by_block[static_cast<std::size_t>(P.rows[static_cast<std::size_t>(i)].blk[q])].push_back({static_cast<int>(i), q});
    std::vector<Eigen::Triplet<double>> trip;
    std::size_t count = 0;
    for (const auto& list : by_block) count += list.size() * list.size();
    trip.reserve(count);
    for (const auto& list : by_block)
      for (const auto& [ci, qi] : list)
        for (const auto& [cj, qj] : list)
          trip.emplace_back(ci, cj, P.rows[static_cast<std::size_t>(ci)].g[qi].dot(P.rows[static_cast<std::size_t>(cj)].g[qj]));
    H.setFromTriplets(trip.begin(), trip.end());
  }
  const double eps = opt.eps;
  Eigen::VectorXd lambda = Eigen::VectorXd::Zero(m), mu = Eigen::VectorXd::Zero(m);
  std::vector<Eigen::Index> pos(static_cast<std::size_t>(m), -1);
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower> ldlt;
  std::vector<Eigen::Triplet<double>> sub;
  int factorizations = 0;

  // One sub-problem min 1/2 lambda^T (H + eps I) lambda - (c + eps mu)^T lambda, lambda >= 0,
  // by projected Newton steps, warm-started from lambda. Returns false on budget or breakdown.
  std::vector<Eigen::Index> F;
  std::vector<char> in_f(static_cast<std::size_t>(m), 0), prev_f(static_cast<std::size_t>(m), 2);
  auto q_of = [&](const Eigen::VectorXd& l, const Eigen::VectorXd& y) { return 0.5 * y.squaredNorm() + 0.5 * eps * l.squaredNorm() - (P.c + eps * mu).dot(l); };
  auto inner = [&]() -> bool {
    while (true) {
      const Eigen::VectorXd y = ldp_primal(P, lambda);
      const Eigen::VectorXd g = ldp_slack(P, y) + eps * (lambda - mu);  // gradient of the sub-problem
      bool done = true;
      double pg = 0;
      const double noise = 4 * rounding * lambda.cwiseAbs().maxCoeff();  // rounding of g at this lambda
      for (Eigen::Index i = 0; i < m; ++i) {
        const double t = 0.125 * P.tol[i] + noise;
        done = done && (lambda[i] > 0 ? std::abs(g[i]) <= t : g[i] >= -t);
        pg = std::max(pg, std::abs(lambda[i] - std::max(0.0, lambda[i] - g[i])));
      }
      if (done) return true;
      // Bertsekas's active set: at (or within delta of) the bound with the gradient pushing there.
      const double delta = std::min(pg, 1e-3 * cmax);
      bool same = true;
      for (Eigen::Index i = 0; i < m; ++i) {
        in_f[static_cast<std::size_t>(i)] = !(lambda[i] <= delta && g[i] > 0);
        same = same && in_f[static_cast<std::size_t>(i)] == prev_f[static_cast<std::size_t>(i)];
      }
      if (++factorizations > opt.max_factorizations) return false;
      if (!same) {
        prev_f = in_f;
        F.clear();
        for (Eigen::Index i = 0; i < m; ++i)
          if (in_f[static_cast<std::size_t>(i)]) {
            pos[static_cast<std::size_t>(i)] = static_cast<Eigen::Index>(F.size());
            F.push_back(i);
          }
        if (!F.empty()) {
          const auto f = static_cast<Eigen::Index>(F.size());
          sub.clear();
          for (Eigen::Index k = 0; k < f; ++k) {
            const Eigen::Index j = F[static_cast<std::size_t>(k)];
            for (Eigen::SparseMatrix<double>::InnerIterator it(H, j); it; ++it) {
              const Eigen::Index i = it.row();
              if (i < j || !in_f[static_cast<std::size_t>(i)]) continue;  // lower triangle of F x F
              sub.emplace_back(pos[static_cast<std::size_t>(i)], k, it.value() + (i == j ? eps : 0.0));
            }
          }
          Eigen::SparseMatrix<double> K(f, f);
          K.setFromTriplets(sub.begin(), sub.end());
          ldlt.compute(K);
          if (ldlt.info() != Eigen::Success) return false;
        }
      }
      // The minimiser on the face {lambda_i = 0 off F}, then a projected search towards it.
      Eigen::VectorXd target = Eigen::VectorXd::Zero(m);
      if (!F.empty()) {
        const auto f = static_cast<Eigen::Index>(F.size());
        Eigen::VectorXd rhs(f);
        for (Eigen::Index k = 0; k < f; ++k) rhs[k] = P.c[F[static_cast<std::size_t>(k)]] + eps * mu[F[static_cast<std::size_t>(k)]];
        const Eigen::VectorXd lf = ldlt.solve(rhs);
        if (!lf.allFinite()) return false;
        for (Eigen::Index k = 0; k < f; ++k) target[F[static_cast<std::size_t>(k)]] = lf[k];
      }
      const Eigen::VectorXd d = target - lambda;
      const double q0 = q_of(lambda, y);
      double alpha = 1;
      bool moved = false;
      for (int ls = 0; ls < 40; ++ls, alpha *= 0.5) {
        const Eigen::VectorXd ln = (lambda + alpha * d).cwiseMax(0.0);
        const double qn = q_of(ln, ldp_primal(P, ln));
        if (qn <= q0 + 1e-4 * g.dot(ln - lambda) + 1e-14 * std::abs(q0)) {
          moved = (ln - lambda).cwiseAbs().maxCoeff() > 0;
          lambda = ln;
          break;
        }
      }
      if (!moved) return false;
    }
  };
  for (int outer = 0; outer <= 200; ++outer) {
    const bool ok = inner();
    lambda = lambda.cwiseMax(0.0);
    const Eigen::VectorXd y = ldp_primal(P, lambda);
    out.iterations = factorizations;
    out.status = ldp_outer_verdict(P, lambda, y, ok, rounding, opt.far);
    if (out.status == LdpStatus::Solved) out.lambda = lambda;
    if (out.status != LdpStatus::Failed || !ok) return out;
    mu = lambda;
  }
  return out;  // Failed: the proximal iteration does not settle
}

}  // namespace impact::detail
