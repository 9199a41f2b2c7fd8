// SPDX-License-Identifier: MIT
// project_zone and rigid_zone_motion: momentum and angular momentum kept (1e-12 relative, the
// angular momentum about the configuration where the normals are taken), constraints met,
// optimality against the analytic single-constraint answer, zero angular velocity. Both solvers
// of the projection (dense Lawson-Hanson, sparse block principal pivoting) against an oracle
// written here: the KKT conditions checked on the returned positions and multipliers (feasible,
// multipliers >= 0, complementary, and the change rebuilt from the multipliers), the two
// solvers' objectives against each other on random small zones, duplicate and redundant
// constraints, infeasible zones, and zones of thousands of constraints (stacked grids of cloth
// vertices pressed against a floor and against each other), in double and float.
#include "impact/cloth/zone_projection.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

namespace {

using namespace impact;
using Mat = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;

struct Zone {
  Mat p;       // configuration where normals are taken (contact points' difference along n)
  Mat xhat;    // end positions to project
  Eigen::VectorXd w;
  std::vector<ZoneConstraint> cons;
};

// A random zone: n vertices, m vertex-face / edge-edge constraints among them, normals along the
// difference of the weighted points at p, targets above the current gaps (all violated).
Zone random_zone(int n, int m, std::mt19937& rng, bool with_pinned) {
  std::uniform_real_distribution<double> U(-1, 1), W(0.2, 1);
  Zone z;
  z.p.resize(n, 3), z.xhat.resize(n, 3), z.w.resize(n);
  for (int i = 0; i < n; ++i) {
    z.p.row(i) << U(rng), U(rng), U(rng);
    z.xhat.row(i) = z.p.row(i) + 0.1 * Eigen::RowVector3d(U(rng), U(rng), U(rng));
    z.w[i] = with_pinned && i == 0 ? 0.0 : 1 / (0.5 + W(rng));
  }
  std::uniform_int_distribution<int> V(0, n - 1);
  for (int c = 0; c < m; ++c) {
    ZoneConstraint k;
    int v[4];
    do {
      for (int& x : v) x = V(rng);
    } while (v[0] == v[1] || v[0] == v[2] || v[0] == v[3] || v[1] == v[2] || v[1] == v[3] || v[2] == v[3]);
    const bool ee = c % 2;
    const double s = W(rng) - 0.2, t = W(rng) - 0.2;
    if (ee) {
      k.a[0] = 1 - s, k.a[1] = s, k.a[2] = -(1 - t), k.a[3] = -t;
    } else {
      const double b1 = s * 0.5, b2 = t * 0.4;
      k.a[0] = 1, k.a[1] = -(1 - b1 - b2), k.a[2] = -b1, k.a[3] = -b2;
    }
    Vec3<double> d = Vec3<double>::Zero(), g = Vec3<double>::Zero();
    for (int j = 0; j < 4; ++j) k.v[j] = v[j], d += k.a[j] * z.p.row(v[j]).transpose();
    k.n = d.normalized();
    for (int j = 0; j < 4; ++j) g += k.a[j] * z.xhat.row(v[j]).transpose();
    k.b = k.n.dot(g) + 0.05 + 0.05 * W(rng);
    z.cons.push_back(k);
  }
  return z;
}

// The KKT conditions of min sum m_i |x_i - xhat_i|^2 s.t. a.x >= b, checked on the returned x
// and multipliers with this file's own arithmetic: the largest violation, the most negative
// multiplier, the largest gap of a constraint with a positive multiplier (complementarity), and
// the largest difference between m_i (x_i - xhat_i) and sum_c lambda_c a_k n_c (stationarity,
// relative to the largest impulse), infinite-mass rows unmoved (stationarity there is 0 change).
struct ZoneKkt {
  double violation = 0, min_lambda = 0, complementarity = 0, stationarity = 0;
};

template <class MatX, class MatH, class Wv>
ZoneKkt zone_kkt(const std::vector<ZoneConstraint>& cons, const Wv& w, const MatH& xhat, const MatX& x, const std::vector<double>& lambda) {
  ZoneKkt k;
  EXPECT_EQ(lambda.size(), cons.size());
  const Eigen::Index n = xhat.rows();
  Eigen::MatrixXd impulse = Eigen::MatrixXd::Zero(n, 3);
  auto row = [](const auto& X, int v) { return Vec3<double>(double(X(v, 0)), double(X(v, 1)), double(X(v, 2))); };
  for (std::size_t c = 0; c < cons.size() && c < lambda.size(); ++c) {
    const auto& z = cons[c];
    double g = 0;
    for (int j = 0; j < z.count; ++j) g += z.a[j] * z.n.dot(row(x, z.v[j]));
    k.violation = std::max(k.violation, z.b - g);
    k.min_lambda = std::min(k.min_lambda, lambda[c]);
    if (lambda[c] > 0) k.complementarity = std::max(k.complementarity, std::abs(g - z.b));
    for (int j = 0; j < z.count; ++j) impulse.row(z.v[j]) += (lambda[c] * z.a[j]) * z.n.transpose();
  }
  const double scale = std::max(impulse.cwiseAbs().maxCoeff(), 1e-300);
  for (Eigen::Index i = 0; i < n; ++i) {
    const Vec3<double> d = row(x, int(i)) - row(xhat, int(i));
    const double wi = double(w[i]);
    const double e = wi > 0 ? (d / wi - impulse.row(i).transpose()).norm() / scale : d.norm();
    k.stationarity = std::max(k.stationarity, e);
  }
  return k;
}

double zone_objective(const Zone& z, const Mat& x) {
  double f = 0;
  for (Eigen::Index i = 0; i < x.rows(); ++i)
    if (z.w[i] > 0) f += (x.row(i) - z.xhat.row(i)).squaredNorm() / z.w[i];
  return f;
}

ZoneProjectionOptions zone_solver_options(ZoneSolver s) {
  ZoneProjectionOptions o;
  o.solver = s;
  return o;
}

TEST(ZoneProjection, KeepsMomentumAndAngularMomentum) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 40; ++trial) {
    Zone z = random_zone(12, 6 + trial % 5, rng, false);
    Mat x = z.xhat;
    const auto r = project_zone(z.cons, z.w, z.xhat, x, zone_solver_options(trial % 2 ? ZoneSolver::Sparse : ZoneSolver::Dense));
    ASSERT_TRUE(r.converged) << trial;
    EXPECT_EQ(r.solver, trial % 2 ? ZoneSolver::Sparse : ZoneSolver::Dense);
    EXPECT_GT(r.active, 0);
    Vec3<double> P = Vec3<double>::Zero(), L = Vec3<double>::Zero();
    double scale = 0;
    for (int i = 0; i < x.rows(); ++i) {
      const Vec3<double> dv = (x.row(i) - z.xhat.row(i)).transpose() / z.w[i];
      P += dv;
      L += z.p.row(i).transpose().cross(dv);
      scale = std::max(scale, dv.norm());
    }
    EXPECT_LT(P.norm(), 1e-12 * scale) << trial;
    EXPECT_LT(L.norm(), 1e-12 * scale) << trial;
    for (const auto& k : z.cons) {
      double g = 0;
      for (int j = 0; j < 4; ++j) g += k.a[j] * k.n.dot(x.row(k.v[j]).transpose());
      EXPECT_GE(g, k.b - 1e-9);
    }
  }
}

TEST(ZoneProjection, SingleConstraintMatchesTheAnalyticProjection) {
  for (const auto solver : {ZoneSolver::Dense, ZoneSolver::Sparse}) {
    std::mt19937 rng(5);
    Zone z = random_zone(4, 1, rng, false);
    Mat x = z.xhat;
    ASSERT_TRUE(project_zone(z.cons, z.w, z.xhat, x, zone_solver_options(solver)).converged);
    const auto& k = z.cons[0];
    double g = 0, den = 0;
    for (int j = 0; j < 4; ++j) g += k.a[j] * k.n.dot(z.xhat.row(k.v[j]).transpose()), den += k.a[j] * k.a[j] * z.w[k.v[j]];
    const double lam = (k.b - g) / den;
    for (int j = 0; j < 4; ++j) {
      const Eigen::RowVector3d expect = z.xhat.row(k.v[j]) + (z.w[k.v[j]] * k.a[j] * lam) * k.n.transpose();
      EXPECT_LT((x.row(k.v[j]) - expect).norm(), 1e-13);
    }
  }
}

TEST(ZoneProjection, SatisfiedConstraintsChangeNothingAndPinnedStay) {
  for (const auto solver : {ZoneSolver::Dense, ZoneSolver::Sparse}) {
    std::mt19937 rng(7);
    Zone z = random_zone(10, 8, rng, true);
    for (auto& k : z.cons) k.b -= 10;  // all met
    Mat x = z.xhat;
    const auto r = project_zone(z.cons, z.w, z.xhat, x, zone_solver_options(solver));
    EXPECT_TRUE(r.converged);
    EXPECT_EQ(r.active, 0);
    EXPECT_TRUE(x == z.xhat);
    for (auto& k : z.cons) k.b += 10;
    const auto r2 = project_zone(z.cons, z.w, z.xhat, x, zone_solver_options(solver));
    EXPECT_TRUE(r2.converged);
    EXPECT_GT(r2.active, 0);
    EXPECT_TRUE(x.row(0) == z.xhat.row(0));  // infinite mass
  }
}

TEST(ZoneProjection, DetectsAnInfeasibleZone) {
  for (const auto solver : {ZoneSolver::Dense, ZoneSolver::Sparse}) {
    // One free vertex pushed both up past 1 and down below -1 against pinned points.
    Mat p(3, 3);
    p << 0, 0, 0, 0, 0, 5, 0, 0, -5;
    Eigen::VectorXd w(3);
    w << 1, 0, 0;
    ZoneConstraint up, down;
    up.count = down.count = 2;
    up.v[0] = 0, up.v[1] = 2, up.a[0] = 1, up.a[1] = -1, up.n = Vec3<double>(0, 0, 1), up.b = 6;    // z0 >= 1
    down.v[0] = 0, down.v[1] = 1, down.a[0] = 1, down.a[1] = -1, down.n = Vec3<double>(0, 0, -1), down.b = 4;  // -z0 + 5 >= 4: z0 <= 1, feasible only at z0 = 1
    Mat x = p;
    auto r = project_zone(std::vector<ZoneConstraint>{up, down}, w, p, x, zone_solver_options(solver));
    EXPECT_TRUE(r.converged);
    EXPECT_NEAR(x(0, 2), 1.0, 1e-9);
    down.b = 4.5;  // z0 <= 0.5 and z0 >= 1
    x = p;
    r = project_zone(std::vector<ZoneConstraint>{up, down}, w, p, x, zone_solver_options(solver));
    EXPECT_FALSE(r.converged);
    EXPECT_TRUE(r.infeasible);
    EXPECT_TRUE(x == p);
  }
}

// Random small zones: the sparse solver's answer meets the KKT conditions and has the dense
// solver's objective (both are the unique optimum: the objective is strictly convex).
TEST(ZoneProjection, SparseMatchesDenseOnRandomZones) {
  std::mt19937 rng(23);
  int compared = 0;
  for (int trial = 0; trial < 150; ++trial) {
    Zone z = random_zone(6 + trial % 15, 3 + trial % 28, rng, trial % 3 == 0);
    Mat xd = z.xhat, xs = z.xhat;
    const auto rd = project_zone(z.cons, z.w, z.xhat, xd, zone_solver_options(ZoneSolver::Dense));
    const auto rs = project_zone(z.cons, z.w, z.xhat, xs, zone_solver_options(ZoneSolver::Sparse));
    ASSERT_EQ(rd.converged, rs.converged) << trial;
    ASSERT_EQ(rd.infeasible, rs.infeasible) << trial;
    if (!rs.converged) continue;
    ++compared;
    for (const auto* r : {&rd, &rs}) {
      const auto k = zone_kkt(z.cons, z.w, z.xhat, r == &rd ? xd : xs, r->multipliers);
      EXPECT_LE(k.violation, 1e-9) << trial;
      EXPECT_GE(k.min_lambda, 0.0) << trial;
      EXPECT_LE(k.complementarity, 1e-9) << trial;
      EXPECT_LE(k.stationarity, 1e-12) << trial;
    }
    const double fd = zone_objective(z, xd), fs = zone_objective(z, xs);
    EXPECT_NEAR(fs, fd, 1e-8 * fd) << trial;
    EXPECT_LT((xs - xd).cwiseAbs().maxCoeff(), 1e-7) << trial;
  }
  EXPECT_GT(compared, 140);
}

// Exact duplicates, near duplicates (normal turned by 1e-10) and implied constraints (copies with
// a smaller b) leave the feasible set as it was: same optimum, both solvers, no breakdown.
TEST(ZoneProjection, DuplicateAndRedundantConstraints) {
  std::mt19937 rng(31);
  for (int trial = 0; trial < 30; ++trial) {
    Zone z = random_zone(10, 8, rng, trial % 2 == 0);
    Mat x0 = z.xhat;
    ASSERT_TRUE(project_zone(z.cons, z.w, z.xhat, x0, zone_solver_options(ZoneSolver::Dense)).converged);
    const double f0 = zone_objective(z, x0);
    Zone d = z;
    for (const auto& k : z.cons) {
      d.cons.push_back(k);  // exact duplicate
      ZoneConstraint weaker = k;
      weaker.b -= 0.01;
      d.cons.push_back(weaker);
      weaker.b -= 0.01;
      d.cons.push_back(weaker);
    }  // 33 constraints on at most 30 unknowns: the sparse solver's primal path
    ZoneConstraint near = z.cons[0];
    near.n = (near.n + Vec3<double>(1e-10, -1e-10, 0)).normalized();
    d.cons.push_back(near);
    for (const auto solver : {ZoneSolver::Dense, ZoneSolver::Sparse}) {
      Mat x = d.xhat;
      const auto r = project_zone(d.cons, d.w, d.xhat, x, zone_solver_options(solver));
      ASSERT_TRUE(r.converged) << trial;
      const auto k = zone_kkt(d.cons, d.w, d.xhat, x, r.multipliers);
      EXPECT_LE(k.violation, 1e-9) << trial;
      EXPECT_GE(k.min_lambda, 0.0) << trial;
      EXPECT_LE(k.complementarity, 1e-9) << trial;
      EXPECT_LE(k.stationarity, 1e-12) << trial;
      EXPECT_NEAR(zone_objective(d, x), f0, 1e-6 * f0) << trial;
    }
  }
}

// A stack of `layers` square grids of (cells + 1)^2 cloth vertices, spacing 1 cm, `gap` apart at
// the configuration p where the normals are taken, pressed together at xhat (half the gap, with
// noise): each vertex above the bottom layer against the triangle below it (vertex-face), each
// cell's diagonal against the crossing diagonal below (edge-edge, nearly redundant with the
// vertex-face ones), and with `floor` the bottom layer against an immovable floor triangle
// (and with `ceiling_at` > 0 the top layer under an immovable ceiling at that height). Targets:
// the gap. Normals: the contact points' difference at p (so the angular momentum about p is kept).
struct ZoneStack {
  Mat p, xhat;
  Eigen::VectorXd w;
  std::vector<ZoneConstraint> cons;
};

ZoneStack pressed_stack(int cells, int layers, bool floor, double ceiling_at, std::mt19937& rng) {
  const int side = cells + 1, per = side * side;
  const double s = 0.01, gap = 0.004;
  std::uniform_real_distribution<double> U(-1, 1), W(0.5, 2);
  ZoneStack z;
  const int fixed = 6;  // floor triangle, ceiling triangle
  const int n = layers * per + fixed;
  z.p.resize(n, 3), z.xhat.resize(n, 3), z.w.resize(n);
  auto id = [&](int l, int i, int j) { return l * per + i * side + j; };
  for (int l = 0; l < layers; ++l)
    for (int i = 0; i < side; ++i)
      for (int j = 0; j < side; ++j) {
        const int v = id(l, i, j);
        z.p.row(v) << i * s + 0.2 * s * U(rng), j * s + 0.2 * s * U(rng), l * gap;
        z.xhat.row(v) = z.p.row(v);
        z.xhat(v, 2) = 0.5 * l * gap + 0.2 * gap * U(rng) + 0.5 * gap;
        z.w[v] = 1 / W(rng);
      }
  const double big = 10 * s * side;
  const int f0 = layers * per, c0 = f0 + 3;
  z.p.row(f0) << -big, -big, -gap;
  z.p.row(f0 + 1) << 3 * big, -big, -gap;
  z.p.row(f0 + 2) << -big, 3 * big, -gap;
  const double top = ceiling_at > 0 ? ceiling_at : layers * gap + 1;
  z.p.row(c0) << -big, -big, top;
  z.p.row(c0 + 1) << -big, 3 * big, top;
  z.p.row(c0 + 2) << 3 * big, -big, top;
  for (int v = f0; v < n; ++v) z.xhat.row(v) = z.p.row(v), z.w[v] = 0;
  auto add = [&](const int (&v)[4], const double (&a)[4]) {
    ZoneConstraint k;
    Vec3<double> d = Vec3<double>::Zero();
    for (int j = 0; j < 4; ++j) k.v[j] = v[j], k.a[j] = a[j], d += a[j] * z.p.row(v[j]).transpose();
    k.n = d.normalized();
    k.b = gap;
    z.cons.push_back(k);
  };
  // Barycentric weights of (x, y) in the triangle (q0, q1, q2) of p, projected on the plane.
  auto bary = [&](const Eigen::RowVector3d& q, int t0, int t1, int t2, double (&b)[3]) {
    const Eigen::Vector2d e1 = (z.p.row(t1) - z.p.row(t0)).head<2>().transpose(), e2 = (z.p.row(t2) - z.p.row(t0)).head<2>().transpose();
    const Eigen::Vector2d r = (q - z.p.row(t0)).head<2>().transpose();
    Eigen::Matrix2d E;
    E << e1, e2;
    const Eigen::Vector2d uv = E.inverse() * r;
    b[0] = 1 - uv[0] - uv[1], b[1] = uv[0], b[2] = uv[1];
  };
  for (int l = 0; l < layers; ++l)
    for (int i = 0; i < side; ++i)
      for (int j = 0; j < side; ++j) {
        const int v = id(l, i, j);
        if (l == 0 && floor) {
          double b[3];
          bary(z.p.row(v), f0, f0 + 1, f0 + 2, b);
          add({v, f0, f0 + 1, f0 + 2}, {1, -b[0], -b[1], -b[2]});
        }
        if (l == layers - 1 && ceiling_at > 0) {
          double b[3];
          bary(z.p.row(v), c0, c0 + 1, c0 + 2, b);
          add({c0, c0 + 1, c0 + 2, v}, {b[0], b[1], b[2], -1});  // ceiling point above v
        }
        if (l > 0) {
          // the triangle of the cell below containing (x, y) (clamped to the grid)
          const int ci = std::min(std::max(i, 0), cells - 1), cj = std::min(std::max(j, 0), cells - 1);
          const int t0 = id(l - 1, ci, cj), t1 = id(l - 1, ci + 1, cj), t2 = id(l - 1, ci, cj + 1), t3 = id(l - 1, ci + 1, cj + 1);
          double b[3];
          bary(z.p.row(v), t0, t1, t2, b);
          if (b[0] < 0) bary(z.p.row(v), t3, t2, t1, b), add({v, t3, t2, t1}, {1, -b[0], -b[1], -b[2]});
          else add({v, t0, t1, t2}, {1, -b[0], -b[1], -b[2]});
          if (i < cells && j < cells) {  // diagonal (i,j)-(i+1,j+1) over the anti-diagonal below
            add({id(l, i, j), id(l, i + 1, j + 1), id(l - 1, i + 1, j), id(l - 1, i, j + 1)}, {0.5, 0.5, -0.5, -0.5});
          }
        }
      }
  return z;
}

TEST(ZoneProjection, LargePressedStackConverges) {
  std::mt19937 rng(41);
  const auto z = pressed_stack(20, 4, true, 0, rng);
  ASSERT_GT(z.cons.size(), 2500u);
  Mat x = z.xhat;
  ZoneProjectionOptions o;
  o.tolerance = 1e-9;
  const auto r = project_zone(z.cons, z.w, z.xhat, x, o);  // Auto: sparse at this size
  ASSERT_TRUE(r.converged);
  EXPECT_EQ(r.solver, ZoneSolver::Sparse);
  EXPECT_LT(r.iterations, 60);
  EXPECT_GT(r.active, 500);
  const auto k = zone_kkt(z.cons, z.w, z.xhat, x, r.multipliers);
  EXPECT_LE(k.violation, 1e-9);
  EXPECT_GE(k.min_lambda, 0.0);
  EXPECT_LE(k.complementarity, 1e-9);
  EXPECT_LE(k.stationarity, 1e-12);
  // the floor and ceiling never move
  for (Eigen::Index v = x.rows() - 6; v < x.rows(); ++v) EXPECT_TRUE(x.row(v) == z.xhat.row(v));
}

// Many redundant constraints on few vertices (as dense self-contact accumulates them over the
// zone stage's rounds): every constraint of a stacked zone four times, the copies weaker by up to
// a tenth of the gap. m > 3n, so the sparse solver takes its primal path; the optimum is the one
// of the original constraints alone (m < 3n: its dual path), and the KKT conditions hold.
TEST(ZoneProjection, RedundantLargeZoneMatchesItsCore) {
  std::mt19937 rng(59);
  const auto z = pressed_stack(10, 3, true, 0, rng);
  ZoneStack many = z;
  std::uniform_real_distribution<double> U(0, 1e-4);
  for (int copy = 0; copy < 3; ++copy)
    for (const auto& k : z.cons) {
      ZoneConstraint weaker = k;
      weaker.b -= U(rng) * (copy > 0);
      many.cons.push_back(weaker);
    }
  ASSERT_GT(many.cons.size(), 3 * 363u);
  ASSERT_LT(z.cons.size(), 3 * 363u);
  Mat x1 = z.xhat, x2 = z.xhat;
  const auto r1 = project_zone(z.cons, z.w, z.xhat, x1, zone_solver_options(ZoneSolver::Sparse));
  const auto r2 = project_zone(many.cons, many.w, many.xhat, x2, zone_solver_options(ZoneSolver::Sparse));
  ASSERT_TRUE(r1.converged);
  ASSERT_TRUE(r2.converged);
  const auto k = zone_kkt(many.cons, many.w, many.xhat, x2, r2.multipliers);
  EXPECT_LE(k.violation, 1e-9);
  EXPECT_GE(k.min_lambda, 0.0);
  EXPECT_LE(k.complementarity, 1e-9);
  EXPECT_LE(k.stationarity, 1e-12);
  auto objective = [&](const Mat& x) {
    double f = 0;
    for (Eigen::Index i = 0; i < x.rows(); ++i)
      if (z.w[i] > 0) f += (x.row(i) - z.xhat.row(i)).squaredNorm() / z.w[i];
    return f;
  };
  EXPECT_NEAR(objective(x2), objective(x1), 1e-6 * objective(x1));
  EXPECT_LT((x2 - x1).cwiseAbs().maxCoeff(), 1e-6);
}

TEST(ZoneProjection, LargeFreeStackKeepsMomentum) {
  std::mt19937 rng(43);
  const auto z = pressed_stack(16, 3, false, 0, rng);
  Mat x = z.xhat;
  const auto r = project_zone(z.cons, z.w, z.xhat, x, zone_solver_options(ZoneSolver::Sparse));
  ASSERT_TRUE(r.converged);
  EXPECT_EQ(r.solver, ZoneSolver::Sparse);
  Vec3<double> P = Vec3<double>::Zero(), L = Vec3<double>::Zero();
  double scale = 0;
  for (Eigen::Index i = 0; i < x.rows(); ++i) {
    if (!(z.w[i] > 0)) continue;
    const Vec3<double> dv = (x.row(i) - z.xhat.row(i)).transpose() / z.w[i];
    P += dv;
    L += z.p.row(i).transpose().cross(dv);
    scale += dv.norm() * std::max(1.0, z.p.row(i).norm());
  }
  EXPECT_GT(scale, 0);
  EXPECT_LT(P.norm(), 1e-12 * scale);
  EXPECT_LT(L.norm(), 1e-12 * scale);
  const auto k = zone_kkt(z.cons, z.w, z.xhat, x, r.multipliers);
  EXPECT_LE(k.violation, 1e-9);
  EXPECT_LE(k.complementarity, 1e-9);
  EXPECT_LE(k.stationarity, 1e-12);
}

TEST(ZoneProjection, LargeStackInFloat) {
  using MatF = Eigen::Matrix<float, Eigen::Dynamic, 3, Eigen::RowMajor>;
  std::mt19937 rng(47);
  const auto z = pressed_stack(14, 3, true, 0, rng);
  const MatF xhat = z.xhat.cast<float>();
  const Eigen::VectorXf w = z.w.cast<float>();
  MatF x = xhat;
  ZoneProjectionOptions o;
  o.tolerance = 1e-6;
  o.solver = ZoneSolver::Sparse;
  const auto r = project_zone(z.cons, w, xhat, x, o);
  ASSERT_TRUE(r.converged);
  EXPECT_EQ(r.solver, ZoneSolver::Sparse);
  // In the float coordinates as stored: met up to the tolerance and the rounding to float.
  const auto k = zone_kkt(z.cons, w, xhat, x, r.multipliers);
  EXPECT_LE(k.violation, 1e-6 + 1e-6);
  EXPECT_GE(k.min_lambda, 0.0);
  EXPECT_LE(k.complementarity, 1e-6 + 1e-6);
}

TEST(ZoneProjection, LargeInfeasibleStackIsReported) {
  // Three layers between a floor at -gap and a ceiling: they need 4 gaps of room and get 3.5.
  for (const auto solver : {ZoneSolver::Sparse}) {  // (the dense solver's verdict: DetectsAnInfeasibleZone)
    std::mt19937 rng(53);
    const auto z = pressed_stack(12, 3, true, 2.5 * 0.004, rng);
    Mat x = z.xhat;
    const auto r = project_zone(z.cons, z.w, z.xhat, x, zone_solver_options(solver));
    EXPECT_FALSE(r.converged);
    EXPECT_TRUE(r.infeasible);
    EXPECT_EQ(r.solver, solver);
    EXPECT_TRUE(x == z.xhat);
    // With room for them (4 gaps and a little), the same zone is feasible.
    std::mt19937 rng2(53);
    const auto ok = pressed_stack(12, 3, true, 3.01 * 0.004, rng2);
    Mat x2 = ok.xhat;
    const auto r2 = project_zone(ok.cons, ok.w, ok.xhat, x2, zone_solver_options(solver));
    EXPECT_TRUE(r2.converged);
    EXPECT_FALSE(r2.infeasible);
  }
}

// The primal solver's Newton system (detail::PrimalSystem: block order, permuted upper triangle
// written in place) against the matrix built here densely, I + sum_{active} g_i g_i^T / eps, on
// random rows of one to four blocks (blocks repeated across rows, some blocks in no active row,
// one row on a single block): K^-1 x must solve the dense system to rounding, for several active
// sets of one LDP (the order is recomputed for each) and with no row active (K = I).
TEST(ZoneProjection, PrimalNewtonSystemSolvesTheDenseSystem) {
  std::mt19937 rng(1234);
  std::uniform_real_distribution<double> U(-1, 1);
  for (int trial = 0; trial < 6; ++trial) {
    const int blocks = 5 + 7 * trial, m = 4 * blocks;
    detail::ZoneLdp P;
    P.blocks = blocks;
    std::uniform_int_distribution<int> B(0, blocks - 3), NB(1, 4);  // the last two blocks are in no row
    for (int i = 0; i < m; ++i) {
      detail::LdpRow r;
      r.nb = i == 0 ? 1 : std::min(NB(rng), blocks - 2);
      double norm2 = 0;
      for (int a = 0; a < r.nb; ++a) {
        int b;
        do b = B(rng);
        while (std::find(r.blk, r.blk + a, b) != r.blk + a);
        r.blk[a] = b;
        r.g[a] = Vec3<double>(U(rng), U(rng), U(rng));
        norm2 += r.g[a].squaredNorm();
      }
      for (int a = 0; a < r.nb; ++a) r.g[a] /= std::sqrt(norm2);
      P.rows.push_back(r);
    }
    P.c = Eigen::VectorXd::Zero(m), P.tol = Eigen::VectorXd::Constant(m, 1e-9);
    detail::PrimalSystem sys(blocks);
    for (int pass = 0; pass < 4; ++pass) {
      std::vector<char> act(static_cast<std::size_t>(m));
      for (auto& a : act) a = pass == 3 ? 0 : static_cast<char>(U(rng) > -0.3 + 0.4 * pass);
      const double inv_eps = pass == 1 ? 1e6 : 1e2;
      Eigen::MatrixXd K = Eigen::MatrixXd::Identity(3 * blocks, 3 * blocks);
      for (int i = 0; i < m; ++i) {
        if (!act[static_cast<std::size_t>(i)]) continue;
        Eigen::VectorXd g = Eigen::VectorXd::Zero(3 * blocks);
        const auto& r = P.rows[static_cast<std::size_t>(i)];
        for (int a = 0; a < r.nb; ++a) g.segment<3>(3 * r.blk[a]) = r.g[a];
        K += inv_eps * g * g.transpose();
      }
      const Eigen::VectorXd x = Eigen::VectorXd::NullaryExpr(3 * blocks, [&](Eigen::Index) { return U(rng); });
      sys.order(P, [&](std::size_t i) { return act[i] != 0; });
      ASSERT_TRUE(sys.factorize(P, act, inv_eps));
      const Eigen::VectorXd d = sys.solve(x);
      EXPECT_LE((K * d - x).norm(), 1e-9 * x.norm()) << "trial " << trial << " pass " << pass;
      EXPECT_LE((d - K.ldlt().solve(x)).norm(), 1e-8 * std::max(1.0, d.norm())) << "trial " << trial << " pass " << pass;
    }
  }
}

TEST(RigidZone, KeepsMomentumAndAngularMomentum) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> U(-1, 1), W(0.5, 2);
  const int n = 9;
  Mat x0(n, 3), x1(n, 3);
  Eigen::VectorXd w(n);
  for (int i = 0; i < n; ++i) {
    x0.row(i) << U(rng), U(rng), U(rng);
    x1.row(i) = x0.row(i) + 0.01 * Eigen::RowVector3d(U(rng), U(rng), U(rng));
    w[i] = 1 / W(rng);
  }
  std::vector<std::int32_t> verts(n);
  for (int i = 0; i < n; ++i) verts[std::size_t(i)] = i;
  Mat out = x1;
  const auto m = rigid_zone_motion(verts, w, x0, out);
  // Linear momentum of the step displacements: exact up to rounding.
  Vec3<double> P0 = Vec3<double>::Zero(), P1 = Vec3<double>::Zero(), L0 = Vec3<double>::Zero(), Lr = Vec3<double>::Zero();
  for (int i = 0; i < n; ++i) {
    const Vec3<double> r = x0.row(i).transpose() - m.center0;
    P0 += (x1.row(i) - x0.row(i)).transpose() / w[i];
    P1 += (out.row(i) - x0.row(i)).transpose() / w[i];
    L0 += r.cross(Vec3<double>((x1.row(i) - x0.row(i)).transpose())) / w[i];
    Lr += r.cross(Vec3<double>(m.omega.cross(r))) / w[i];  // the rigid velocity field's
  }
  EXPECT_LT((P1 - P0).norm(), 1e-12 * P0.norm() + 1e-15);
  EXPECT_LT((Lr - L0).norm(), 1e-12 * L0.norm());
  // Rigid: pairwise distances kept.
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n; ++j) EXPECT_NEAR((out.row(i) - out.row(j)).norm(), (x0.row(i) - x0.row(j)).norm(), 1e-13);
}

TEST(RigidZone, ZeroAngularMomentumIsAPureTranslation) {
  // Collinear points (singular inertia) translating: omega exactly zero, no NaN.
  Mat x0(3, 3), x1(3, 3);
  x0 << 0, 0, 0, 1, 0, 0, 2, 0, 0;
  x1 = x0;
  x1.col(1).array() += 0.5;
  x1(0, 2) = 0.25, x1(2, 2) = -0.25;  // spin about y... through the centre: an angular momentum
  x1(1, 2) = 0;
  Eigen::VectorXd w = Eigen::VectorXd::Ones(3);
  std::vector<std::int32_t> verts = {0, 1, 2};
  Mat out = x1;
  auto m = rigid_zone_motion(verts, w, x0, out);
  EXPECT_TRUE(out.allFinite());
  EXPECT_GT(m.omega.norm(), 0);
  EXPECT_EQ(m.omega.x(), 0.0);  // no inertia about the line: no spin about it
  x1 = x0;
  x1.col(1).array() += 0.5;  // pure translation
  out = x1;
  m = rigid_zone_motion(verts, w, x0, out);
  EXPECT_EQ(m.omega.norm(), 0.0);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR((out.row(i) - x1.row(i)).norm(), 0.0, 1e-15);
  // A single point.
  std::vector<std::int32_t> one = {1};
  out = x1;
  m = rigid_zone_motion(one, w, x0, out);
  EXPECT_EQ(m.omega.norm(), 0.0);
  EXPECT_TRUE(out.row(1) == x1.row(1));
}

}  // namespace
