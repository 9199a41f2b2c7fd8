// SPDX-License-Identifier: MIT
// The reference mass-spring cloth (cloth_model.hpp): spring construction, the implicit step
// against a dense reference solve written here, analytic oracles (free fall with and without air
// drag, a triangle hanging at its static equilibrium), pinned and scripted vertices, damping,
// stability at large steps, and bad input. Float and double.
#include "impact/cloth/cloth_model.hpp"
#include "impact/geometry/mesh_generators.hpp"
#include "support/random.hpp"
#include "support/sanitizer.hpp"

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace impact {
namespace {

template <class T> class ClothModel : public ::testing::Test {};
using Scalars = ::testing::Types<float, double>;
TYPED_TEST_SUITE(ClothModel, Scalars);

// Under AddressSanitizer the long runs take fewer steps through the same code (the Release run
// keeps the full counts).
constexpr int kLong = IMPACT_TEST_SANITIZED ? 5 : 1;

template <class S> S tol(double f, double d) { return static_cast<S>(std::is_same_v<S, float> ? f : d); }

TYPED_TEST(ClothModel, SpringsAndMassesOfAGrid) {
  using S = TypeParam;
  // 2 x 2 cells of side 0.5: 9 vertices, 8 triangles, 16 edges, 4 quad diagonals crossed by
  // shear springs, 4 interior axis edges crossed by flap (bending) springs.
  const TriangleMesh<S> g = make_grid<S>(2, 2, S(1));
  MassSpringParams<S> p;
  p.density = S(0.3);
  const auto c = make_mass_spring_cloth(g, p);
  EXPECT_EQ(c.count(SpringKind::stretch), 16);
  EXPECT_EQ(c.count(SpringKind::shear), 4);
  EXPECT_EQ(c.count(SpringKind::bend), 4);
  EXPECT_EQ(c.springs.size(), 24u);
  for (const auto& s : c.springs) {
    const S len = (g.vertex(s.a) - g.vertex(s.b)).norm();
    EXPECT_NEAR(s.rest_length, len, S(1e-6));
    if (s.kind == SpringKind::stretch) {
      EXPECT_EQ(s.stiffness, p.stretch_stiffness);
    } else if (s.kind == SpringKind::shear) {
      // the other diagonal of a quad (the grid splits each cell along a-c, so b-d)
      EXPECT_NEAR(len, S(0.5) * std::sqrt(S(2)), S(1e-6));
      const Vec3<S> d = g.vertex(s.b) - g.vertex(s.a);
      EXPECT_LT(d.x() * d.y(), S(0));  // b = (i+1, j), d = (i, j+1): the anti-diagonal
      EXPECT_EQ(s.stiffness, p.shear_stiffness);
    } else {
      // a flap spring across an axis edge: the "knight" of the two triangles' far corners
      EXPECT_NEAR(len, S(0.5) * std::sqrt(S(5)), S(1e-6));
      EXPECT_EQ(s.stiffness, p.bend_stiffness);
    }
    EXPECT_NEAR(s.damping, p.damping_time * s.stiffness, S(1e-6) * s.stiffness);
  }
  // lumped masses: corners of one triangle or two, edge vertices, the centre of six triangles
  const S tri = S(0.3) * S(0.125) / S(3);
  EXPECT_NEAR(c.mass.sum(), S(0.3), S(1e-6));
  EXPECT_NEAR(c.mass(0), 2 * tri, S(1e-7));  // (0,0): a of the cell's a-b-c and a-c-d
  EXPECT_NEAR(c.mass(2), tri, S(1e-7));      // (2,0): b of a-b-c only
  EXPECT_NEAR(c.mass(4), 6 * tri, S(1e-7));  // centre
}

// The matrix-free CG solve against a dense system assembled here from the textbook formulas
// (Baraff-Witkin, compressed springs' transverse stiffness dropped), solved by LDLT.
TYPED_TEST(ClothModel, StepMatchesADenseBackwardEulerSolve) {
  using S = TypeParam;
  test::Rng rng(7);
  TriangleMesh<S> g = make_grid<S>(3, 3, S(1));
  auto c = make_mass_spring_cloth(g, {});
  c.pin(0);
  const int n = c.num_vertices();
  Vertices<S> x0 = g.V, v0(n, 3);
  for (int i = 0; i < n; ++i) {  // stretch some springs, compress others, move everything
    if (i != 0) x0.row(i) += (S(0.06) * rng.vec(-1, 1).cast<S>()).transpose();
    v0.row(i) = rng.vec(-1, 1).cast<S>().transpose();
  }
  v0.row(0).setZero();
  ImplicitStepOptions<S> o;
  o.dt = S(1) / S(100);
  o.tolerance = tol<S>(1e-6, 1e-14);
  const auto r = implicit_euler_step(c, x0, v0, o);
  ASSERT_TRUE(r.converged);

  using M = Eigen::MatrixXd;
  const double h = double(o.dt);
  M A = M::Zero(3 * n, 3 * n);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(3 * n);
  for (int i = 0; i < n; ++i) {
    const double m = std::isinf(double(c.mass(i))) ? 1.0 : double(c.mass(i));
    A.block<3, 3>(3 * i, 3 * i) += m * (1 + h * double(c.air_damping)) * Eigen::Matrix3d::Identity();
    b.segment<3>(3 * i) += h * m * (c.gravity.template cast<double>() - double(c.air_damping) * v0.row(i).transpose().template cast<double>());
  }
  for (const auto& s : c.springs) {
    const Eigen::Vector3d d = (x0.row(s.a) - x0.row(s.b)).transpose().template cast<double>();
    const double l = d.norm(), L = double(s.rest_length), k = double(s.stiffness), kd = double(s.damping);
    const Eigen::Vector3d u = d / l;
    const Eigen::Vector3d vab = (v0.row(s.a) - v0.row(s.b)).transpose().template cast<double>();
    const Eigen::Matrix3d uu = u * u.transpose();
    const Eigen::Matrix3d K = k * (uu + std::max(0.0, 1 - L / l) * (Eigen::Matrix3d::Identity() - uu));
    const Eigen::Vector3d f = -k * (l - L) * u - kd * u.dot(vab) * u;
    const Eigen::Matrix3d Bk = h * h * K + h * kd * uu;
    b.segment<3>(3 * s.a) += h * (f - h * K * vab);
    b.segment<3>(3 * s.b) -= h * (f - h * K * vab);
    A.block<3, 3>(3 * s.a, 3 * s.a) += Bk;
    A.block<3, 3>(3 * s.b, 3 * s.b) += Bk;
    A.block<3, 3>(3 * s.a, 3 * s.b) -= Bk;
    A.block<3, 3>(3 * s.b, 3 * s.a) -= Bk;
  }
  // vertex 0 is pinned: dv_0 = -v0_0 = 0; drop its row and column
  const M Af = A.bottomRightCorner(3 * n - 3, 3 * n - 3);
  const Eigen::VectorXd dv = Af.ldlt().solve(b.tail(3 * n - 3));
  for (int i = 1; i < n; ++i)
    for (int d = 0; d < 3; ++d) {
      EXPECT_NEAR(double(r.v1(i, d)), double(v0(i, d)) + dv(3 * (i - 1) + d), tol<S>(2e-3, 1e-9)) << i << " " << d;
      EXPECT_NEAR(double(r.x1(i, d)), double(x0(i, d)) + h * (double(v0(i, d)) + dv(3 * (i - 1) + d)), tol<S>(2e-5, 1e-11));
    }
  EXPECT_EQ(r.x1.row(0), x0.row(0));
}

// Backward Euler on a free-falling cloth at rest shape: every vertex follows the integrator's
// exact discrete solution x_n = x_0 + g dt^2 n (n + 1) / 2 (that is g t^2 / 2 + g t dt / 2) and
// no spring changes length; with air drag c the velocity follows v_{n+1} = (v_n + g dt) / (1 + c dt).
TYPED_TEST(ClothModel, FreeFallFollowsTheDiscreteAnalyticSolution) {
  using S = TypeParam;
  const TriangleMesh<S> g = make_grid<S>(6, 5, S(1.3));
  for (const double air : {0.0, 0.7}) {
    MassSpringParams<S> p;
    p.air_damping = S(air);
    const auto c = make_mass_spring_cloth(g, p);
    ImplicitStepOptions<S> o;
    o.dt = S(1) / S(240);
    Vertices<S> x = g.V, v = Vertices<S>::Zero(g.num_vertices(), 3);
    double vz = 0, z = 0;
    const double h = double(o.dt), gz = -9.81;
    for (int n = 0; n < 240; ++n) {
      const auto r = implicit_euler_step(c, x, v, o);
      x = r.x1;
      v = r.v1;
      vz = (vz + gz * h) / (1 + air * h);
      z += h * vz;
    }
    if (air == 0.0) {
      EXPECT_NEAR(z, gz * h * h * 240 * 241 / 2, 1e-12);
      EXPECT_NEAR(z, gz * (240 * h) * (240 * h) / 2 + gz * (240 * h) * h / 2, 1e-12);  // g t^2/2 + g t dt/2
    }
    for (int i = 0; i < g.num_vertices(); ++i) {
      EXPECT_NEAR(double(x(i, 2)), z, tol<S>(1e-5, 1e-12) * (1 + std::abs(z))) << i;
      EXPECT_NEAR(double(x(i, 0)), double(g.V(i, 0)), tol<S>(1e-6, 1e-14));
      EXPECT_NEAR(double(v(i, 2)), vz, tol<S>(1e-5, 1e-12) * (1 + std::abs(vz)));
    }
    for (const auto& s : c.springs) EXPECT_NEAR((x.row(s.a) - x.row(s.b)).norm(), s.rest_length, tol<S>(1e-5, 1e-13));
  }
}

// One free vertex of mass m hanging from two pinned ones on springs of stiffness k: at rest the
// vertical force balance 2 k (l - L) (y / l) = m g, l = sqrt(a^2 + y^2), fixes the depth y. Solved
// here by bisection in long double; the simulation, damped, must settle there.
TYPED_TEST(ClothModel, HangingTriangleSettlesAtTheAnalyticEquilibrium) {
  using S = TypeParam;
  const long double a = 0.5L, y0 = 0.4L, m = 0.02L, k = 50.0L, g = 9.81L;
  Vertices<S> V(3, 3);
  V << S(-a), S(0), S(0), S(a), S(0), S(0), S(0), S(0), S(-y0);
  Faces F(1, 3);
  F << 0, 1, 2;
  MassSpringParams<S> p;
  p.stretch_stiffness = S(k);
  p.damping_time = S(0.01);
  p.air_damping = S(2);
  auto c = make_mass_spring_cloth(V, F, p);
  c.pin(0);
  c.pin(1);
  c.mass(2) = S(m);
  const long double L = std::sqrt(a * a + y0 * y0);
  long double lo = y0, hi = 10;  // the spring stretches: y > y0
  for (int i = 0; i < 200; ++i) {
    const long double y = (lo + hi) / 2, l = std::sqrt(a * a + y * y);
    (2 * k * (l - L) * (y / l) > m * g ? hi : lo) = y;
  }
  const double y_eq = double((lo + hi) / 2);
  ASSERT_GT(y_eq, double(y0) * 1.01);  // a visible sag
  ImplicitStepOptions<S> o;
  o.dt = S(1) / S(120);
  o.tolerance = tol<S>(1e-6, 1e-12);
  Vertices<S> x = V, v = Vertices<S>::Zero(3, 3);
  for (int n = 0; n < 3000; ++n) {
    const auto r = implicit_euler_step(c, x, v, o);
    x = r.x1;
    v = r.v1;
  }
  EXPECT_NEAR(double(x(2, 2)), -y_eq, tol<S>(1e-5, 1e-9));
  EXPECT_NEAR(double(x(2, 0)), 0.0, tol<S>(1e-6, 1e-12));
  EXPECT_NEAR(double(x(2, 1)), 0.0, tol<S>(1e-6, 1e-12));
  EXPECT_EQ(x.row(0), V.row(0));
  EXPECT_EQ(x.row(1), V.row(1));
}

template <class S> Vertices<S> settle(const MassSpringCloth<S>& c, Vertices<S> x, int steps, S dt) {
  Vertices<S> v = Vertices<S>::Zero(x.rows(), 3);
  ImplicitStepOptions<S> o;
  o.dt = dt;
  for (int n = 0; n < steps; ++n) {
    const auto r = implicit_euler_step(c, x, v, o);
    x = r.x1;
    v = r.v1;
  }
  return x;
}

// A square cloth pinned at its four corners sags most at the centre, less at the middle of its
// edges; stiffer cloth sags less, heavier cloth more. At rest the forces balance: the gradient of
// the potential energy (central differences here) vanishes at every free vertex.
TYPED_TEST(ClothModel, PinnedSquareSagOrderingAndStaticBalance) {
  using S = TypeParam;
  const int N = IMPACT_TEST_SANITIZED ? 4 : 6;
  const TriangleMesh<S> g = make_grid<S>(N, N, S(1));
  auto id = [&](int i, int j) { return i + j * (N + 1); };
  auto run = [&](S stretch, S density) {
    MassSpringParams<S> p;
    p.stretch_stiffness = stretch;
    p.shear_stiffness = stretch / S(10);
    p.density = density;
    p.air_damping = S(3);
    auto c = make_mass_spring_cloth(g, p);
    for (int v : {id(0, 0), id(N, 0), id(0, N), id(N, N)}) c.pin(v);
    return std::make_pair(c, settle(c, g.V, 600, S(1) / S(60)));
  };
  const auto [c, x] = run(S(200), S(0.1));
  const S centre = -x(id(N / 2, N / 2), 2), edge = -x(id(N / 2, 0), 2);
  EXPECT_GT(centre, edge);
  EXPECT_GT(edge, S(0.005));
  for (int v : {id(0, 0), id(N, 0), id(0, N), id(N, N)}) EXPECT_EQ(x.row(v), g.V.row(v));
  const S stiff = -run(S(800), S(0.1)).second(id(N / 2, N / 2), 2);
  const S heavy = -run(S(200), S(0.3)).second(id(N / 2, N / 2), 2);
  EXPECT_LT(stiff, S(0.9) * centre);
  EXPECT_GT(heavy, S(1.1) * centre);
  if constexpr (std::is_same_v<S, double>) {
    double worst = 0, weight = 0;
    for (int i = 0; i < c.num_vertices(); ++i) {
      if (c.kinematic(i)) continue;
      weight = std::max(weight, 9.81 * c.mass(i));
      for (int d = 0; d < 3; ++d) {
        Vertices<S> xp = x, xm = x;
        const double e = 1e-6;
        xp(i, d) += e;
        xm(i, d) -= e;
        worst = std::max(worst, std::abs((cloth_potential_energy(c, xp) - cloth_potential_energy(c, xm)) / (2 * e)));
      }
    }
    EXPECT_LT(worst, 1e-4 * weight);
  }
}

// A cloth pinned at three corners swings down from horizontal: with damping (springs, air and
// backward Euler's own) its total energy never grows and ends well below where it started; then
// one corner is scripted along a circle: it ends every step exactly at its target, and once the
// script stops it stays. The pinned vertices never move.
TYPED_TEST(ClothModel, EnergyDecreasesPinnedStayScriptedFollow) {
  using S = TypeParam;
  const int N = IMPACT_TEST_SANITIZED ? 4 : 10;
  const TriangleMesh<S> g = make_grid<S>(N, N, S(1));
  auto c = make_mass_spring_cloth(g, {});
  c.pin(0);
  c.pin(N);
  const int moving = N * (N + 1);  // corner (0, N)
  c.pin(moving);
  ImplicitStepOptions<S> o;
  o.dt = S(1) / S(60);
  Vertices<S> x = g.V, v = Vertices<S>::Zero(g.num_vertices(), 3);
  ScriptedVertices<S> sc;
  sc.ids = {moving};
  sc.positions.resize(1, 3);
  const S e0 = cloth_kinetic_energy(c, v) + cloth_potential_energy(c, x);
  S e_prev = e0, worst_rise = S(0), e_swung = S(0);
  for (int n = 0; n < 600; ++n) {
    const bool script = n >= 300 && n < 450;
    const S t = S(n - 299) * o.dt;
    sc.positions.row(0) = g.V.row(moving) + Eigen::Matrix<S, 1, 3>(S(0.1) * std::sin(t), S(0), S(0.1) * (std::cos(t) - S(1)));
    const auto r = implicit_euler_step(c, x, v, o, script ? &sc : nullptr);
    if (script) EXPECT_EQ(r.x1.row(moving), sc.positions.row(0));
    else EXPECT_EQ(r.x1.row(moving), x.row(moving));
    EXPECT_EQ(r.x1.row(0), g.V.row(0));
    EXPECT_EQ(r.x1.row(N), g.V.row(N));
    x = r.x1;
    v = r.v1;
    const S e = cloth_kinetic_energy(c, v) + cloth_potential_energy(c, x);
    if (n < 300) worst_rise = std::max(worst_rise, e - e_prev);
    if (n == 299) e_swung = e;
    e_prev = e;
  }
  S weight = S(0);
  for (int i = 0; i < c.num_vertices(); ++i)
    if (!c.kinematic(i)) weight += c.mass(i) * S(9.81);
  const S scale = weight * S(1);  // weight x size (the cloth starts at E = 0)
  EXPECT_LE(worst_rise, tol<S>(1e-5, 1e-10) * scale);
  EXPECT_LT(e_swung, e0 - S(0.02) * scale);
  EXPECT_NE(x.row(moving), g.V.row(moving));
}

// Very stiff springs at large steps: 1,000 steps at dt = 1/60 and 1/30 of a cloth hanging from
// one edge never blow up (bounded speed and stretch) and come to rest.
TYPED_TEST(ClothModel, StableAtLargeStepsWithStiffSprings) {
  using S = TypeParam;
  const int N = IMPACT_TEST_SANITIZED ? 4 : 8;
  const TriangleMesh<S> g = make_grid<S>(N, N, S(1));
  MassSpringParams<S> p;
  p.stretch_stiffness = S(1e5);
  p.shear_stiffness = S(1e4);
  p.bend_stiffness = S(1e3);
  p.air_damping = S(0);
  p.damping_time = S(0);
  auto c = make_mass_spring_cloth(g, p);
  for (int i = 0; i <= N; ++i) c.pin(i);
  for (const S dt : {S(1) / S(60), S(1) / S(30)}) {
    ImplicitStepOptions<S> o;
    o.dt = dt;
    Vertices<S> x = g.V, v = Vertices<S>::Zero(g.num_vertices(), 3);
    S max_speed = S(0), max_strain = S(0);
    for (int n = 0; n < 1000 / kLong; ++n) {
      const auto r = implicit_euler_step(c, x, v, o);
      x = r.x1;
      v = r.v1;
      ASSERT_TRUE(all_finite(x) && all_finite(v)) << n;
      for (int i = 0; i < v.rows(); ++i) max_speed = std::max(max_speed, v.row(i).norm());
      for (const auto& s : c.springs)
        if (s.kind == SpringKind::stretch) max_strain = std::max(max_strain, (x.row(s.a) - x.row(s.b)).norm() / s.rest_length - S(1));
    }
    EXPECT_LT(max_speed, S(5));  // falling 1 m at most: sqrt(2 g) < 4.5 m/s
    EXPECT_LT(max_strain, S(0.05));
    S final_speed = S(0);
    for (int i = 0; i < v.rows(); ++i) final_speed = std::max(final_speed, v.row(i).norm());
    if (kLong == 1) {
      EXPECT_LT(final_speed, S(0.05));  // numerical damping brought it to rest
      EXPECT_LT(x.col(2).minCoeff(), S(-0.9));  // and it hangs down
    }
  }
}

TYPED_TEST(ClothModel, BadInputThrows) {
  using S = TypeParam;
  const TriangleMesh<S> g = make_grid<S>(2, 2, S(1));
  MassSpringParams<S> bad;
  bad.density = S(-1);
  EXPECT_THROW(make_mass_spring_cloth(g, bad), InvalidInput);
  bad = {};
  bad.stretch_stiffness = std::numeric_limits<S>::quiet_NaN();
  EXPECT_THROW(make_mass_spring_cloth(g, bad), InvalidInput);
  TriangleMesh<S> lonely = g;  // a vertex in no triangle has no mass
  lonely.V.conservativeResize(g.num_vertices() + 1, 3);
  lonely.V.row(g.num_vertices()).setZero();
  EXPECT_THROW(make_mass_spring_cloth(lonely, {}), InvalidInput);
  EXPECT_THROW(make_mass_spring_cloth(Vertices<S>(0, 3), Faces(0, 3), {}), InvalidInput);

  auto c = make_mass_spring_cloth(g, {});
  EXPECT_THROW(c.pin(99), InvalidInput);
  const Vertices<S> x = g.V, v = Vertices<S>::Zero(9, 3);
  ImplicitStepOptions<S> o;
  EXPECT_NO_THROW(implicit_euler_step(c, x, v, o));
  Vertices<S> xn = x;
  xn(4, 1) = std::numeric_limits<S>::quiet_NaN();
  EXPECT_THROW(implicit_euler_step(c, xn, v, o), InvalidInput);
  Vertices<S> vi = v;
  vi(2, 0) = std::numeric_limits<S>::infinity();
  EXPECT_THROW(implicit_euler_step(c, x, vi, o), InvalidInput);
  EXPECT_THROW(implicit_euler_step(c, x, Vertices<S>(Vertices<S>::Zero(8, 3)), o), InvalidInput);
  auto od = o;
  od.dt = S(0);
  EXPECT_THROW(implicit_euler_step(c, x, v, od), InvalidInput);
  od.dt = std::numeric_limits<S>::quiet_NaN();
  EXPECT_THROW(implicit_euler_step(c, x, v, od), InvalidInput);
  ScriptedVertices<S> sc;
  sc.ids = {3};
  sc.positions = Vertices<S>::Zero(1, 3);
  EXPECT_THROW(implicit_euler_step(c, x, v, o, &sc), InvalidInput);  // vertex 3 has finite mass
  c.pin(3);
  EXPECT_NO_THROW(implicit_euler_step(c, x, v, o, &sc));
  sc.ids = {30};
  EXPECT_THROW(implicit_euler_step(c, x, v, o, &sc), InvalidInput);
  sc.ids = {3, 3};
  EXPECT_THROW(implicit_euler_step(c, x, v, o, &sc), InvalidInput);  // 2 ids, 1 position
}

}  // namespace
}  // namespace impact
