// SPDX-License-Identifier: MIT
/// \file
/// The two ways an impact zone is resolved in the cloth collision step:
///  - project_zone (Harmon, Vouga, Tamstorf, Grinspun 2008, "Robust treatment of simultaneous
///    collisions", section 4): the zone's end positions x are moved to the nearest point, in the
///    mass-weighted norm sum_i m_i |x_i - xhat_i|^2, of the set where every collision constraint
///    sum_k a_k n . x_{v_k} >= b of the zone holds. The change is M^-1 A^T lambda with lambda >= 0:
///    each constraint pushes its vertices with equal and opposite impulses along its normal, so
///    the zone's linear momentum is kept exactly, and its angular momentum too when each normal
///    is parallel to the constraint's relative vector sum_k a_k p_k at the configuration p where it
///    was linearised (the contact points' difference at the time of impact). Tangential motion is
///    changed only as far as the normals reach, so sliding survives.
///    Method: the problem is a least-distance programme (min |y|^2, G y >= c after the change of
///    variable y = M^(1/2) (x - xhat); cloth/zone_ldp.hpp), solved to convergence by one of
///    three solvers of its multipliers (ZoneSolver; Auto picks by the zone's constraint count m
///    and unknown count 3n, n movable vertices):
///     - dense (Auto: m <= dense_limit = 600): LDP through non-negative least squares with the
///       Lawson-Hanson active-set algorithm (Lawson and Hanson 1974, chapter 23): finitely many
///       active-set changes, redundant and degenerate constraints handled, infeasibility from the
///       NNLS residual. A dense m x m Gram matrix and a dense LDLT per active-set change: O(m^2)
///       memory, up to O(m^4) time (cloth/zone_ldp.hpp);
///     - sparse, m <= 3n: projected Newton on the dual with a proximal term, one sparse LDLT of
///       the free rows' block of A W A^T (m x m at most) per iteration (cloth/zone_ldp_sparse.hpp);
///     - sparse, m > 3n (dense self-contact: many redundant constraints on few vertices): an
///       augmented Lagrangian with semismooth Newton on the primal, one sparse LDLT of a
///       3n x 3n system per iteration (cloth/zone_ldp_primal.hpp); without a verdict it hands
///       over to the dense solver (Auto, after at most 200 steps, up to dense_fallback_limit
///       constraints) or to the dual one.
///    The sparse solvers change many active constraints per iteration, check the KKT conditions
///    row by row and certify infeasibility by weak duality; a sparse run without a verdict goes
///    to the dense solver up to dense_fallback_limit constraints. Whichever solver ran, the new
///    positions are rebuilt here from its multipliers (so the momentum argument above holds to
///    rounding) and every constraint is checked on them.
///  - rigid_zone_motion (Provot 1997, "Collision and self-collision handling in cloth model
///    dedicated to design garments"; Bridson et al. 2002, section 7.4): the zone moves as one rigid
///    body with the linear and angular momentum of its vertices' step velocities.
/// Both work in double whatever the scalar of the step.
#pragma once

#include "impact/cloth/zone_ldp.hpp"
#include "impact/cloth/zone_ldp_primal.hpp"
#include "impact/cloth/zone_ldp_sparse.hpp"
#include "impact/core/types.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <utility>
#include <unordered_map>
#include <vector>

namespace impact {

/// One linear constraint of a zone on end positions: sum_{k < count} a[k] (n . x_{v[k]}) >= b.
/// For a vertex-face collision v = (p, f0, f1, f2), a = (1, -w0, -w1, -w2) with the triangle
/// point's barycentric weights; for edge-edge v = (a0, a1, b0, b1), a = (1 - s, s, -(1 - t), -t).
/// n is a unit normal pointing from the second primitive to the first.
struct ZoneConstraint {
  std::int32_t v[4] = {-1, -1, -1, -1};
  double a[4] = {0, 0, 0, 0};
  int count = 4;
  Vec3<double> n = Vec3<double>::Zero();
  double b = 0;
};

/// Which solver project_zone uses for a zone's least-distance programme.
enum class ZoneSolver {
  /// Dense Lawson-Hanson up to `dense_limit` constraints, sparse above; a sparse run that ends
  /// without a verdict (budget, breakdown) is repeated densely up to `dense_fallback_limit`.
  Auto,
  Dense,   ///< Lawson-Hanson NNLS (cloth/zone_ldp.hpp): O(m^2) memory, up to O(m^4) time
  Sparse,  ///< sparse LDLT per iteration: dual (m <= 3n) or primal (m > 3n) Newton-type method
};

struct ZoneProjectionOptions {
  /// Iteration budget: active-set changes of the dense solver (each adds or drops one
  /// constraint); Newton steps of the sparse ones (each may change many).
  int max_iterations = 500;
  double tolerance = 1e-9;     ///< a constraint counts as met when violated by at most this (length)
  ZoneSolver solver = ZoneSolver::Auto;
  int dense_limit = 600;            ///< Auto: the dense solver up to this many constraints
  int dense_fallback_limit = 3000;  ///< Auto: a failed sparse run goes dense up to this many
};

struct ZoneProjectionResult {
  bool converged = false;       ///< every constraint met within the tolerance
  bool infeasible = false;      ///< no positions of the zone's movable vertices meet them all
  int iterations = 0;           ///< the budget used (see ZoneProjectionOptions::max_iterations)
  int active = 0;               ///< constraints with a positive multiplier
  double max_violation = 0;     ///< largest b - a.x left (<= 0 when every constraint is met)
  ZoneSolver solver = ZoneSolver::Dense;  ///< the solver whose answer was taken (Dense or Sparse)
  /// When converged: the multiplier of each constraint (input order; 0 for one with no movable
  /// vertex), x = xhat + W sum_c lambda_c sum_k a_k n_c e_{v_k}, lambda >= 0. Empty otherwise.
  std::vector<double> multipliers;
};

/// Projects the end positions of one zone (see the file comment). `inverse_mass[i]` for every
/// vertex index used (0 = infinite mass: such a vertex is a constant of the constraints and never
/// moves). `xhat` holds the positions to stay close to; `x` receives the result for the movable
/// vertices of the constraints (other rows of x are untouched). Rows are indexed by vertex id.
/// Returns converged == false (x unchanged) when the budget runs out or the zone is infeasible;
/// converged is decided on the new positions themselves (every constraint within the tolerance).
template <class InverseMass, class MatIn, class MatOut>
ZoneProjectionResult project_zone(const std::vector<ZoneConstraint>& cons, const InverseMass& inverse_mass, const MatIn& xhat, MatOut& x,
                                  const ZoneProjectionOptions& opt = {}) {
  ZoneProjectionResult res;
  if (cons.empty()) {
    res.converged = true;
    return res;
  }
  // Local numbering of the movable vertices.
  std::unordered_map<std::int32_t, int> local;
  std::vector<std::int32_t> verts;
  for (const auto& c : cons)
    for (int k = 0; k < c.count; ++k)
      if (static_cast<double>(inverse_mass[c.v[k]]) > 0 && !local.count(c.v[k])) {
        local.emplace(c.v[k], static_cast<int>(verts.size()));
        verts.push_back(c.v[k]);
      }
  auto pos = [&](std::int32_t v) { return Vec3<double>(double(xhat(v, 0)), double(xhat(v, 1)), double(xhat(v, 2))); };
  // The LDP: row c of G (unit after scaling), right-hand side and tolerance:
  // sum_k a_k n . (xhat_k + sqrt(w_k) y_k) >= b  <=>  g_c . y >= rhs_c. Constraints with no
  // movable vertex are constants: met, or the zone is infeasible.
  detail::ZoneLdp P;
  P.blocks = static_cast<int>(verts.size());
  std::vector<double> rhs, tol;
  std::vector<std::size_t> source;  // constraint of each LDP row
  std::vector<double> row_scale;
  for (std::size_t c = 0; c < cons.size(); ++c) {
    const auto& k = cons[c];
    double r = k.b, norm2 = 0;
    detail::LdpRow row;
    for (int j = 0; j < k.count; ++j) {
      r -= k.a[j] * k.n.dot(pos(k.v[j]));
      const double w = static_cast<double>(inverse_mass[k.v[j]]);
      if (w > 0) {
        const int l = local.at(k.v[j]);
        int slot = -1;
        for (int q = 0; q < row.nb; ++q)
          if (row.blk[q] == l) slot = q;
        if (slot < 0) {
          slot = row.nb++;
          row.blk[slot] = l;
          row.g[slot].setZero();
        }
        row.g[slot] += k.a[j] * std::sqrt(w) * k.n;
      }
    }
    for (int q = 0; q < row.nb; ++q) norm2 += row.g[q].squaredNorm();
    if (!(norm2 > 0)) {
      if (r > opt.tolerance) {  // nothing movable and violated
        res.infeasible = true;
        res.max_violation = std::max(res.max_violation, r);
        return res;
      }
      continue;
    }
    const double scale = 1 / std::sqrt(norm2);
    for (int q = 0; q < row.nb; ++q) row.g[q] *= scale;
    P.rows.push_back(row);
    rhs.push_back(r * scale);
    tol.push_back(opt.tolerance * scale);
    source.push_back(c);
    row_scale.push_back(scale);
  }
  P.c = Eigen::Map<const Eigen::VectorXd>(rhs.data(), static_cast<Eigen::Index>(rhs.size()));
  P.tol = Eigen::Map<const Eigen::VectorXd>(tol.data(), static_cast<Eigen::Index>(tol.size()));
  const auto m = static_cast<int>(P.rows.size());
  // Solve: dense or sparse, as the options say.
  detail::LdpSolution sol;
  const bool sparse = opt.solver == ZoneSolver::Sparse || (opt.solver == ZoneSolver::Auto && m > opt.dense_limit);
  if (sparse) {
    // The smaller linear system: m x m on the dual, 3n x 3n on the primal.
    res.solver = ZoneSolver::Sparse;
    // Auto: the primal solver gets at most 200 Newton steps (the twist runs' zones need up to
    // about 160) and then hands over to the dense solver when it may, not to the dual one (slow
    // on such zones).
    const bool dense_next = opt.solver == ZoneSolver::Auto && m <= opt.dense_fallback_limit;
    if (m > 3 * P.blocks) {
      detail::PrimalLdpOptions po;
      po.max_factorizations = dense_next ? std::min(opt.max_iterations, 200) : opt.max_iterations;
      sol = detail::solve_ldp_primal(P, po);
      res.iterations = sol.iterations;
    }
    if (m <= 3 * P.blocks || (sol.status == detail::LdpStatus::Failed && !dense_next)) {
      detail::SparseLdpOptions so;
      so.max_factorizations = opt.max_iterations;
      sol = detail::solve_ldp_sparse(P, so);
      res.iterations += sol.iterations;
    }
    if (sol.status == detail::LdpStatus::Failed && opt.solver == ZoneSolver::Auto && m <= opt.dense_fallback_limit) {
      sol = detail::solve_ldp_dense(P, opt.max_iterations);
      res.solver = ZoneSolver::Dense;
      res.iterations += sol.iterations;
    }
  } else {
    sol = detail::solve_ldp_dense(P, opt.max_iterations);
    res.solver = ZoneSolver::Dense;
    res.iterations = sol.iterations;
  }
  if (sol.status == detail::LdpStatus::Infeasible) {
    res.infeasible = true;
    return res;
  }
  if (sol.status != detail::LdpStatus::Solved) return res;
  // Positions x = xhat + W A^T lambda (lambda of the scaled rows times the row's scale).
  std::vector<Vec3<double>> dx(verts.size(), Vec3<double>::Zero());
  std::vector<double> multipliers(cons.size(), 0.0);
  for (std::size_t i = 0; i < P.rows.size(); ++i) {
    const double lam = sol.lambda[static_cast<Eigen::Index>(i)] * row_scale[i];
    if (!(lam > 0)) continue;
    multipliers[source[i]] = lam;
    ++res.active;
    const auto& k = cons[source[i]];
    for (int j = 0; j < k.count; ++j) {
      const double w = static_cast<double>(inverse_mass[k.v[j]]);
      if (w > 0) dx[static_cast<std::size_t>(local.at(k.v[j]))] += (w * k.a[j] * lam) * k.n;
    }
  }
  // Check every constraint on the new positions (as the caller will store them).
  auto newpos = [&](std::int32_t v) {
    const auto itl = local.find(v);
    return itl == local.end() ? pos(v) : Vec3<double>(pos(v) + dx[static_cast<std::size_t>(itl->second)]);
  };
  double viol = -std::numeric_limits<double>::infinity();
  for (const auto& k : cons) {
    double r = k.b;
    for (int j = 0; j < k.count; ++j) r -= k.a[j] * k.n.dot(newpos(k.v[j]));
    viol = std::max(viol, r);
  }
  res.max_violation = viol;
  res.converged = viol <= opt.tolerance;
  if (!res.converged) return res;
  res.multipliers = std::move(multipliers);
  for (std::size_t l = 0; l < verts.size(); ++l) {
    const Vec3<double> p = pos(verts[l]) + dx[l];
    for (int i = 0; i < 3; ++i) x(verts[l], i) = static_cast<typename MatOut::Scalar>(p[i]);
  }
  return res;
}

/// Rigid motion of a zone: the centre of mass, its displacement over the step, and the angular
/// velocity (per step) with which the zone turns about it.
struct RigidZoneMotion {
  Vec3<double> center0 = Vec3<double>::Zero();  ///< centre of mass at x0
  Vec3<double> velocity = Vec3<double>::Zero(); ///< displacement of the centre of mass over the step
  Vec3<double> omega = Vec3<double>::Zero();    ///< angular velocity (radians per step)
};

/// The rigid motion with the same linear momentum and angular momentum (about the centre of mass,
/// positions x0, velocities x1 - x0) as the zone's vertices `verts` (all of finite mass):
/// I omega = L with I the inertia tensor at x0; when I is singular (collinear or single points)
/// the least-norm omega (pseudo-inverse: no spin about an axis with no inertia). Zero angular
/// momentum gives exactly zero omega. x1 receives x0_c + velocity + R(omega) (x0_i - center0),
/// R the rotation by |omega| about omega (Rodrigues), for the rows in `verts`.
template <class InverseMass, class Mat0, class Mat1>
RigidZoneMotion rigid_zone_motion(const std::vector<std::int32_t>& verts, const InverseMass& inverse_mass, const Mat0& x0, Mat1& x1) {
  RigidZoneMotion r;
  double mass = 0;
  Vec3<double> c1 = Vec3<double>::Zero();
  auto row = [](const auto& X, std::int32_t v) { return Vec3<double>(double(X(v, 0)), double(X(v, 1)), double(X(v, 2))); };
  for (const auto v : verts) {
    const double m = 1 / static_cast<double>(inverse_mass[v]);
    mass += m;
    r.center0 += m * row(x0, v);
    c1 += m * row(x1, v);
  }
  r.center0 /= mass;
  c1 /= mass;
  r.velocity = c1 - r.center0;
  Mat3<double> I = Mat3<double>::Zero();
  Vec3<double> L = Vec3<double>::Zero();
  for (const auto v : verts) {
    const double m = 1 / static_cast<double>(inverse_mass[v]);
    const Vec3<double> p = row(x0, v) - r.center0;
    const Vec3<double> vel = row(x1, v) - row(x0, v) - r.velocity;
    L += m * p.cross(vel);
    I += m * (p.squaredNorm() * Mat3<double>::Identity() - p * p.transpose());
  }
  if (L.squaredNorm() > 0) {
    Eigen::SelfAdjointEigenSolver<Mat3<double>> es(I);
    const Vec3<double> ev = es.eigenvalues();
    const double cut = 1e-12 * std::max(ev.maxCoeff(), 0.0);
    Vec3<double> w = Vec3<double>::Zero();
    for (int k = 0; k < 3; ++k)
      if (ev[k] > cut && ev[k] > 0) {
        const Vec3<double> e = es.eigenvectors().col(k);
        w += e * (e.dot(L) / ev[k]);
      }
    r.omega = w;
  }
  const double th = r.omega.norm();
  Mat3<double> R = Mat3<double>::Identity();
  if (th > 0) R = Eigen::AngleAxis<double>(th, r.omega / th).toRotationMatrix();
  for (const auto v : verts) {
    const Vec3<double> p = r.center0 + r.velocity + R * (row(x0, v) - r.center0);
    for (int i = 0; i < 3; ++i) x1(v, i) = static_cast<typename Mat1::Scalar>(p[i]);
  }
  return r;
}

}  // namespace impact
