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
#include <Eigen/OrderingMethods>
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

/// The Newton system of the primal solver, K = I + sum_{i active} g_i g_i^T / eps (3n x 3n),
/// assembled directly in a fill-reducing order of its 3 x 3 vertex blocks and factorised by
/// Eigen's SimplicialLDLT without an ordering of its own. The order is the approximate minimum
/// degree order (Eigen's AMD) of the block graph (n nodes, an edge per pair of blocks sharing an
/// active row), a ninth of the scalar graph the factorisation would otherwise order, computed
/// for each matrix: an order kept from an earlier Newton step, or computed once on the pattern
/// of every row, costs far more fill than it saves (measured on zones of the layers scene at
/// 10^5 vertices: up to 30 times slower). The matrix is written straight into its permuted upper
/// triangle, the layout the factorisation reads (no triplets, no sorting, no transposition;
/// Eigen still copies it once per factorisation, as it does any input with NaturalOrdering<int>):
/// column 3B + v (B in the new order) holds rows 3A .. 3A + 2 of each coupled
/// block A < B in increasing order, then the diagonal block's rows 3B .. 3B + v.
template <class Ldp = ZoneLdp>
struct PrimalSystem {
  int nb = 0;
  std::vector<int> newidx;           ///< block -> its place in the order
  std::vector<int> col_off, col_adj;  ///< per (new) block B: the coupled blocks A < B, sorted (CSR)
  std::vector<int> stamp, outer;
  Eigen::SparseMatrix<double> K;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Upper, Eigen::NaturalOrdering<int>> ldlt;
  Eigen::VectorXd rhs;

  explicit PrimalSystem(int blocks) : nb(blocks), newidx(static_cast<std::size_t>(blocks)), stamp(static_cast<std::size_t>(blocks), -1) {
    for (int b = 0; b < nb; ++b) newidx[static_cast<std::size_t>(b)] = b;
  }

  /// col_off / col_adj: for each block B (indices mapped by `map`), the blocks A < B sharing a
  /// row with use(i) with it, sorted and unique (with `both`, the blocks A > B too).
  template <class Use>
  void couple(const Ldp& P, const Use& use, const std::vector<int>& map, bool both) {
    const auto nbs = static_cast<std::size_t>(nb);
    col_off.assign(nbs + 2, 0);
    auto each = [&](auto&& f) {
      for (std::size_t i = 0; i < P.rows.size(); ++i) {
        if (!use(i)) continue;
        const LdpRow& r = P.rows[i];
        for (int a = 0; a < r.nb; ++a)
          for (int b = a + 1; b < r.nb; ++b) {
            const int A = map[static_cast<std::size_t>(r.blk[a])], B = map[static_cast<std::size_t>(r.blk[b])];
            f(std::min(A, B), std::max(A, B));
            if (both) f(std::max(A, B), std::min(A, B));
          }
      }
    };
    each([&](int, int B) { ++col_off[static_cast<std::size_t>(B) + 2]; });
    for (std::size_t b = 2; b < col_off.size(); ++b) col_off[b] += col_off[b - 1];
    col_adj.resize(static_cast<std::size_t>(col_off.back()));
    each([&](int A, int B) { col_adj[static_cast<std::size_t>(col_off[static_cast<std::size_t>(B) + 1]++)] = A; });
    // now col_off[B] .. col_off[B + 1] holds B's list, duplicates included: drop them, sort, compact
    std::fill(stamp.begin(), stamp.end(), -1);
    int w = 0;
    for (std::size_t B = 0; B < nbs; ++B) {
      const int begin = col_off[B], end = col_off[B + 1], start = w;
      for (int k = begin; k < end; ++k) {
        const int A = col_adj[static_cast<std::size_t>(k)];
        if (stamp[static_cast<std::size_t>(A)] == static_cast<int>(B)) continue;
        stamp[static_cast<std::size_t>(A)] = static_cast<int>(B);
        col_adj[static_cast<std::size_t>(w++)] = A;
      }
      std::sort(col_adj.begin() + start, col_adj.begin() + w);
      col_off[B] = start;
    }
    col_off[nbs] = w;
    col_adj.resize(static_cast<std::size_t>(w));
  }

  /// newidx from the AMD order of the block graph of the rows with use(i).
  template <class Use>
  void order(const Ldp& P, const Use& use) {
    std::vector<int> id(static_cast<std::size_t>(nb));
    for (int b = 0; b < nb; ++b) id[static_cast<std::size_t>(b)] = b;
    couple(P, use, id, /*both=*/true);
    const auto nbs = static_cast<std::size_t>(nb);
    Eigen::SparseMatrix<double> G(nb, nb);  // the full symmetric pattern, with the diagonal
    G.resizeNonZeros(col_off[nbs] + nb);
    int p = 0;
    for (std::size_t B = 0; B < nbs; ++B) {
      G.outerIndexPtr()[B] = p;
      bool diag = false;
      for (int k = col_off[B]; k < col_off[B + 1]; ++k) {
        const int A = col_adj[static_cast<std::size_t>(k)];
        if (!diag && A > static_cast<int>(B)) G.innerIndexPtr()[p] = static_cast<int>(B), G.valuePtr()[p++] = 1, diag = true;
        G.innerIndexPtr()[p] = A, G.valuePtr()[p++] = 1;
      }
      if (!diag) G.innerIndexPtr()[p] = static_cast<int>(B), G.valuePtr()[p++] = 1;
    }
    G.outerIndexPtr()[nbs] = p;
    Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> perm;
    Eigen::AMDOrdering<int>()(G, perm);  // perm.indices()[k]: the block eliminated k-th
    if (perm.size() != nb) return;       // (no order: keep the one there is)
    for (int k = 0; k < nb; ++k) newidx[static_cast<std::size_t>(perm.indices()[k])] = k;
  }

  /// Assembles K for the rows with act[i] (inv_eps = 1 / eps) and factorises it. False on breakdown.
  bool factorize(const Ldp& P, const std::vector<char>& act, double inv_eps) {
    couple(P, [&](std::size_t i) { return act[i] != 0; }, newidx, /*both=*/false);
    const auto nbs = static_cast<std::size_t>(nb);
    const auto n = 3 * static_cast<Eigen::Index>(nb);
    K.resize(n, n);
    outer.assign(static_cast<std::size_t>(n) + 1, 0);
    for (std::size_t B = 0; B < nbs; ++B)
      for (int v = 0; v < 3; ++v) {
        const std::size_t col = 3 * B + static_cast<std::size_t>(v);
        outer[col + 1] = outer[col] + 3 * (col_off[B + 1] - col_off[B]) + v + 1;
      }
    K.resizeNonZeros(outer.back());
    std::copy(outer.begin(), outer.end(), K.outerIndexPtr());
    int* inner = K.innerIndexPtr();
    double* val = K.valuePtr();
    std::fill(val, val + outer.back(), 0.0);
    for (std::size_t B = 0; B < nbs; ++B)
      for (int v = 0; v < 3; ++v) {
        int p = outer[3 * B + static_cast<std::size_t>(v)];
        for (int k = col_off[B]; k < col_off[B + 1]; ++k)
          for (int u = 0; u < 3; ++u) inner[p++] = 3 * col_adj[static_cast<std::size_t>(k)] + u;
        for (int u = 0; u <= v; ++u) inner[p++] = 3 * static_cast<int>(B) + u;
        val[p - 1] = 1;  // the identity's diagonal entry comes last in its column
      }
    for (std::size_t i = 0; i < P.rows.size(); ++i) {
      if (!act[i]) continue;
      const LdpRow& r = P.rows[i];
      int nbk[4];
      for (int a = 0; a < r.nb; ++a) nbk[a] = newidx[static_cast<std::size_t>(r.blk[a])];
      for (int a = 0; a < r.nb; ++a)
        for (int b = 0; b < r.nb; ++b) {
          const int A = nbk[a], B = nbk[b];  // rows of block A, columns of block B, A <= B
          if (A > B) continue;
          int off = 0;  // place of A among B's coupled blocks
          const auto Bs = static_cast<std::size_t>(B);
          if (A != B) {
            const int* lo = col_adj.data() + col_off[Bs];
            const int* hi = col_adj.data() + col_off[Bs + 1];
            off = static_cast<int>(std::lower_bound(lo, hi, A) - lo);
          }
          for (int v = 0; v < 3; ++v) {
            const double gv = inv_eps * r.g[b][v];
            double* q = val + outer[3 * Bs + static_cast<std::size_t>(v)];
            if (A == B) {
              q += 3 * (col_off[Bs + 1] - col_off[Bs]);
              for (int u = 0; u <= v; ++u) q[u] += r.g[a][u] * gv;
            } else {
              q += 3 * off;
              for (int u = 0; u < 3; ++u) q[u] += r.g[a][u] * gv;
            }
          }
        }
    }
    ldlt.compute(K);
    return ldlt.info() == Eigen::Success;
  }

  /// K^-1 x (x and the result in the blocks' own order).
  Eigen::VectorXd solve(const Eigen::VectorXd& x) {
    rhs.resize(x.size());
    for (int b = 0; b < nb; ++b) rhs.segment<3>(3 * newidx[static_cast<std::size_t>(b)]) = x.segment<3>(3 * b);
    const Eigen::VectorXd sol = ldlt.solve(rhs);
    Eigen::VectorXd out(x.size());
    for (int b = 0; b < nb; ++b) out.segment<3>(3 * b) = sol.segment<3>(3 * newidx[static_cast<std::size_t>(b)]);
    return out;
  }
};

/// Solves the LDP `P` (see the file comment). Failed when the budget runs out or a
/// factorisation breaks down; Infeasible with the certificate above; Solved when the KKT
/// conditions hold to a quarter of each row's tolerance.
template <class Ldp = ZoneLdp>
LdpSolution solve_ldp_primal(const Ldp& P, const PrimalLdpOptions& opt = {}) {
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
  PrimalSystem<Ldp> sys(P.blocks);
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
      // Hessian I + sum_{active} g_i g_i^T / eps, gradient y - G^T lambda.
      sys.order(P, [&](std::size_t i) { return act[i] != 0; });
      if (!sys.factorize(P, act, inv_eps)) return false;
      const Eigen::VectorXd d = -sys.solve(grad);
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
