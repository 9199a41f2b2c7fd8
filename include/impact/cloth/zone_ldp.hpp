// SPDX-License-Identifier: MIT
/// \file
/// The least-distance programme (LDP) of one impact zone, and its dense solver.
/// project_zone (cloth/zone_projection.hpp) turns a zone's constraints into
///     min |y|^2  subject to  g_i . y >= c_i  (i < m),   |g_i| = 1,
/// with y = M^(1/2) (x - xhat) over the zone's movable vertices (3 unknowns each): each row g_i
/// has at most four non-zero 3-blocks, one per vertex of its collision. The solution is
/// y = sum_i lambda_i g_i with lambda >= 0 (KKT: g_i . y >= c_i, lambda_i (g_i . y - c_i) = 0).
/// Three solvers return that lambda:
///  - solve_ldp_dense (here): LDP through non-negative least squares (Lawson and Hanson,
///    "Solving Least Squares Problems", 1974, chapter 23) with the Lawson-Hanson active-set
///    algorithm: finitely many active-set changes, redundant and degenerate rows handled, an
///    infeasible problem detected by the NNLS residual. Cost: a dense m x m Gram matrix, then a
///    dense LDLT of the active block per active-set change (one row added or dropped at a time):
///    O(m^2) memory and up to O(m^4) time, the better tool for small zones;
///  - solve_ldp_sparse (cloth/zone_ldp_sparse.hpp, projected Newton on the dual) and
///    solve_ldp_primal (cloth/zone_ldp_primal.hpp, semismooth Newton on an augmented
///    Lagrangian of the primal): a sparse LDLT per iteration, for large zones.
/// The three solvers (and the primal one's Newton system) are templates, always used with
/// ZoneLdp, only so that Eigen's factorisations are instantiated in the files that call them: as
/// inline functions they cost every file including a cloth header about 7 s of compile time.
/// Internals of the cloth layer (namespace impact::detail).
#pragma once

#include "impact/core/types.hpp"

#include <Eigen/Cholesky>
#include <Eigen/QR>

#include <algorithm>
#include <cstddef>
#include <vector>

namespace impact::detail {

/// One unit row of an LDP: blocks blk[0..nb) (movable-vertex indices) with 3-vectors g[0..nb).
struct LdpRow {
  int blk[4] = {-1, -1, -1, -1};
  Vec3<double> g[4];
  int nb = 0;
};

/// min |y|^2 subject to rows[i] . y >= c[i]; y has 3 * blocks entries. Every row has unit norm
/// and at least one block. tol[i] > 0 is row i's tolerance on g_i . y - c_i (the caller's
/// length tolerance times the row's scale).
struct ZoneLdp {
  int blocks = 0;
  std::vector<LdpRow> rows;
  Eigen::VectorXd c, tol;
};

enum class LdpStatus {
  Solved,      ///< lambda meets the KKT conditions (within the solver's contract)
  Infeasible,  ///< no y meets every row (see each solver for the certificate)
  Failed,      ///< iteration budget spent or numerical breakdown: no verdict
};

struct LdpSolution {
  LdpStatus status = LdpStatus::Failed;
  Eigen::VectorXd lambda;  ///< >= 0, one per row (valid when Solved)
  int iterations = 0;      ///< dense: active-set changes; sparse: factorizations
};

/// y = sum_i lambda_i g_i (3 * blocks entries).
inline Eigen::VectorXd ldp_primal(const ZoneLdp& P, const Eigen::VectorXd& lambda) {
  Eigen::VectorXd y = Eigen::VectorXd::Zero(3 * static_cast<Eigen::Index>(P.blocks));
  for (std::size_t i = 0; i < P.rows.size(); ++i) {
    const double l = lambda[static_cast<Eigen::Index>(i)];
    if (l == 0) continue;
    const LdpRow& r = P.rows[i];
    for (int q = 0; q < r.nb; ++q) y.segment<3>(3 * static_cast<Eigen::Index>(r.blk[q])) += l * r.g[q];
  }
  return y;
}

/// g_i . y - c_i for every row (>= 0: met).
inline Eigen::VectorXd ldp_slack(const ZoneLdp& P, const Eigen::VectorXd& y) {
  Eigen::VectorXd w(static_cast<Eigen::Index>(P.rows.size()));
  for (std::size_t i = 0; i < P.rows.size(); ++i) {
    const LdpRow& r = P.rows[i];
    double s = 0;
    for (int q = 0; q < r.nb; ++q) s += r.g[q].dot(y.segment<3>(3 * static_cast<Eigen::Index>(r.blk[q])));
    w[static_cast<Eigen::Index>(i)] = s - P.c[static_cast<Eigen::Index>(i)];
  }
  return w;
}

/// The rounding bound of the sparse solvers: |fl(G^T lambda) - G^T lambda| <= rounding * sum_i
/// lambda_i, from (deg + 1) u sum_i lambda_i |g_i|_1 with |g_i|_1 <= sqrt(12), deg the largest
/// number of rows on one block.
inline double ldp_rounding(const ZoneLdp& P) {
  std::vector<int> deg(static_cast<std::size_t>(P.blocks), 0);
  int dmax = 0;
  for (const auto& r : P.rows)
    for (int q = 0; q < r.nb; ++q) dmax = std::max(dmax, ++deg[static_cast<std::size_t>(r.blk[q])]);
  return 4 * static_cast<double>(dmax + 1) * 1.2e-16;
}

/// The sparse solvers' verdict after one outer iteration reached lambda (>= 0) and y = G^T lambda.
/// Solved: the inner iteration converged and the KKT conditions hold to a quarter of each row's
/// tolerance (g_i . y - c_i >= -t_i / 4, and <= t_i / 4 where lambda_i > 0). Infeasible: weak
/// duality proves every feasible y longer than far * max c_i, with the rounding of y included
/// (`rounding` from ldp_rounding). Failed: no verdict yet (the caller iterates on when `converged`,
/// gives up otherwise).
inline LdpStatus ldp_outer_verdict(const ZoneLdp& P, const Eigen::VectorXd& lambda, const Eigen::VectorXd& y,
                                   bool converged, double rounding, double far) {
  if (converged) {
    const Eigen::VectorXd w = ldp_slack(P, y);
    bool kkt = true;
    for (Eigen::Index i = 0; i < w.size() && kkt; ++i)
      kkt = w[i] >= -0.25 * P.tol[i] && (lambda[i] == 0 || w[i] <= 0.25 * P.tol[i]);
    if (kkt) return LdpStatus::Solved;
  }
  const double num = P.c.dot(lambda) - P.tol.dot(lambda);
  const double den = y.norm() + rounding * lambda.sum();
  if (num > 0 && num > far * P.c.maxCoeff() * den) return LdpStatus::Infeasible;
  return LdpStatus::Failed;
}

/// Lawson-Hanson LDP through NNLS (see the file comment). `max_changes` bounds the active-set
/// changes (each adds or drops one row). Infeasible when the NNLS residual vanishes (relative
/// 1e-12). Solved means the NNLS's own optimality test passed; the caller checks the rows.
template <class Ldp = ZoneLdp>
LdpSolution solve_ldp_dense(const Ldp& P, int max_changes) {
  LdpSolution out;
  const auto M = static_cast<Eigen::Index>(P.rows.size());
  out.lambda = Eigen::VectorXd::Zero(M);
  const double rhs_max = M > 0 ? P.c.maxCoeff() : 0.0;
  if (!(rhs_max > 0)) {  // y = 0 meets every row
    out.status = LdpStatus::Solved;
    return out;
  }
  const Eigen::VectorXd cvec = P.c / rhs_max;  // normalised: largest entry 1
  // Gram matrix of E = [G^T; c^T]: N = G G^T + c c^T (rows of G are sparse).
  Eigen::MatrixXd N = cvec * cvec.transpose();
  {
    std::vector<std::vector<std::pair<int, int>>> by_block(static_cast<std::size_t>(P.blocks));  // (row, slot)
    for (Eigen::Index c = 0; c < M; ++c)
      for (int q = 0; q < P.rows[static_cast<std::size_t>(c)].nb; ++q)
        by_block[static_cast<std::size_t>(P.rows[static_cast<std::size_t>(c)].blk[q])].push_back({static_cast<int>(c), q});
    for (const auto& list : by_block)
      for (const auto& [ci, qi] : list)
        for (const auto& [cj, qj] : list) N(ci, cj) += P.rows[static_cast<std::size_t>(ci)].g[qi].dot(P.rows[static_cast<std::size_t>(cj)].g[qj]);
  }
  // Lawson-Hanson NNLS: min |E u - f|^2, u >= 0, f = e_last; E^T f = c, E^T E = N.
  Eigen::VectorXd u = Eigen::VectorXd::Zero(M), z(M);
  std::vector<char> passive(static_cast<std::size_t>(M), 0);
  const double kkt_tol = 1e-13 * static_cast<double>(M);
  auto solve_passive = [&](Eigen::VectorXd& res) {
    std::vector<Eigen::Index> Pi;
    for (Eigen::Index i = 0; i < M; ++i)
      if (passive[static_cast<std::size_t>(i)]) Pi.push_back(i);
    const auto p = static_cast<Eigen::Index>(Pi.size());
    Eigen::MatrixXd NP(p, p);
    Eigen::VectorXd cP(p);
    for (Eigen::Index i = 0; i < p; ++i) {
      cP[i] = cvec[Pi[static_cast<std::size_t>(i)]];
      for (Eigen::Index j = 0; j < p; ++j) NP(i, j) = N(Pi[static_cast<std::size_t>(i)], Pi[static_cast<std::size_t>(j)]);
    }
    Eigen::VectorXd zp = Eigen::LDLT<Eigen::MatrixXd>(NP).solve(cP);
    if (!zp.allFinite()) zp = NP.completeOrthogonalDecomposition().solve(cP);
    res.setZero();
    for (Eigen::Index i = 0; i < p; ++i) res[Pi[static_cast<std::size_t>(i)]] = zp[i];
  };
  int it = 0;
  while (true) {
    // c - N u over the columns where u is nonzero (only passive rows are): N is symmetric and
    // the passive set is mostly a small part of the rows.
    Eigen::VectorXd wgrad = cvec;
    for (Eigen::Index j = 0; j < M; ++j)
      if (u[j] != 0) wgrad -= u[j] * N.col(j);
    Eigen::Index best = -1;
    double best_w = kkt_tol;
    for (Eigen::Index i = 0; i < M; ++i)
      if (!passive[static_cast<std::size_t>(i)] && wgrad[i] > best_w) {
        best_w = wgrad[i];
        best = i;
      }
    if (best < 0) break;
    if (++it > max_changes) {
      out.iterations = it - 1;
      return out;  // Failed
    }
    passive[static_cast<std::size_t>(best)] = 1;
    bool added_ok = false;
    for (Eigen::Index inner = 0; inner < 4 * M + 8; ++inner) {
      solve_passive(z);
      bool all_pos = true;
      for (Eigen::Index i = 0; i < M; ++i)
        if (passive[static_cast<std::size_t>(i)] && !(z[i] > 0)) all_pos = false;
      if (all_pos) {
        u = z;
        added_ok = true;
        break;
      }
      double alpha = 1;
      for (Eigen::Index i = 0; i < M; ++i)
        if (passive[static_cast<std::size_t>(i)] && !(z[i] > 0)) alpha = std::min(alpha, u[i] / (u[i] - z[i]));
      u += alpha * (z - u);
      for (Eigen::Index i = 0; i < M; ++i)
        if (passive[static_cast<std::size_t>(i)] && u[i] <= 1e-15) {
          passive[static_cast<std::size_t>(i)] = 0;
          u[i] = 0;
        }
    }
    if (!added_ok) {  // numerically stuck: the entering column is dependent; drop it
      passive[static_cast<std::size_t>(best)] = 0;
      u[best] = 0;
      break;
    }
  }
  out.iterations = it;
  const double denom = 1 - cvec.dot(u);  // last residual component is c.u - 1
  if (!(denom > 1e-12)) {
    out.status = LdpStatus::Infeasible;
    return out;
  }
  out.lambda = (u / denom * rhs_max).cwiseMax(0.0);
  out.status = LdpStatus::Solved;
  return out;
}

}  // namespace impact::detail
