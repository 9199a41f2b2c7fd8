// SPDX-License-Identifier: MIT
// cloth_collision_step against oracles written here (cloth_oracles.hpp: all-pairs sampled
// distances by closest points, all-pairs CCD without a tree) and the exact verify_cloth_state:
// a vertex at 1000 m/s, bad input, float and double; the broad phase of a step: candidates gathered
// once, gathered again when a vertex is pushed out of its envelope, CCD skipped by the distance
// bounds where nothing approaches and by a separating direction where sheets slide.
#include "cloth_oracles.hpp"
#include "impact/cloth/collision_step.hpp"
#include "impact/cloth/verify_state.hpp"
#include "impact/geometry/mesh_generators.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>

namespace {

using namespace impact;
using cloth_test::combine;

template <class S>
class ClothStep : public ::testing::Test {};
using Scalars = ::testing::Types<float, double>;
TYPED_TEST_SUITE(ClothStep, Scalars);

template <class S>
Vertices<S> rows(std::initializer_list<std::array<double, 3>> r) {
  Vertices<S> V(static_cast<Eigen::Index>(r.size()), 3);
  Eigen::Index i = 0;
  for (const auto& p : r) V.row(i++) << S(p[0]), S(p[1]), S(p[2]);
  return V;
}

/// A static obstacle: the big triangle in the plane z = 0.
template <class S>
struct Floor {
  Vertices<S> V = rows<S>({{-10, -10, 0}, {10, -10, 0}, {0, 10, 0}});
  Faces F = (Faces(1, 3) << 0, 1, 2).finished();
};

// A small cloth triangle falls at 1000 m/s (dt = 0.01: 10 units per step) through a static floor.
TYPED_TEST(ClothStep, VertexAt1000MetresPerSecondStopsAboveTheFloor) {
  using S = TypeParam;
  Floor<S> floor;
  ClothObstacles<S> obs;
  obs.kinematic.push_back({&floor.V, &floor.V, &floor.F});
  const Faces F = (Faces(1, 3) << 0, 1, 2).finished();
  const Vertices<S> x0 = rows<S>({{0, 0, 0.05}, {0.1, 0, 0.06}, {0, 0.1, 0.07}});
  Vertices<S> x1 = x0;
  x1.col(2).array() -= S(10);   // 1000 m/s * 0.01 s
  x1.col(0).array() += S(0.3);  // and sliding sideways
  Eigen::Matrix<S, Eigen::Dynamic, 1> w = Eigen::Matrix<S, Eigen::Dynamic, 1>::Ones(3);
  ClothCollisionOptions<S> opt;
  opt.thickness = S(1e-3);
  opt.friction = S(0);
  const Vertices<S> x1_in = x1;
  const auto st = cloth_collision_step(F, w, x0, x1, obs, opt);
  EXPECT_TRUE(st.collision_free);
  EXPECT_FALSE(st.failsafe_used);
  EXPECT_GT(st.impulses.collisions + st.zones.collisions, 0u);
  const auto c = combine(F, x0, x1, obs);
  EXPECT_EQ(cloth_test::all_pairs_ccd_hits(c, 1e-3), 0);
  EXPECT_GE(cloth_test::sampled_min_distance(c), 1e-3);
  // It stops at the floor (within the separation target), and without friction keeps sliding.
  for (int i = 0; i < 3; ++i) {
    EXPECT_GE(double(x1(i, 2)), 1e-3);
    EXPECT_LT(double(x1(i, 2)), 0.08);
    EXPECT_NEAR(double(x1(i, 0)), double(x1_in(i, 0)), 1e-5);
  }
  const auto rep = verify_cloth_state(F, x1, obs, ObstacleTime::End, ClothVerifyOptions{1.0, 16});
  EXPECT_EQ(rep.intersections, 0u);
  EXPECT_GE(rep.min_distance, 1e-3);
}

// Two cloth triangles (separate components): one shot through the other, both movable.
TYPED_TEST(ClothStep, ClothShotThroughClothIsStopped) {
  using S = TypeParam;
  const Faces F = (Faces(2, 3) << 0, 1, 2, 3, 4, 5).finished();
  const Vertices<S> x0 = rows<S>({{-1, -1, 0}, {1, -1, 0}, {0, 1, 0}, {0, 0, 0.1}, {0.05, 0, 0.1}, {0, 0.05, 0.12}});
  Vertices<S> x1 = x0;
  for (int i = 3; i < 6; ++i) x1(i, 2) -= S(10);
  Eigen::Matrix<S, Eigen::Dynamic, 1> w = Eigen::Matrix<S, Eigen::Dynamic, 1>::Ones(6);
  ClothCollisionOptions<S> opt;
  opt.thickness = S(1e-3);
  const auto st = cloth_collision_step(F, w, x0, x1, ClothObstacles<S>{}, opt);
  EXPECT_TRUE(st.collision_free);
  const auto c = combine(F, x0, x1, ClothObstacles<S>{});
  EXPECT_EQ(cloth_test::all_pairs_ccd_hits(c, 1e-3), 0);
  EXPECT_GE(cloth_test::sampled_min_distance(c), 1e-3);
  EXPECT_EQ(verify_cloth_state(F, x1, ClothObstacles<S>{}).intersections, 0u);
  // Equal masses, inelastic: the momentum along z is shared (total z displacement kept).
  double zsum0 = 0, zsum1 = 0;
  for (int i = 0; i < 6; ++i) zsum0 += double(x0(i, 2)), zsum1 += double(x1(i, 2));
  EXPECT_NEAR(zsum1 - zsum0, -30.0, 1e-3 * 30);
}

TYPED_TEST(ClothStep, BadInputThrowsAndModifiesNothing) {
  using S = TypeParam;
  const Faces F = (Faces(2, 3) << 0, 1, 2, 3, 4, 5).finished();
  const Vertices<S> x0 = rows<S>({{-1, -1, 0}, {1, -1, 0}, {0, 1, 0}, {0, 0, 0.1}, {0.05, 0, 0.1}, {0, 0.05, 0.12}});
  Vertices<S> x1 = x0;
  x1(3, 2) -= S(1);
  const Vertices<S> keep = x1;
  Eigen::Matrix<S, Eigen::Dynamic, 1> w = Eigen::Matrix<S, Eigen::Dynamic, 1>::Ones(6);
  ClothCollisionOptions<S> opt;
  opt.thickness = S(1e-3);
  const ClothObstacles<S> none;
  auto expect_throw = [&](auto&& call, const char* what) {
    EXPECT_THROW(call(), InvalidInput) << what;
    EXPECT_TRUE(x1 == keep) << what;
  };
  {
    auto o = opt;
    o.thickness = S(0);
    expect_throw([&] { cloth_collision_step(F, w, x0, x1, none, o); }, "h = 0");
    o.thickness = std::numeric_limits<S>::quiet_NaN();
    expect_throw([&] { cloth_collision_step(F, w, x0, x1, none, o); }, "h NaN");
    o = opt;
    o.proximity_distance = S(5e-4);
    expect_throw([&] { cloth_collision_step(F, w, x0, x1, none, o); }, "proximity < h");
    o = opt;
    o.friction = S(-1);
    expect_throw([&] { cloth_collision_step(F, w, x0, x1, none, o); }, "friction < 0");
    o = opt;
    o.proximity_rounds = 0;
    expect_throw([&] { cloth_collision_step(F, w, x0, x1, none, o); }, "proximity_rounds 0");
    o = opt;
    o.proximity_tolerance = S(0);
    expect_throw([&] { cloth_collision_step(F, w, x0, x1, none, o); }, "proximity_tolerance 0");
  }
  {
    auto w2 = w;
    w2[2] = S(-1);
    expect_throw([&] { cloth_collision_step(F, w2, x0, x1, none, opt); }, "negative inverse mass");
    w2[2] = std::numeric_limits<S>::quiet_NaN();
    expect_throw([&] { cloth_collision_step(F, w2, x0, x1, none, opt); }, "NaN mass");
    Eigen::Matrix<S, Eigen::Dynamic, 1> w3 = Eigen::Matrix<S, Eigen::Dynamic, 1>::Ones(5);
    expect_throw([&] { cloth_collision_step(F, w3, x0, x1, none, opt); }, "mass size");
  }
  {
    auto bad0 = x0;
    bad0(4, 1) = std::numeric_limits<S>::infinity();
    expect_throw([&] { cloth_collision_step(F, w, bad0, x1, none, opt); }, "Inf in x0");
    Vertices<S> short0 = x0.topRows(5);
    expect_throw([&] { cloth_collision_step(F, w, short0, x1, none, opt); }, "size mismatch / index out of range");
    Vertices<S> nan1 = x1;
    nan1(0, 0) = std::numeric_limits<S>::quiet_NaN();
    const Vertices<S> nan_keep = nan1;
    EXPECT_THROW(cloth_collision_step(F, w, x0, nan1, none, opt), InvalidInput);
    EXPECT_TRUE(nan1.topRows(1).hasNaN() && nan1.bottomRows(5) == nan_keep.bottomRows(5));
  }
  {
    // x0 closer than h: vertex 3 at 5e-4 above the first triangle.
    auto close0 = x0;
    close0(3, 2) = S(5e-4);
    try {
      cloth_collision_step(F, w, close0, x1, none, opt);
      ADD_FAILURE() << "no throw";
    } catch (const InvalidInput& e) {
      EXPECT_NE(std::string(e.what()).find("vertex 3-face (0,1,2)"), std::string::npos) << e.what();
    }
    EXPECT_TRUE(x1 == keep);
    auto o = opt;
    o.on_start_violation = StartViolation::Report;
    Vertices<S> x1r = x1;
    const auto st = cloth_collision_step(F, w, close0, x1r, none, o);
    ASSERT_FALSE(st.start_violations.empty());
    EXPECT_EQ(st.start_violations[0].v[0], 3);
  }
  {
    // An obstacle with an out-of-range index.
    Floor<S> floor;
    Faces badF = floor.F;
    badF(0, 2) = 7;
    ClothObstacles<S> obs;
    obs.kinematic.push_back({&floor.V, &floor.V, &badF});
    expect_throw([&] { cloth_collision_step(F, w, x0, x1, obs, opt); }, "obstacle index");
  }
}

// The start check's exact intersection test (cloth/detail/start_intersections.hpp): an edge
// through a triangle's interior with every vertex-face and edge-edge pair far farther apart than
// h is seen by no distance, only by the triangle pair's exact test; it throws naming the two
// triangles, or is listed with StartViolation::Report. Non-adjacent, sharing a vertex (the
// opposite edge through the other triangle), and against an obstacle.
TYPED_TEST(ClothStep, IntersectingStartThrowsNamingTheTriangles) {
  using S = TypeParam;
  const S h = S(1e-3);
  ClothCollisionOptions<S> opt;
  opt.thickness = h;
  const ClothObstacles<S> none;
  auto expect_intersecting_start = [&](const Faces& F, const Vertices<S>& x0, const ClothObstacles<S>& obs, const std::string& named) {
    // the oracles: verify_cloth_state's exact test sees the intersection, no pair is within 100 h
    const auto rep = verify_cloth_state(F, x0, obs, ObstacleTime::Start);
    EXPECT_EQ(rep.intersections, 1u);
    EXPECT_GT(cloth_test::sampled_min_distance(combine(F, x0, x0, obs), 1), 100 * double(h));
    Vertices<S> x1 = x0;
    x1.col(2).array() -= S(0.01);
    const Vertices<S> keep = x1;
    Eigen::Matrix<S, Eigen::Dynamic, 1> w = Eigen::Matrix<S, Eigen::Dynamic, 1>::Ones(x0.rows());
    try {
      cloth_collision_step(F, w, x0, x1, obs, opt);
      ADD_FAILURE() << "no throw for " << named;
    } catch (const InvalidInput& e) {
      EXPECT_NE(std::string(e.what()).find(named), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("intersects"), std::string::npos) << e.what();
    }
    EXPECT_TRUE(x1 == keep);
    auto o = opt;
    o.on_start_violation = StartViolation::Report;
    const auto st = cloth_collision_step(F, w, x0, x1, obs, o);
    ASSERT_EQ(st.start_intersections.size(), 1u);
    EXPECT_TRUE(st.start_violations.empty());
  };
  // Triangle 0 in z = 0; triangle 1 upright, its edges (3,4) and (4,5) through 0's interior.
  const Faces F = (Faces(2, 3) << 0, 1, 2, 3, 4, 5).finished();
  const Vertices<S> x0 = rows<S>({{-1, -1, 0}, {1, -1, 0}, {0, 1, 0}, {0, -0.2, 0.5}, {0, -0.2, -0.5}, {0.1, -0.2, 0.6}});
  expect_intersecting_start(F, x0, none, "triangle 0 (0,1,2) and triangle 1 (3,4,5)");
  // Sharing vertex 0: the edge (3,4) opposite it passes through triangle 0's interior.
  const Faces Fv = (Faces(2, 3) << 0, 1, 2, 0, 3, 4).finished();
  const Vertices<S> xv = rows<S>({{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {0.5, 0.5, 1}, {0.5, 0.5, -1}});
  expect_intersecting_start(Fv, xv, none, "triangle 0 (0,1,2) and triangle 1 (0,3,4)");
  // Against a kinematic obstacle (triangle 1, vertices 3-5): the obstacle's edge through the cloth.
  const Faces Fc = (Faces(1, 3) << 0, 1, 2).finished();
  const Vertices<S> xc = x0.topRows(3);
  const Vertices<S> ob = x0.bottomRows(3);
  const Faces Fo = (Faces(1, 3) << 0, 1, 2).finished();
  ClothObstacles<S> obs;
  obs.kinematic.push_back({&ob, &ob, &Fo});
  expect_intersecting_start(Fc, xc, obs, "triangle 0 (0,1,2) and triangle 1 (3,4,5)");
  // The same triangle twice (a duplicated face): it shares every point with itself.
  const Faces Fd = (Faces(2, 3) << 0, 1, 2, 1, 2, 0).finished();
  expect_intersecting_start(Fd, xc, none, "triangle 0 (0,1,2) and triangle 1 (1,2,0)");
}

// With a workspace, a start that is bit for bit the last step's clean end skips the exact
// intersection test (known free); any other start, the start after a step that threw, and the
// start after a step whose own start intersected (StartViolation::Report) are tested again.
TYPED_TEST(ClothStep, StartAfterACleanStepIsKnownFreeOfIntersections) {
  using S = TypeParam;
  ClothCollisionOptions<S> opt;
  opt.thickness = S(1e-3);
  const ClothObstacles<S> none;
  const Faces F = (Faces(2, 3) << 0, 1, 2, 3, 4, 5).finished();
  // triangle 1 upright through triangle 0's interior (every vertex-face and edge-edge pair far)
  const Vertices<S> pierced = rows<S>({{-1, -1, 0}, {1, -1, 0}, {0, 1, 0}, {0, -0.2, 0.5}, {0, -0.2, -0.5}, {0.1, -0.2, 0.6}});
  Vertices<S> apart = pierced;
  apart.bottomRows(3).col(2).array() += S(2);  // lifted clear of triangle 0
  const Eigen::Matrix<S, Eigen::Dynamic, 1> w = Eigen::Matrix<S, Eigen::Dynamic, 1>::Ones(6);
  ClothCollisionWorkspace<S> ws;
  auto step = [&](const Vertices<S>& x0, Vertices<S>& x1, StartViolation on) {
    auto o = opt;
    o.on_start_violation = on;
    return cloth_collision_step(F, w, x0, x1, none, o, &ws);
  };
  Vertices<S> x1 = apart;
  x1.col(2).array() -= S(0.01);
  const auto first = step(apart, x1, StartViolation::Throw);
  EXPECT_FALSE(first.start_intersections_known_free);
  ASSERT_TRUE(first.collision_free);
  Vertices<S> x0 = x1;
  x1.col(2).array() -= S(0.01);
  EXPECT_TRUE(step(x0, x1, StartViolation::Throw).start_intersections_known_free);
  // not the last end: tested, and it throws
  Vertices<S> x1p = pierced;
  EXPECT_THROW(step(pierced, x1p, StartViolation::Throw), InvalidInput);
  // the step that threw left no clean end behind
  x0 = x1;
  EXPECT_FALSE(step(x0, x1, StartViolation::Throw).start_intersections_known_free);
  // a reported intersection stays: the next start is tested again and reports it again
  x1p = pierced;
  EXPECT_EQ(step(pierced, x1p, StartViolation::Report).start_intersections.size(), 1u);
  const Vertices<S> x0p = x1p;
  const auto again = step(x0p, x1p, StartViolation::Report);
  EXPECT_FALSE(again.start_intersections_known_free);
  EXPECT_EQ(again.start_intersections.size(), 1u);
}

// Starts that touch within the thickness band but do not intersect: a flat sheet (adjacent
// triangles coplanar), a second sheet 1.5 h above it, an upright triangle standing 1.5 h above
// the top sheet's interior, and one whose edge crosses the sheet's plane 1.5 h beyond its
// border. Nothing throws, in float and double; 0.7 h closer, a start pair is closer than h.
TYPED_TEST(ClothStep, TouchingAndNearStartsDoNotThrow) {
  using S = TypeParam;
  const S h = S(1e-3);
  const auto g = make_grid<S>(4, 4, S(1));
  const Eigen::Index n = g.V.rows(), m = g.F.rows();
  Faces F(2 * m + 2, 3);
  F.topRows(m) = g.F;
  F.middleRows(m, m) = g.F.array() + int(n);
  Vertices<S> x0(2 * n + 6, 3);
  x0.topRows(n) = g.V;
  x0.middleRows(n, n) = g.V;
  x0.middleRows(n, n).col(2).array() += S(1.5) * h;
  const S top = S(1.5) * h, edge = g.V.col(0).maxCoeff();
  // upright over the interior, its lowest vertex 1.5 h above the top sheet
  x0.row(2 * n) << S(0.3), S(0.3), top + S(1.5) * h;
  x0.row(2 * n + 1) << S(0.3), S(0.35), S(0.5);
  x0.row(2 * n + 2) << S(0.35), S(0.3), S(0.5);
  // an edge down through the sheets' plane 1.5 h beyond their border x = edge
  x0.row(2 * n + 3) << edge + S(1.5) * h, S(0.5), S(0.5);
  x0.row(2 * n + 4) << edge + S(1.5) * h, S(0.5), S(-0.5);
  x0.row(2 * n + 5) << edge + S(0.3), S(0.5), S(0.5);
  F.row(2 * m) << int(2 * n), int(2 * n + 1), int(2 * n + 2);
  F.row(2 * m + 1) << int(2 * n + 3), int(2 * n + 4), int(2 * n + 5);
  const ClothObstacles<S> none;
  EXPECT_EQ(verify_cloth_state(F, x0, none, ObstacleTime::Start).intersections, 0u);
  ClothCollisionOptions<S> opt;
  opt.thickness = h;
  Eigen::Matrix<S, Eigen::Dynamic, 1> w = Eigen::Matrix<S, Eigen::Dynamic, 1>::Ones(x0.rows());
  Vertices<S> x1 = x0;
  EXPECT_NO_THROW(cloth_collision_step(F, w, x0, x1, none, opt));
  for (Eigen::Index v : {Eigen::Index(2 * n), Eigen::Index(2 * n + 3)}) {
    Vertices<S> closer = x0;
    closer(v, v == 2 * n ? 2 : 0) -= S(0.7) * h;
    if (v == 2 * n + 3) closer(v + 1, 0) -= S(0.7) * h;
    Vertices<S> x1c = closer;
    EXPECT_THROW(cloth_collision_step(F, w, closer, x1c, none, opt), InvalidInput) << v;
  }
}

// Random triangle pairs (a third sharing a vertex) around a triangle, h = 0.01: whenever the exact
// verify_cloth_state finds them intersecting at x0, the step throws; when it throws for an
// intersection, verify_cloth_state finds one; when it does not throw, no pair is within h.
TYPED_TEST(ClothStep, StartCheckAgreesWithExactVerification) {
  using S = TypeParam;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> U(-1, 1);
  ClothCollisionOptions<S> opt;
  opt.thickness = S(0.01);
  const ClothObstacles<S> none;
  int pierced = 0, intersecting = 0;
  for (int it = 0; it < 300; ++it) {
    const bool shared = it % 3 == 0;
    const Faces F = shared ? (Faces(2, 3) << 0, 1, 2, 0, 3, 4).finished() : (Faces(2, 3) << 0, 1, 2, 3, 4, 5).finished();
    Vertices<S> x0(shared ? 5 : 6, 3);
    for (Eigen::Index i = 0; i < x0.rows(); ++i)
      for (int k = 0; k < 3; ++k) x0(i, k) = S(i < 3 && k == 2 ? 0.1 * U(rng) : U(rng));
    const bool hit = verify_cloth_state(F, x0, none, ObstacleTime::Start).intersections > 0;
    intersecting += hit;
    Vertices<S> x1 = x0;
    Eigen::Matrix<S, Eigen::Dynamic, 1> w = Eigen::Matrix<S, Eigen::Dynamic, 1>::Ones(x0.rows());
    try {
      cloth_collision_step(F, w, x0, x1, none, opt);
      EXPECT_FALSE(hit) << it;
      EXPECT_GE(cloth_test::sampled_min_distance(combine(F, x0, x0, none), 1), 0.01) << it;
    } catch (const InvalidInput& e) {
      if (std::string(e.what()).find("intersects") != std::string::npos) {
        ++pierced;
        EXPECT_TRUE(hit) << it << ": " << e.what();
      }
    }
  }
  EXPECT_GE(intersecting, 60);
  EXPECT_GE(pierced, 30);
}

// A floor rising 0.5 in one step pushes a resting cloth triangle (A) far out of the envelope the
// step gathered its candidates for (its swept box and h around it) and into a second cloth
// triangle (B) hanging above it, which A's first candidates never met: only a new gathering sees
// A against B. Without it A would pass through B; the all-pairs oracles say nothing does.
TYPED_TEST(ClothStep, PushedOutOfItsEnvelopeIsGatheredAgain) {
  using S = TypeParam;
  Floor<S> floor;
  Vertices<S> floor1 = floor.V;
  floor1.col(2).array() += S(0.5);
  ClothObstacles<S> obs;
  obs.kinematic.push_back({&floor.V, &floor1, &floor.F});
  const Faces F = (Faces(2, 3) << 0, 1, 2, 3, 4, 5).finished();
  const Vertices<S> x0 =
      rows<S>({{0, 0, 0.05}, {0.1, 0, 0.05}, {0, 0.1, 0.05}, {-0.05, -0.05, 0.3}, {0.2, -0.05, 0.3}, {-0.05, 0.2, 0.3}});
  Vertices<S> x1 = x0;  // both at rest
  Eigen::Matrix<S, Eigen::Dynamic, 1> w = Eigen::Matrix<S, Eigen::Dynamic, 1>::Ones(6);
  ClothCollisionOptions<S> opt;
  opt.thickness = S(1e-3);
  const auto st = cloth_collision_step(F, w, x0, x1, obs, opt);
  EXPECT_TRUE(st.collision_free);
  EXPECT_GE(st.broad.passes, 2);  // gathered again after A left its envelope
  const auto c = combine(F, x0, x1, obs);
  EXPECT_EQ(cloth_test::all_pairs_ccd_hits(c, 1e-3), 0);
  EXPECT_GE(cloth_test::sampled_min_distance(c), 1e-3);
  // Floor, then A, then B, each at least h above the one below.
  for (int i = 0; i < 3; ++i) {
    EXPECT_GE(double(x1(i, 2)), 0.5 + 1e-3);
    for (int j = 3; j < 6; ++j) EXPECT_GE(double(x1(j, 2)) - double(x1(i, 2)), 1e-3 * 0.999);
  }
}

// A kinematic piston under one corner region of a large cloth triangle A rises 0.5 in one step and
// pushes A out of its envelope, through the point of a hanging spike B (its lowest vertex) over
// A's interior, far from A's vertices and edges and from the piston: only the pairs of B's
// vertices (which did not move) against A's face (which grew) find it, so a re-gathering must test
// the faces of grown triangles against vertices that did not grow.
TYPED_TEST(ClothStep, GrownFaceMeetsAStillVertex) {
  using S = TypeParam;
  const Vertices<S> piston0 = rows<S>({{0.3, -0.2, 0}, {0.35, -0.2, -0.05}, {0.3, -0.15, -0.05}});
  Vertices<S> piston1 = piston0;
  piston1.col(2).array() += S(0.5);
  const Faces piston_faces = (Faces(1, 3) << 0, 1, 2).finished();
  ClothObstacles<S> obs;
  obs.kinematic.push_back({&piston0, &piston1, &piston_faces});
  const Faces F = (Faces(2, 3) << 0, 1, 2, 3, 4, 5).finished();
  const Vertices<S> x0 =
      rows<S>({{-0.3, -0.3, 0.05}, {0.6, -0.3, 0.05}, {-0.3, 0.6, 0.05}, {0, 0.1, 0.2}, {-0.05, 0.1, 0.3}, {0.05, 0.1, 0.3}});
  Vertices<S> x1 = x0;  // both at rest
  Eigen::Matrix<S, Eigen::Dynamic, 1> w = Eigen::Matrix<S, Eigen::Dynamic, 1>::Ones(6);
  ClothCollisionOptions<S> opt;
  opt.thickness = S(1e-3);
  const auto st = cloth_collision_step(F, w, x0, x1, obs, opt);
  EXPECT_TRUE(st.collision_free);
  EXPECT_GE(st.broad.passes, 2);
  EXPECT_GT(double(x1(1, 2)), 0.3);  // A was pushed past B's point
  const auto c = combine(F, x0, x1, obs);
  EXPECT_EQ(cloth_test::all_pairs_ccd_hits(c, 1e-3), 0);
  EXPECT_GE(cloth_test::sampled_min_distance(c), 1e-3);
}

// A piston rises 0.5 in one step under the centroid of a cloth triangle A and lifts it out of its
// envelope, across the lower edge of a still triangle B hanging beside it: A's face sweeps over
// that edge and B's face over an edge of A, while no vertex of either passes the other's face,
// so only edge-edge pairs of a grown edge against a still one find the crossing. A re-gathering
// meets the triangle pair in an order that depends on its tree, so the scene is placed at random
// (seeded: turned, moved, the faces in either order, each triangle's vertices rotated) to meet
// both orders; each step must end with no hit of the all-pairs CCD oracle.
TYPED_TEST(ClothStep, GrownEdgeMeetsAStillEdgeInEitherOrder) {
  using S = TypeParam;
  const double h = 1e-3;
  const Eigen::Vector3d a[3] = {{-0.3, 0, 0.05}, {0.3, 0, 0.05}, {-0.1, -0.3, 0.05}};
  const Eigen::Vector3d b[3] = {{0, -0.4, 0.3}, {0, 0.1, 0.3}, {0.2, -0.15, 0.5}};
  const Eigen::Vector3d p[3] = {{-0.1 / 3, -0.1, 0}, {-0.1 / 3 - 0.05, -0.1, -0.05}, {-0.1 / 3, -0.05, -0.05}};
  std::mt19937 rng(7);
  std::normal_distribution<double> N(0, 1);
  for (int scene = 0; scene < 8; ++scene) {
    SCOPED_TRACE("scene " + std::to_string(scene));
    const Eigen::Matrix3d R = Eigen::Quaterniond(N(rng), N(rng), N(rng), N(rng)).normalized().toRotationMatrix();
    const Eigen::Vector3d shift(0.2 * N(rng), 0.2 * N(rng), 0.2 * N(rng)), up = R.col(2);
    auto place = [&](const Eigen::Vector3d& q, Vertices<S>& X, Eigen::Index row, double lift) {
      X.row(row) = (R * q + shift + lift * up).template cast<S>().transpose();
    };
    const bool a_first = scene % 2 == 0;  // face order
    const int ra = int(rng() % 3), rb = int(rng() % 3);  // each triangle's first vertex
    Vertices<S> x0(6, 3), piston0(3, 3), piston1(3, 3);
    const Eigen::Index oa = a_first ? 0 : 3, ob = a_first ? 3 : 0;
    for (int k = 0; k < 3; ++k) {
      place(a[(k + ra) % 3], x0, oa + k, 0);
      place(b[(k + rb) % 3], x0, ob + k, 0);
      place(p[k], piston0, k, 0);
      place(p[k], piston1, k, 0.5);
    }
    const Faces F = (Faces(2, 3) << 0, 1, 2, 3, 4, 5).finished();
    const Faces piston_faces = (Faces(1, 3) << 0, 1, 2).finished();
    ClothObstacles<S> obs;
    obs.kinematic.push_back({&piston0, &piston1, &piston_faces});
    // A lifted with the piston and nothing else moving crosses B through edge-edge pairs only.
    Vertices<S> lifted = x0;
    for (int k = 0; k < 3; ++k) lifted.row(oa + k) = piston1.row(0) - piston0.row(0) + x0.row(oa + k);
    const auto free = combine(F, x0, lifted, obs);
    ASSERT_GT(cloth_test::all_pairs_ccd_hits(free, h), 0);
    CcdOptions o;
    o.min_separation = h;
    for (const auto& q : cloth_test::unique_pairs(free)) {
      if (q.edge_edge) continue;
      auto at = [&](const Vertices<S>& X, int k) { return Vec3<S>(X.row(q.v[k]).transpose()); };
      ASSERT_FALSE(vertex_face_ccd(at(free.X0, 0), at(free.X0, 1), at(free.X0, 2), at(free.X0, 3), at(free.X1, 0), at(free.X1, 1),
                                   at(free.X1, 2), at(free.X1, 3), o)
                       .hit);
    }
    Vertices<S> x1 = x0;  // both at rest
    Eigen::Matrix<S, Eigen::Dynamic, 1> w = Eigen::Matrix<S, Eigen::Dynamic, 1>::Ones(6);
    ClothCollisionOptions<S> opt;
    opt.thickness = S(h);
    const auto st = cloth_collision_step(F, w, x0, x1, obs, opt);
    EXPECT_TRUE(st.collision_free);
    EXPECT_GE(st.broad.passes, 2);
    EXPECT_GT((x1.row(oa) - x0.row(oa)).template cast<double>().dot(up.transpose()), 0.3);  // A was lifted past B's lower edge
    const auto cmb = combine(F, x0, x1, obs);
    EXPECT_EQ(cloth_test::all_pairs_ccd_hits(cmb, h), 0);
    EXPECT_GE(cloth_test::sampled_min_distance(cmb), h);
  }
}

// A sheet translating rigidly, far from everything: its candidates (neighbours within the
// proximity distance) are gathered once, and every one is settled by the distance bound (distance
// at x0 minus relative motion, here 0, stays above h) without a CCD test; nothing changes.
TYPED_TEST(ClothStep, RigidlyMovingSheetNeedsNoCcd) {
  using S = TypeParam;
  const auto g = make_grid<S>(8, 8, S(1));  // cells of 1/8
  const Vertices<S> x0 = g.V;
  Vertices<S> x1 = x0;
  x1.col(0).array() += S(0.02);
  x1.col(2).array() -= S(0.05);
  const Vertices<S> x1_in = x1;
  Eigen::Matrix<S, Eigen::Dynamic, 1> w = Eigen::Matrix<S, Eigen::Dynamic, 1>::Ones(x0.rows());
  ClothCollisionOptions<S> opt;
  opt.thickness = S(0.04);  // the grown envelopes (h around each swept box) reach the neighbouring cells
  opt.proximity = false;
  const auto st = cloth_collision_step(g.F, w, x0, x1, ClothObstacles<S>{}, opt);
  EXPECT_TRUE(st.collision_free);
  EXPECT_EQ(st.broad.passes, 1);
  EXPECT_GT(st.candidates_vf + st.candidates_ee, 100u);
  EXPECT_EQ(st.ccd_tests, 0u);
  EXPECT_GE(st.ccd_skipped, st.candidates_vf + st.candidates_ee);
  EXPECT_TRUE(x1 == x1_in);
  // The same sheet bending about its middle: pairs across the bend move relative to each other,
  // so they get CCD tests, and over all pairs nothing comes within h.
  Vertices<S> fold = x0;
  for (Eigen::Index i = 0; i < x0.rows(); ++i)
    if (x0(i, 0) > S(0)) fold(i, 2) = S(-2) * x0(i, 0);  // the grid spans [-0.5, 0.5]^2
  const Vertices<S> fold_in = fold;
  const auto st2 = cloth_collision_step(g.F, w, x0, fold, ClothObstacles<S>{}, opt);
  EXPECT_TRUE(st2.collision_free);
  EXPECT_TRUE(fold == fold_in);  // nothing to correct
  EXPECT_EQ(cloth_test::all_pairs_ccd_hits(combine(g.F, x0, fold, ClothObstacles<S>{}), 0.04), 0);
}

/// Two 4 x 4 sheets 1.5 h apart (sheet B above sheet A), one mesh.
template <class S>
struct TwoSheets {
  Faces F;
  Vertices<S> x0;
  Eigen::Index nb = 0;  // the first vertex of sheet B
  explicit TwoSheets(double gap) {
    const auto g = make_grid<S>(4, 4, S(1));
    nb = g.V.rows();
    x0.resize(2 * nb, 3);
    F.resize(2 * g.F.rows(), 3);
    x0.topRows(nb) = g.V;
    x0.bottomRows(nb) = g.V;
    x0.bottomRows(nb).col(2).array() += S(gap);
    F.topRows(g.F.rows()) = g.F;
    F.bottomRows(g.F.rows()) = g.F.array() + static_cast<int>(nb);
  }
};

// Sliding contact: sheet B slides over sheet A by more than a cell in one step, 1.5 h above it.
// The pairs' relative motion (0.3) is far larger than their clearance (0.5 h), so the distance
// bounds fail, but a fixed separating direction (the sheets' normal) proves every pair: no CCD
// runs, nothing changes, and the all-pairs CCD oracle agrees that nothing comes within h. When a
// vertex of sheet A rises through sheet B instead, the same direction does not prove its pairs:
// the CCD runs and the step ends collision-free by the oracle.
TYPED_TEST(ClothStep, SlidingSheetsAreProvedSeparatedWithoutCcd) {
  using S = TypeParam;
  const double h = 0.02;
  const TwoSheets<S> sh(1.5 * h);
  Vertices<S> x1 = sh.x0;
  x1.bottomRows(sh.nb).col(0).array() += S(0.3);
  const Vertices<S> x1_in = x1;
  Eigen::Matrix<S, Eigen::Dynamic, 1> w = Eigen::Matrix<S, Eigen::Dynamic, 1>::Ones(sh.x0.rows());
  ClothCollisionOptions<S> opt;
  opt.thickness = S(h);
  opt.proximity = false;
  ASSERT_EQ(cloth_test::all_pairs_ccd_hits(combine(sh.F, sh.x0, x1, ClothObstacles<S>{}), h), 0);
  const auto st = cloth_collision_step(sh.F, w, sh.x0, x1, ClothObstacles<S>{}, opt);
  EXPECT_TRUE(st.collision_free);
  EXPECT_GT(st.candidates_vf + st.candidates_ee, 50u);
  EXPECT_EQ(st.ccd_tests, 0u);
  EXPECT_TRUE(x1 == x1_in);

  Vertices<S> poke = x1_in;
  poke(6, 2) = S(3 * h);  // an interior vertex of sheet A ends above sheet B
  ASSERT_GT(cloth_test::all_pairs_ccd_hits(combine(sh.F, sh.x0, poke, ClothObstacles<S>{}), h), 0);
  const auto st2 = cloth_collision_step(sh.F, w, sh.x0, poke, ClothObstacles<S>{}, opt);
  EXPECT_TRUE(st2.collision_free);
  EXPECT_GT(st2.ccd_tests, 0u);
  EXPECT_EQ(cloth_test::all_pairs_ccd_hits(combine(sh.F, sh.x0, poke, ClothObstacles<S>{}), h), 0);
}

// Proofs kept across passes: sheet B lands on sheet A at rest (2.5 h above it, moving down by
// 2 h), so the impulse passes move vertices of both sheets by a fraction of h, and the next
// passes list every candidate through them again, the pairs within each sheet among them (a cell
// apart, proved with a large margin in the first pass). Those keep their proof (ccd_kept) instead
// of being tested again; the step ends collision-free by the all-pairs oracles.
TYPED_TEST(ClothStep, ProofsAreKeptAcrossPasses) {
  using S = TypeParam;
  const double h = 0.02;
  const TwoSheets<S> sh(2.5 * h);
  Vertices<S> x1 = sh.x0;
  x1.bottomRows(sh.nb).col(2).array() -= S(2 * h);
  Eigen::Matrix<S, Eigen::Dynamic, 1> w = Eigen::Matrix<S, Eigen::Dynamic, 1>::Ones(sh.x0.rows());
  ClothCollisionOptions<S> opt;
  opt.thickness = S(h);
  opt.proximity = false;
  ASSERT_GT(cloth_test::all_pairs_ccd_hits(combine(sh.F, sh.x0, x1, ClothObstacles<S>{}), h), 0);
  const auto st = cloth_collision_step(sh.F, w, sh.x0, x1, ClothObstacles<S>{}, opt);
  EXPECT_TRUE(st.collision_free);
  EXPECT_FALSE(st.failsafe_used);
  EXPECT_GT(st.impulses.collisions, 0u);
  EXPECT_GT(st.ccd_kept, 0u);
  const auto c = combine(sh.F, sh.x0, x1, ClothObstacles<S>{});
  EXPECT_EQ(cloth_test::all_pairs_ccd_hits(c, h), 0);
  EXPECT_GE(cloth_test::sampled_min_distance(c), h * 0.999);
}

}  // namespace
