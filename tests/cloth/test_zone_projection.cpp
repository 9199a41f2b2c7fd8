// SPDX-License-Identifier: MIT
// project_zone and rigid_zone_motion: momentum and angular momentum kept (1e-12 relative, the
// angular momentum about the configuration where the normals are taken), constraints met,
// optimality against the analytic single-constraint answer, zero angular velocity.
#include "impact/cloth/zone_projection.hpp"

#include <gtest/gtest.h>

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

TEST(ZoneProjection, KeepsMomentumAndAngularMomentum) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 20; ++trial) {
    Zone z = random_zone(12, 6 + trial % 5, rng, false);
    Mat x = z.xhat;
    const auto r = project_zone(z.cons, z.w, z.xhat, x);
    ASSERT_TRUE(r.converged) << trial;
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
  std::mt19937 rng(5);
  Zone z = random_zone(4, 1, rng, false);
  Mat x = z.xhat;
  ASSERT_TRUE(project_zone(z.cons, z.w, z.xhat, x).converged);
  const auto& k = z.cons[0];
  double g = 0, den = 0;
  for (int j = 0; j < 4; ++j) g += k.a[j] * k.n.dot(z.xhat.row(k.v[j]).transpose()), den += k.a[j] * k.a[j] * z.w[k.v[j]];
  const double lam = (k.b - g) / den;
  for (int j = 0; j < 4; ++j) {
    const Eigen::RowVector3d expect = z.xhat.row(k.v[j]) + (z.w[k.v[j]] * k.a[j] * lam) * k.n.transpose();
    EXPECT_LT((x.row(k.v[j]) - expect).norm(), 1e-13);
  }
}

TEST(ZoneProjection, SatisfiedConstraintsChangeNothingAndPinnedStay) {
  std::mt19937 rng(7);
  Zone z = random_zone(10, 8, rng, true);
  for (auto& k : z.cons) k.b -= 10;  // all met
  Mat x = z.xhat;
  const auto r = project_zone(z.cons, z.w, z.xhat, x);
  EXPECT_TRUE(r.converged);
  EXPECT_EQ(r.active, 0);
  EXPECT_TRUE(x == z.xhat);
  for (auto& k : z.cons) k.b += 10;
  const auto r2 = project_zone(z.cons, z.w, z.xhat, x);
  EXPECT_TRUE(r2.converged);
  EXPECT_TRUE(x.row(0) == z.xhat.row(0));  // infinite mass
}

TEST(ZoneProjection, DetectsAnInfeasibleZone) {
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
  auto r = project_zone(std::vector<ZoneConstraint>{up, down}, w, p, x);
  EXPECT_TRUE(r.converged);
  EXPECT_NEAR(x(0, 2), 1.0, 1e-12);
  down.b = 4.5;  // z0 <= 0.5 and z0 >= 1
  x = p;
  r = project_zone(std::vector<ZoneConstraint>{up, down}, w, p, x);
  EXPECT_FALSE(r.converged);
  EXPECT_TRUE(r.infeasible);
  EXPECT_TRUE(x == p);
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
