// SPDX-License-Identifier: MIT
// The collision step on scenes with many simultaneous contacts, each stage alone and together,
// against the oracles of cloth_oracles.hpp (all pairs sampled by closest points, all pairs through
// the primitive CCD) and the exact verify_cloth_state: two cloth layers pressed between two
// approaching planes (hundreds of contacts), pinned vertices, sliding that survives Harmon's zones
// and not rigid ones (coplanar and parallel edges), a stack pushed up over several steps (the
// re-gatherings), a step whose result does not depend on the tree, float and double.
#include "cloth_oracles.hpp"
#include "impact/cloth/verify_state.hpp"
#include "scenes.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <random>
#include <type_traits>

namespace {

using namespace impact;
using cloth_test::combine;

template <class S>
class ClothScenes : public ::testing::Test {};
using Scalars = ::testing::Types<float, double>;
TYPED_TEST_SUITE(ClothScenes, Scalars);

enum class Stages { FailsafeOnly, ImpulsesOnly, HarmonOnly, RigidOnly, All };

template <class S>
struct Pressed {
  TriangleMesh<S> cloth;
  Vertices<S> x1;
  Eigen::Matrix<S, Eigen::Dynamic, 1> w;
  Vertices<S> lo0, lo1, hi0, hi1;
  Faces qf = cloth_test::quad_faces();
  ClothObstacles<S> obs;
  double h = 0.01;

  explicit Pressed(unsigned seed) {
    cloth = cloth_test::layers<S>(8, {-h, h});
    lo0 = cloth_test::quad<S>(2, -4 * h), lo1 = cloth_test::quad<S>(2, -2.4 * h);
    hi0 = cloth_test::quad<S>(2, 4 * h), hi1 = cloth_test::quad<S>(2, 2.4 * h);
    obs.kinematic.push_back({&lo0, &lo1, &qf});
    obs.kinematic.push_back({&hi0, &hi1, &qf});
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> U(-1, 1);
    x1 = cloth.V;
    w = Eigen::Matrix<S, Eigen::Dynamic, 1>::Ones(cloth.V.rows());
    for (Eigen::Index i = 0; i < x1.rows(); ++i) {
      x1(i, 0) += S(h * U(rng)), x1(i, 1) += S(h * U(rng)), x1(i, 2) += S(3 * h * U(rng));
      w[i] = S(1 / (1 + 0.5 * (U(rng) + 1)));
    }
    // Pin the corners of the lower layer (scripted: they move as given) and make vertex 40 heavy-pinned still.
    for (int c : {0, 8, 72, 80}) w[c] = S(0), x1.row(c) = cloth.V.row(c);
    w[40] = S(0), x1.row(40) = cloth.V.row(40);
  }
};

template <class S>
ClothCollisionOptions<S> options_for(Stages s, double h) {
  ClothCollisionOptions<S> o;
  o.thickness = S(h);
  o.proximity = s == Stages::All;
  o.impulses = s == Stages::ImpulsesOnly || s == Stages::All;
  o.zones = s == Stages::HarmonOnly || s == Stages::RigidOnly || s == Stages::All;
  o.zone_method = s == Stages::RigidOnly ? ZoneMethod::Rigid : ZoneMethod::Harmon;
  return o;
}

template <class S>
void run_pressed(Stages s, unsigned seed) {
  Pressed<S> p(seed);
  Vertices<S> x1 = p.x1;
  const auto opt = options_for<S>(s, p.h);
  const auto t0 = std::chrono::steady_clock::now();
  const auto st = cloth_collision_step(p.cloth.F, p.w, p.cloth.V, x1, p.obs, opt);
  ::testing::Test::RecordProperty("step_ms", std::to_string(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count()));
  SCOPED_TRACE(testing::Message() << "stages " << int(s) << " seed " << seed);
  EXPECT_TRUE(st.collision_free);
  EXPECT_TRUE(st.unresolved.empty());
  // Hundreds of simultaneous contacts.
  const std::size_t handled = st.proximity.collisions + st.impulses.collisions + st.zones.collisions + st.failsafe.collisions;
  EXPECT_GT(handled, 100u);
  if (s == Stages::FailsafeOnly) {
    EXPECT_TRUE(st.failsafe_used);
  }
  if (s == Stages::HarmonOnly || s == Stages::All) {
    EXPECT_FALSE(st.failsafe_used);
  }
  if (s == Stages::HarmonOnly) {
    EXPECT_GT(st.zone_count, 0u);
  }
  // All stages: the impulse passes' hits, relaxed together (impulse_relax_rounds), leave the
  // zones nothing here.
  if (s == Stages::All) {
    EXPECT_GT(st.impulse_relax_impulses, 0u);
    EXPECT_EQ(st.zone_count, 0u);
  }
  // Pinned and infinite-mass vertices never move away from their scripted end.
  for (Eigen::Index i = 0; i < x1.rows(); ++i)
    if (p.w[i] == S(0)) {
      EXPECT_TRUE(x1.row(i) == p.x1.row(i)) << i;
    }
  // Oracles independent of the step's tree and stages.
  const auto c = combine(p.cloth.F, p.cloth.V, x1, p.obs);
  EXPECT_EQ(cloth_test::all_pairs_ccd_hits(c, p.h), 0);
  EXPECT_GE(cloth_test::sampled_min_distance(c, 8, 2 * p.h), p.h);
  const auto rep = verify_cloth_state(p.cloth.F, x1, p.obs, ObstacleTime::End, ClothVerifyOptions{2 * p.h, 16});
  EXPECT_EQ(rep.intersections, 0u);
  EXPECT_GE(rep.min_distance, p.h);
}

TYPED_TEST(ClothScenes, PressedBetweenPlanesFailsafeOnly) { run_pressed<TypeParam>(Stages::FailsafeOnly, 1); }
TYPED_TEST(ClothScenes, PressedBetweenPlanesImpulsesOnly) { run_pressed<TypeParam>(Stages::ImpulsesOnly, 2); }
TYPED_TEST(ClothScenes, PressedBetweenPlanesHarmonZones) { run_pressed<TypeParam>(Stages::HarmonOnly, 3); }
TYPED_TEST(ClothScenes, PressedBetweenPlanesRigidZones) { run_pressed<TypeParam>(Stages::RigidOnly, 4); }
TYPED_TEST(ClothScenes, PressedBetweenPlanesAllStages) { run_pressed<TypeParam>(Stages::All, 5); }

// The step's result does not depend on the swept tree, whose shape comes from the first step's
// motion (with a workspace) and orders the candidates as its walk finds them: four sheets resting
// 1.1 h apart on a floor and a fifth landing on them, each vertex falling by its own amount and
// jittered sideways, stepped without a workspace (a tree built for this motion) and with a
// workspace whose tree was built for the sheets lying 10 apart side by side (split at the tree's
// top), end bit for bit the same after the same work. The relaxations (Gauss-Seidel) and the
// impulses take the proximity pairs and the hits in an order of their primitives, not the walk's.
TYPED_TEST(ClothScenes, StepDoesNotDependOnTheTree) {
  using S = TypeParam;
  const double h = 0.01;
  const int K = 5, n = 4, per = (n + 1) * (n + 1);
  const TriangleMesh<S> cloth = cloth_test::layers<S>(n, {1.1 * h, 2.2 * h, 3.3 * h, 4.4 * h, 7.4 * h});
  const Vertices<S> floor = cloth_test::quad<S>(2, 0);
  const Faces qf = cloth_test::quad_faces();
  ClothObstacles<S> obs;
  obs.kinematic.push_back({&floor, &floor, &qf});
  std::mt19937 rng(29);
  std::uniform_real_distribution<double> U(-1, 1);
  Vertices<S> x1 = cloth.V;
  const Eigen::Matrix<S, Eigen::Dynamic, 1> w = Eigen::Matrix<S, Eigen::Dynamic, 1>::Ones(cloth.V.rows());
  for (Eigen::Index i = 0; i < x1.rows(); ++i) {
    x1(i, 0) += S(0.2 * h * U(rng)), x1(i, 1) += S(0.2 * h * U(rng));
    x1(i, 2) -= S(h * (0.6 + 0.1 * U(rng)) + (i >= (K - 1) * per ? 3.4 * h : 0));
  }
  ClothCollisionOptions<S> o;
  o.thickness = S(h);
  Vertices<S> xa = x1;
  const ClothStepStats a = cloth_collision_step(cloth.F, w, cloth.V, xa, obs, o);
  ClothCollisionWorkspace<S> ws;
  Vertices<S> apart = cloth.V;
  for (int k = 0; k < K; ++k) apart.middleRows(k * per, per).col(0).array() += S(10 * k);
  Vertices<S> still = apart;
  cloth_collision_step(cloth.F, w, apart, still, obs, o, &ws);
  Vertices<S> xb = x1;
  const ClothStepStats b = cloth_collision_step(cloth.F, w, cloth.V, xb, obs, o, &ws);
  EXPECT_GT(a.proximity_impulses, 50u);
  EXPECT_GT(a.impulses.collisions, 0u);
  EXPECT_TRUE(a.collision_free);
  EXPECT_TRUE(xb == xa);
  EXPECT_EQ(b.proximity_impulses, a.proximity_impulses);
  EXPECT_EQ(b.impulses.collisions, a.impulses.collisions);
  EXPECT_EQ(b.impulse_relax_impulses, a.impulse_relax_impulses);
  EXPECT_EQ(b.zones.collisions, a.zones.collisions);
  EXPECT_EQ(b.ccd_tests, a.ccd_tests);
  const auto c = combine(cloth.F, cloth.V, xa, obs);
  EXPECT_EQ(cloth_test::all_pairs_ccd_hits(c, h), 0);
}

// Two triangles; B slides along A's edge while closing in on it. Returns the sliding that
// survived: the relative displacement along the edges of their midpoints.
template <class S>
double sliding_after(bool coplanar, ZoneMethod m, bool* collision_free) {
  const double h = 0.01;
  Vertices<S> x0(6, 3);
  if (coplanar)  // both in z = 0, facing edges along x at y = 0 and y = 3h
    x0 << 0, 0, 0, 1, 0, 0, 0.5, -1, 0, 0, 3 * h, 0, 1, 3 * h, 0, 0.5, 1, 0;
  else  // A vertical with its top edge along x at z = 0; B above, its bottom edge parallel at z = 3h
    x0 << 0, 0, 0, 1, 0, 0, 0.5, 0, -1, 0, 0, 3 * h, 1, 0, 3 * h, 0.5, 1, 1;
  const Faces F = (Faces(2, 3) << 0, 1, 2, 3, 4, 5).finished();
  Vertices<S> x1 = x0;
  for (int i = 3; i < 6; ++i) {
    x1(i, 0) += S(0.5);
    x1(i, coplanar ? 1 : 2) -= S(5 * h);
  }
  Eigen::Matrix<S, Eigen::Dynamic, 1> w = Eigen::Matrix<S, Eigen::Dynamic, 1>::Ones(6);
  ClothCollisionOptions<S> o;
  o.thickness = S(h);
  o.proximity = false;
  o.impulses = false;
  o.friction = S(0);
  o.zone_method = m;
  const auto st = cloth_collision_step(F, w, x0, x1, ClothObstacles<S>{}, o);
  *collision_free = st.collision_free && !st.failsafe_used;
  // Zones of free vertices only: the step reports their linear momentum as kept (to rounding of
  // the end positions in S).
  EXPECT_GT(st.zone_count, 0u);
  const double bound = std::is_same<S, float>::value ? 1e-6 : 1e-13;
  EXPECT_LT(st.zone_momentum_error, bound);
  const auto c = combine(F, x0, x1, ClothObstacles<S>{});
  EXPECT_EQ(cloth_test::all_pairs_ccd_hits(c, h), 0);
  EXPECT_GE(cloth_test::sampled_min_distance(c, 64, 2 * h), h);
  // Relative displacement along x of the facing edges' midpoints (the contact).
  auto mid = [&](const Vertices<S>& X, int a, int b) { return 0.5 * double(X(a, 0) + X(b, 0)); };
  return (mid(x1, 3, 4) - mid(x0, 3, 4)) - (mid(x1, 0, 1) - mid(x0, 0, 1));
}

TYPED_TEST(ClothScenes, SlidingSurvivesHarmonNotRigid) {
  using S = TypeParam;
  for (bool coplanar : {true, false}) {
    bool ok = false;
    const double harmon = sliding_after<S>(coplanar, ZoneMethod::Harmon, &ok);
    EXPECT_TRUE(ok);
    EXPECT_NEAR(harmon, 0.5, 0.01) << "coplanar " << coplanar;
    const double rigid = sliding_after<S>(coplanar, ZoneMethod::Rigid, &ok);
    EXPECT_TRUE(ok);
    EXPECT_LT(std::abs(rigid), 0.05) << "coplanar " << coplanar;
  }
}

// A stack of K sheets resting on a still floor, 1.1 h apart (only neighbouring layers are within
// the proximity distance 2 h), all moving down by 0.6 h in the step (gravity), each vertex by a
// little more or less. The inelastic answer stops the whole stack. A single pass of proximity
// impulses cannot (whatever its order, stopping one pair of a chain restarts the next), so the
// CCD then finds collisions; iterated to convergence, the proximity stage leaves nothing to
// the CCD impulses, the zones or the fail-safe. Checked against the all-pairs oracles and by
// the stack's own motion: nothing goes down.
// With `landing`, a sixth sheet 3 h above the stack (beyond the proximity distance) falls onto
// it by 4 h: a CCD hit that pushes the stack, which the relaxation after the impulse pass carries
// down to the floor (impulse_relax_rounds).
template <class S>
ClothStepStats resting_stack(int rounds, Vertices<S>* x0_out, Vertices<S>* x1_out, double* h_out, bool landing = false,
                             int relax_rounds = ClothCollisionOptions<S>{}.impulse_relax_rounds) {
  const double h = 0.01;
  const int K = 5;
  std::vector<double> z;
  for (int k = 0; k < K; ++k) z.push_back(1.1 * h * (k + 1));
  if (landing) z.push_back(z.back() + 3 * h);
  const int n = 4;  // cells per side: (n + 1)^2 vertices per sheet
  const TriangleMesh<S> cloth = cloth_test::layers<S>(n, z);
  static const Vertices<S> floor = cloth_test::quad<S>(2, 0);
  static const Faces qf = cloth_test::quad_faces();
  ClothObstacles<S> obs;
  obs.kinematic.push_back({&floor, &floor, &qf});
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> U(-1, 1);
  Vertices<S> x1 = cloth.V;
  Eigen::Matrix<S, Eigen::Dynamic, 1> w(cloth.V.rows());
  for (Eigen::Index i = 0; i < x1.rows(); ++i) {
    x1(i, 2) -= S(h * (0.6 + 0.05 * U(rng)));
    if (landing && i >= K * (n + 1) * (n + 1)) x1(i, 2) -= S(3.4 * h);
    w[i] = S(1 / (1 + 0.5 * (U(rng) + 1)));
  }
  ClothCollisionOptions<S> o;
  o.thickness = S(h);
  o.proximity_rounds = rounds;
  o.impulse_relax_rounds = relax_rounds;
  const ClothStepStats st = cloth_collision_step(cloth.F, w, cloth.V, x1, obs, o);
  EXPECT_TRUE(st.collision_free);
  const auto c = combine(cloth.F, cloth.V, x1, obs);
  EXPECT_EQ(cloth_test::all_pairs_ccd_hits(c, h), 0);
  EXPECT_GE(cloth_test::sampled_min_distance(c, 8, 2 * h), h);
  *x0_out = cloth.V, *x1_out = x1, *h_out = h;
  return st;
}

TYPED_TEST(ClothScenes, RestingStackStopsInTheProximityStage) {
  using S = TypeParam;
  Vertices<S> x0, x1;
  double h = 0;
  // rounds enough for this stack to converge (the default budget is smaller: the CCD stages take
  // what it leaves)
  const ClothStepStats st = resting_stack<S>(500, &x0, &x1, &h);
  EXPECT_TRUE(st.proximity_converged);
  EXPECT_GT(st.proximity.passes, 1);
  EXPECT_GT(st.proximity.collisions, 50u);
  EXPECT_EQ(st.impulses.collisions, 0u);
  EXPECT_EQ(st.zone_count, 0u);
  EXPECT_EQ(st.zones.collisions, 0u);
  EXPECT_FALSE(st.failsafe_used);
  // Stopped: no vertex goes down by more than the relaxation's tolerance, summed over the layers
  // below it (each pair may keep an approach of 1e-3 h); rounding of float coordinates near 0.05.
  const double slack = 5 * 1e-3 * h + (std::is_same<S, float>::value ? 1e-6 : 1e-12);
  double down = 0;
  for (Eigen::Index i = 0; i < x1.rows(); ++i) down = std::max(down, double(x0(i, 2) - x1(i, 2)));
  EXPECT_LE(down, slack);
  // One pass, as before: the CCD stages have to take over (and do: the oracles above pass).
  const ClothStepStats one = resting_stack<S>(1, &x0, &x1, &h);
  EXPECT_EQ(one.proximity.passes, 1);
  EXPECT_FALSE(one.proximity_converged);
  EXPECT_GT(one.impulses.collisions + one.zones.collisions, 0u);
}

TYPED_TEST(ClothScenes, SheetLandingOnARestingStackNeedsNoZone) {
  using S = TypeParam;
  Vertices<S> x0, x1;
  double h = 0;
  const int rounds = 500;  // the resting stack's relaxation converges first
  // The hits of the landing sheet are the CCD's; relaxed with the resting pairs, nothing is left
  // for the zones.
  const ClothStepStats st = resting_stack<S>(rounds, &x0, &x1, &h, true);
  EXPECT_GT(st.impulses.collisions, 0u);
  EXPECT_GT(st.impulse_relax_impulses, 0u);
  EXPECT_EQ(st.zone_count, 0u);
  EXPECT_FALSE(st.failsafe_used);
  // Without the relaxation after the pass, the pushed stack's pairs become CCD hits of later passes.
  const ClothStepStats alone = resting_stack<S>(rounds, &x0, &x1, &h, true, 0);
  EXPECT_EQ(alone.impulse_relax_impulses, 0u);
  EXPECT_GT(alone.impulses.collisions, st.impulses.collisions);
}


// Four sheets 1.5 h apart fall onto a floor rising 1.5 h per step, over several steps with one
// workspace (the tree refitted, not rebuilt), each vertex with its own random fall and sideways
// jitter: the floor pushes the stack up, out of the envelopes of the falling vertices, so the
// steps gather again, growing only the envelopes left and walking only the grown parts of the
// tree. Every step is checked against the all-pairs
// oracles, which know nothing of envelopes or trees: a pair the re-gatherings missed and that
// then collided would show there.
TYPED_TEST(ClothScenes, FallingStackGatheredAgainOverSteps) {
  using S = TypeParam;
  const double h = 0.01;
  const int n = 5;
  const TriangleMesh<S> cloth = cloth_test::layers<S>(n, {1.5 * h, 3 * h, 4.5 * h, 6 * h});
  const Faces qf = cloth_test::quad_faces();
  std::mt19937 rng(23);
  std::uniform_real_distribution<double> U(-1, 1);
  Eigen::Matrix<S, Eigen::Dynamic, 1> w = Eigen::Matrix<S, Eigen::Dynamic, 1>::Ones(cloth.V.rows());
  ClothCollisionOptions<S> o;
  o.thickness = S(h);
  ClothCollisionWorkspace<S> ws;
  Vertices<S> x0 = cloth.V;
  int regathered = 0;
  for (int step = 0; step < 6; ++step) {
    const Vertices<S> floor0 = cloth_test::quad<S>(2, 1.5 * h * step), floor1 = cloth_test::quad<S>(2, 1.5 * h * (step + 1));
    ClothObstacles<S> obs;
    obs.kinematic.push_back({&floor0, &floor1, &qf});
    Vertices<S> x1 = x0;
    for (Eigen::Index i = 0; i < x1.rows(); ++i) {
      x1(i, 2) -= S(h * (0.5 + 0.4 * U(rng)));
      x1(i, 0) += S(0.3 * h * U(rng));
      x1(i, 1) += S(0.3 * h * U(rng));
    }
    const ClothStepStats st = cloth_collision_step(cloth.F, w, x0, x1, obs, o, &ws);
    EXPECT_TRUE(st.collision_free) << "step " << step;
    regathered += st.broad.passes - 1;
    const auto c = combine(cloth.F, x0, x1, obs);
    EXPECT_EQ(cloth_test::all_pairs_ccd_hits(c, h), 0) << "step " << step;
    EXPECT_GE(cloth_test::sampled_min_distance(c, 8, 2 * h), h) << "step " << step;
    x0 = x1;
  }
  EXPECT_GT(regathered, 0);
}

}  // namespace
