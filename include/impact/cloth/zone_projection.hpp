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
///    variable y = M^(1/2) (x - xhat)); it is solved exactly, to convergence, through its
///    equivalent non-negative least-squares problem (Lawson and Hanson, "Solving Least Squares
///    Problems", 1974, chapter 23: LDP through NNLS), with the Lawson-Hanson active-set algorithm.
///    That algorithm ends after finitely many active-set changes, handles redundant and
///    degenerate constraints, and detects an infeasible zone (the residual of the NNLS is zero).
///    Cost: a dense m x m Gram matrix of the m constraints, then per active-set change a dense
///    Cholesky (LDLT) of the active block: fine for zones of up to a few hundred constraints.
///  - rigid_zone_motion (Provot 1997, "Collision and self-collision handling in cloth model
///    dedicated to design garments"; Bridson et al. 2002, section 7.4): the zone moves as one rigid
///    body with the linear and angular momentum of its vertices' step velocities.
/// Both work in double whatever the scalar of the step.
#pragma once

#include "impact/core/types.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/QR>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
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

struct ZoneProjectionOptions {
  int max_iterations = 500;    ///< active-set changes of the NNLS (each adds or drops one constraint)
  double tolerance = 1e-9;     ///< a constraint counts as met when violated by at most this (length)
};

struct ZoneProjectionResult {
  bool converged = false;       ///< every constraint met within the tolerance
  bool infeasible = false;      ///< no positions of the zone's movable vertices meet them all
  int iterations = 0;           ///< active-set changes
  int active = 0;               ///< constraints with a positive multiplier
  double max_violation = 0;     ///< largest b - a.x left (<= 0 when every constraint is met)
};

/// Projects the end positions of one zone (see the file comment). `inverse_mass[i]` for every
/// vertex index used (0 = infinite mass: such a vertex is a constant of the constraints and never
/// moves). `xhat` holds the positions to stay close to; `x` receives the result for the movable
/// vertices of the constraints (other rows of x are untouched). Rows are indexed by vertex id.
/// Returns converged == false (x unchanged) when the budget runs out or the zone is infeasible.
template <class InverseMass, class MatIn, class MatOut>
ZoneProjectionResult project_zone(const std::vector<ZoneConstraint>& cons, const InverseMass& inverse_mass, const MatIn& xhat, MatOut& x,
                                  const ZoneProjectionOptions& opt = {}) {
  ZoneProjectionResult res;
  const std::size_t m = cons.size();
  if (m == 0) {
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
  // Row c of G (unit after scaling) as sparse blocks, and the right-hand side c_c:
  // sum_k a_k n . (xhat_k + sqrt(w_k) y_k) >= b  <=>  g_c . y >= rhs_c.
  struct Row {
    int blk[4];
    Vec3<double> g[4];
    int nb = 0;
    double scale = 1;  // 1 / |g_c|
  };
  std::vector<Row> rows(m);
  Eigen::VectorXd rhs(static_cast<Eigen::Index>(m));
  double rhs_max = 0;
  for (std::size_t c = 0; c < m; ++c) {
    const auto& k = cons[c];
    double r = k.b, norm2 = 0;
    Row& row = rows[c];
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
    if (norm2 <= 0) {
      // Nothing movable: the constraint holds or it cannot be met.
      if (r > opt.tolerance) {
        res.infeasible = true;
        res.max_violation = std::max(res.max_violation, r);
        return res;
      }
      row.nb = 0;
      rhs[static_cast<Eigen::Index>(c)] = -1;  // never active
      continue;
    }
    row.scale = 1 / std::sqrt(norm2);
    for (int q = 0; q < row.nb; ++q) row.g[q] *= row.scale;
    rhs[static_cast<Eigen::Index>(c)] = r * row.scale;
    rhs_max = std::max(rhs_max, r * row.scale);
  }
  if (!(rhs_max > 0)) {  // xhat already meets every constraint
    res.converged = true;
    res.max_violation = 0;
    for (std::size_t c = 0; c < m; ++c)
      if (rows[c].nb > 0) res.max_violation = std::max(res.max_violation, rhs[static_cast<Eigen::Index>(c)] / rows[c].scale);
    return res;
  }
  const Eigen::VectorXd cvec = rhs / rhs_max;  // normalised: largest entry 1
  // Gram matrix of E = [G^T; c^T]: N = G G^T + c c^T (rows of G are sparse).
  const auto M = static_cast<Eigen::Index>(m);
  Eigen::MatrixXd N = cvec * cvec.transpose();
  {
    std::vector<std::vector<std::pair<int, int>>> by_block(verts.size());  // (constraint, slot)
    for (std::size_t c = 0; c < m; ++c)
      for (int q = 0; q < rows[c].nb; ++q) by_block[static_cast<std::size_t>(rows[c].blk[q])].push_back({static_cast<int>(c), q});
    for (const auto& list : by_block)
      for (const auto& [ci, qi] : list)
        for (const auto& [cj, qj] : list) N(ci, cj) += rows[static_cast<std::size_t>(ci)].g[qi].dot(rows[static_cast<std::size_t>(cj)].g[qj]);
  }
  // Lawson-Hanson NNLS: min |E u - f|^2, u >= 0, f = e_last; E^T f = c, E^T E = N.
  Eigen::VectorXd u = Eigen::VectorXd::Zero(M), z(M);
  std::vector<char> passive(m, 0);
  const double kkt_tol = 1e-13 * static_cast<double>(M);
  auto solve_passive = [&](Eigen::VectorXd& out) {
    std::vector<Eigen::Index> P;
    for (Eigen::Index i = 0; i < M; ++i)
      if (passive[static_cast<std::size_t>(i)]) P.push_back(i);
    const auto p = static_cast<Eigen::Index>(P.size());
    Eigen::MatrixXd NP(p, p);
    Eigen::VectorXd cP(p);
    for (Eigen::Index i = 0; i < p; ++i) {
      cP[i] = cvec[P[static_cast<std::size_t>(i)]];
      for (Eigen::Index j = 0; j < p; ++j) NP(i, j) = N(P[static_cast<std::size_t>(i)], P[static_cast<std::size_t>(j)]);
    }
    Eigen::VectorXd zp = Eigen::LDLT<Eigen::MatrixXd>(NP).solve(cP);
    if (!zp.allFinite()) zp = NP.completeOrthogonalDecomposition().solve(cP);
    out.setZero();
    for (Eigen::Index i = 0; i < p; ++i) out[P[static_cast<std::size_t>(i)]] = zp[i];
  };
  int it = 0;
  bool budget = true;
  while (true) {
    const Eigen::VectorXd wgrad = cvec - N * u;
    Eigen::Index best = -1;
    double best_w = kkt_tol;
    for (Eigen::Index i = 0; i < M; ++i)
      if (!passive[static_cast<std::size_t>(i)] && wgrad[i] > best_w) {
        best_w = wgrad[i];
        best = i;
      }
    if (best < 0) break;
    if (++it > opt.max_iterations) {
      budget = false;
      break;
    }
    passive[static_cast<std::size_t>(best)] = 1;
    bool added_ok = false;
    for (int inner = 0; inner < 4 * static_cast<int>(m) + 8; ++inner) {
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
  res.iterations = it;
  const double denom = 1 - cvec.dot(u);  // last residual component is c.u - 1
  if (!(denom > 1e-12)) {
    res.infeasible = true;
    return res;
  }
  // lambda (scaled rows) = u / denom * rhs_max; positions x = xhat + W A^T lambda.
  std::vector<Vec3<double>> dx(verts.size(), Vec3<double>::Zero());
  for (std::size_t c = 0; c < m; ++c) {
    const double lam = u[static_cast<Eigen::Index>(c)] / denom * rhs_max * rows[c].scale;
    if (!(lam > 0)) continue;
    ++res.active;
    const auto& k = cons[c];
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
  res.converged = budget && viol <= opt.tolerance;
  if (!res.converged) return res;
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
