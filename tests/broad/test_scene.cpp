// SPDX-License-Identifier: MIT
// Scene and broad phases: every broad phase returns exactly the pair set of the all-pairs reference
// on random scenes edited over many steps (adds, removes, moves, sleeping, filters, coincident,
// zero-size and scene-spanning objects); the work counters show that skipped work is skipped; bad
// input throws and leaves the scene unchanged; narrow-phase dispatch per pair of kinds.
#include "impact/broad/scene.hpp"
#include "scene_fixtures.hpp"
#include "support/random.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <memory>
#include <set>
#include <tuple>

using namespace impact;
using impact::test::Rng;
using impact::test::octahedron;
using impact::test::pose_at;
using impact::test::sorted_pairs;

namespace {

/// The same edits applied to one scene per broad phase.
template <class S>
struct Scenes {
  std::vector<Scene<S>> s;
  Scenes() {
    for (auto k : {BroadPhaseKind::AllPairs, BroadPhaseKind::StaticDynamic, BroadPhaseKind::Hierarchical}) {
      SceneOptions o;
      o.broad_phase = k;
      s.emplace_back(o);
    }
  }
  template <class F>
  void each(F&& f) {
    for (auto& x : s) f(x);
  }
};

static_assert(is_broad_phase_v<AllPairsBroadPhase<float>, float>);
static_assert(is_broad_phase_v<HierarchicalBroadPhase<double>, double>);
static_assert(!is_broad_phase_v<DynamicTree<double>, double>);

template <class S>
class BroadTyped : public ::testing::Test {};
using Scalars = ::testing::Types<float, double>;
TYPED_TEST_SUITE(BroadTyped, Scalars);

// Random scenes: all broad phases agree with the reference across edit steps.
TYPED_TEST(BroadTyped, RandomScenesMatchReference) {
  using S = TypeParam;
  const auto mesh = octahedron<S>(S(0.6));
  for (std::uint64_t seed : {1u, 2u, 3u, 4u}) {
    Rng rng(seed);
    Scenes<S> sc;
    std::vector<ObjectId> live;
    ObjectId next_id = 100;
    const double L = 20;
    auto random_shape = [&]() {
      const double u = rng.uniform();
      if (u < 0.35) return Shape<S>::sphere(S(rng.uniform() < 0.1 ? 0.0 : rng.uniform(0.05, 2.0)));
      if (u < 0.6) return Shape<S>::box(rng.vec(0, 1.5).cast<S>() * (rng.uniform() < 0.05 ? S(0) : S(1)));
      if (u < 0.8) return Shape<S>::mesh_of(*mesh);
      return Shape<S>::particle(S(rng.uniform() < 0.5 ? 0.0 : 0.1));
    };
    auto add_one = [&](bool coincident_with_last) {
      const ObjectId id = next_id++;
      Shape<S> shape = random_shape();
      RigidTransform<S> pose = pose_at<S>(rng.vec(0, L), rng.rotation());
      if (coincident_with_last && !live.empty()) {
        pose = sc.s[0].pose(live.back());
        shape = sc.s[0].shape(live.back());
      }
      ObjectOptions o;
      o.body = rng.uniform() < 0.6 ? BodyType::Static : BodyType::Dynamic;
      if (rng.uniform() < 0.1) o.filter = {2u, 0xfffffffdu};  // group 2 does not collide with group 2
      if (o.body == BodyType::Dynamic && rng.uniform() < 0.1) o.sleeping = true;
      sc.each([&](Scene<S>& s) { s.add(id, shape, pose, o); });
      live.push_back(id);
    };
    for (int i = 0; i < 300; ++i) add_one(rng.uniform() < 0.05);
    // Two huge objects spanning the scene, one static and one dynamic.
    sc.each([&](Scene<S>& s) {
      s.add(1, Shape<S>::sphere(S(L)), pose_at<S>(Eigen::Vector3d::Constant(L / 2)), {BodyType::Static});
      s.add(2, Shape<S>::box(Vec3<S>::Constant(S(L))), pose_at<S>(Eigen::Vector3d::Constant(L / 2), rng.rotation()));
    });
    for (int step = 0; step < 25; ++step) {
      // Edits
      const int n_edits = 1 + int(rng.index(40));
      for (int e = 0; e < n_edits; ++e) {
        const double u = rng.uniform();
        if (u < 0.1) {
          add_one(rng.uniform() < 0.3);
        } else if (u < 0.18 && !live.empty()) {
          const std::size_t k = rng.index(live.size());
          sc.each([&](Scene<S>& s) { s.remove(live[k]); });
          live.erase(live.begin() + std::ptrdiff_t(k));
        } else if (u < 0.9 && !live.empty()) {
          const ObjectId id = live[rng.index(live.size())];
          const RigidTransform<S> p =
              rng.uniform() < 0.8 ? pose_at<S>(sc.s[0].pose(id).t.template cast<double>() + rng.vec(-1, 1), rng.rotation())
                                  : pose_at<S>(rng.vec(0, L), rng.rotation());
          sc.each([&](Scene<S>& s) { s.set_pose(id, p); });
        } else if (u < 0.95 && !live.empty()) {
          const ObjectId id = live[rng.index(live.size())];
          if (sc.s[0].shape(id).kind == ShapeKind::Mesh) continue;
          const bool sleep = rng.uniform() < 0.5;
          try {
            sc.each([&](Scene<S>& s) { s.set_sleeping(id, sleep); });
          } catch (const InvalidInput&) {  // static: all three threw on the first, none changed
          }
        } else if (live.size() > 1) {
          const ObjectId a = live[rng.index(live.size())], b = live[rng.index(live.size())];
          if (a != b) {
            if (rng.uniform() < 0.7)
              sc.each([&](Scene<S>& s) { s.ignore_pair(a, b); });
            else
              sc.each([&](Scene<S>& s) { s.unignore_pair(a, b); });
          }
        }
        if (rng.uniform() < 0.03 && !live.empty()) {  // change a filter
          const ObjectId id = live[rng.index(live.size())];
          const CollisionFilter f{1u + std::uint32_t(rng.index(3)), 0xffffffffu ^ std::uint32_t(rng.index(4))};
          sc.each([&](Scene<S>& s) { s.set_filter(id, f); });
        }
      }
      const auto ref = sorted_pairs(sc.s[0].find_pairs().pairs);
      EXPECT_GT(ref.size(), 0u);
      EXPECT_TRUE(std::adjacent_find(ref.begin(), ref.end()) == ref.end()) << "duplicate pair in the reference";
      for (std::size_t k = 1; k < sc.s.size(); ++k) {
        const PairResult r = sc.s[k].find_pairs();
        EXPECT_EQ(r.stats.inactive_pairs_tested, 0u);
        ASSERT_EQ(sorted_pairs(r.pairs), ref) << "broad phase " << k << " seed " << seed << " step " << step;
      }
      const auto* sd = sc.s[1].template broad_phase_as<StaticDynamicBroadPhase<S>>();
      const auto* hi = sc.s[2].template broad_phase_as<HierarchicalBroadPhase<S>>();
      ASSERT_TRUE(sd && hi);
      EXPECT_TRUE(sd->dynamic_tree().valid());
      EXPECT_TRUE(hi->static_tree().valid());
      EXPECT_TRUE(hi->dynamic_tree().valid());
      // Narrow phase: same colliding pairs from every broad phase.
      const auto c0 = sorted_pairs(sc.s[0].collide().pairs);
      for (std::size_t k = 1; k < sc.s.size(); ++k) EXPECT_EQ(sorted_pairs(sc.s[k].collide().pairs), c0);
    }
  }
}

// Many objects at exactly the same place, and zero-size ones.
TYPED_TEST(BroadTyped, CoincidentAndZeroSize) {
  using S = TypeParam;
  Scenes<S> sc;
  for (ObjectId i = 0; i < 20; ++i)
    sc.each([&](Scene<S>& s) {
      s.add(i, i % 2 ? Shape<S>::particle() : Shape<S>::box(Vec3<S>::Zero()), pose_at<S>(Eigen::Vector3d(1, 2, 3)),
            {i % 3 == 0 ? BodyType::Static : BodyType::Dynamic});
    });
  const auto ref = sorted_pairs(sc.s[0].find_pairs().pairs);
  // 20 objects, 7 static: all pairs but the static–static ones.
  EXPECT_EQ(ref.size(), std::size_t(20 * 19 / 2 - 7 * 6 / 2));
  for (auto& s : sc.s) EXPECT_EQ(sorted_pairs(s.find_pairs().pairs), ref);
  for (auto& s : sc.s) EXPECT_EQ(s.collide().pairs.size(), ref.size());
}

TYPED_TEST(BroadTyped, AllStaticSceneCostsNothing) {
  using S = TypeParam;
  Scenes<S> sc;
  Rng rng(7);
  for (ObjectId i = 0; i < 500; ++i) {
    const auto p = pose_at<S>(rng.vec(0, 10));
    sc.each([&](Scene<S>& s) { s.add(i, Shape<S>::sphere(S(1)), p, {BodyType::Static}); });
  }
  for (auto& s : sc.s) {
    s.find_pairs();  // builds the static tree
    for (int step = 0; step < 3; ++step) {
      const PairResult r = s.find_pairs();
      EXPECT_TRUE(r.pairs.empty());
      EXPECT_EQ(r.stats.pairs_tested, 0u);
      EXPECT_EQ(r.stats.bv_tests, 0u);
      EXPECT_EQ(r.stats.refits, 0u);
      EXPECT_EQ(r.stats.static_queries, 0u);
      EXPECT_EQ(r.stats.rebuilds, 0u);
    }
  }
}

TYPED_TEST(BroadTyped, UnmovedObjectsAreNotRefittedOrRequeried) {
  using S = TypeParam;
  Scenes<S> sc;
  Rng rng(11);
  for (ObjectId i = 0; i < 400; ++i) {
    const auto p = pose_at<S>(rng.vec(0, 10));
    sc.each([&](Scene<S>& s) { s.add(i, Shape<S>::sphere(S(0.5)), p, {i < 300 ? BodyType::Static : BodyType::Dynamic}); });
  }
  for (auto& s : sc.s) s.find_pairs();
  // Nothing moved: no refit, no static query.
  for (auto& s : sc.s) {
    const auto st = s.find_pairs().stats;
    EXPECT_EQ(st.refits, 0u);
    EXPECT_EQ(st.static_queries, 0u);
    EXPECT_EQ(st.inactive_pairs_tested, 0u);
  }
  // Five dynamic objects move (one of them twice): five refits, five static queries.
  for (ObjectId i : {300u, 310u, 320u, 330u, 340u, 300u}) {
    const auto p = pose_at<S>(rng.vec(0, 10));
    sc.each([&](Scene<S>& s) { s.set_pose(i, p); });
  }
  const auto sd = sc.s[1].find_pairs().stats;
  EXPECT_EQ(sd.refits, 5u);
  EXPECT_LE(sd.static_queries, 5u);  // only those that left their fat box query the static tree
  const auto hi = sc.s[2].find_pairs().stats;
  EXPECT_EQ(hi.refits, 5u);
  EXPECT_LE(hi.reinserts, 5u);
  // And the next call again does nothing for them.
  EXPECT_EQ(sc.s[1].find_pairs().stats.static_queries, 0u);
}

// Dynamic objects that never move keep their static candidates cached (static/dynamic and
// hierarchical): a static object added next to one, moved onto one, moved away, refiltered or
// removed must still change their pairs, and in the hierarchical broad phase only the dynamic
// objects near the edit query the static tree again.
TYPED_TEST(BroadTyped, StaticEditsReachRestingObjects) {
  using S = TypeParam;
  Scenes<S> sc;
  for (ObjectId i = 0; i < 40; ++i)  // dynamic spheres on a line, 3 apart, never moving
    sc.each([&](Scene<S>& s) { s.add(i, Shape<S>::sphere(S(0.5)), pose_at<S>(Eigen::Vector3d(3.0 * double(i), 0, 0))); });
  for (ObjectId i = 0; i < 40; ++i)  // static spheres far above them
    sc.each([&](Scene<S>& s) {
      s.add(100 + i, Shape<S>::sphere(S(0.5)), pose_at<S>(Eigen::Vector3d(3.0 * double(i), 10, 0)), {BodyType::Static});
    });
  auto check = [&](const char* what, std::size_t expected) {
    const auto ref = sorted_pairs(sc.s[0].find_pairs().pairs);
    EXPECT_EQ(ref.size(), expected) << what;
    for (std::size_t k = 1; k < sc.s.size(); ++k) EXPECT_EQ(sorted_pairs(sc.s[k].find_pairs().pairs), ref) << what << ", broad phase " << k;
  };
  check("start", 0);
  const auto requeries = [&] { return sc.s[2].find_pairs().stats.static_queries; };
  sc.each([&](Scene<S>& s) { s.add(200, Shape<S>::sphere(S(0.5)), pose_at<S>(Eigen::Vector3d(0.5, 0, 0)), {BodyType::Static}); });
  EXPECT_LE(requeries(), 2u);  // objects 0 and perhaps 1 (fat boxes), not all 40
  check("static added on object 0", 1);
  sc.each([&](Scene<S>& s) { s.set_pose(105, pose_at<S>(Eigen::Vector3d(15.2, 0, 0))); });
  EXPECT_LE(requeries(), 2u);
  check("static moved onto object 5", 2);
  sc.each([&](Scene<S>& s) { s.set_pose(105, pose_at<S>(Eigen::Vector3d(15.2, 0, 5))); });
  check("static moved away from object 5", 1);
  sc.each([&](Scene<S>& s) { s.set_pose(105, pose_at<S>(Eigen::Vector3d(21.2, 0, 0))); });
  check("static moved onto object 7", 2);
  sc.each([&](Scene<S>& s) { s.set_filter(200, {1u, 0u}); });
  check("static refiltered", 1);
  sc.each([&](Scene<S>& s) { s.set_filter(200, {1u, 1u}); });
  check("static filter restored", 2);
  sc.each([&](Scene<S>& s) { s.remove(105); });
  check("static removed", 1);
  sc.each([&](Scene<S>& s) {  // its slot reused by a static object on object 9
    s.add(300, Shape<S>::sphere(S(0.5)), pose_at<S>(Eigen::Vector3d(27.3, 0, 0)), {BodyType::Static});
  });
  check("static added in a reused slot", 2);
  sc.each([&](Scene<S>& s) { s.remove(300); });
  check("static removed again", 1);
}

TYPED_TEST(BroadTyped, SleepingObjectsAreSkipped) {
  using S = TypeParam;
  Scenes<S> sc;
  for (ObjectId i = 0; i < 50; ++i)  // all overlapping, half static, half dynamic and asleep
    sc.each([&](Scene<S>& s) {
      s.add(i, Shape<S>::sphere(S(1)), pose_at<S>(Eigen::Vector3d(0.01 * double(i), 0, 0)),
            {i < 25 ? BodyType::Static : BodyType::Dynamic, {}, i >= 25});
    });
  for (auto& s : sc.s) {
    const PairResult r = s.find_pairs();
    EXPECT_TRUE(r.pairs.empty());
    EXPECT_EQ(r.stats.pairs_tested, 0u);
    EXPECT_EQ(r.stats.static_queries, 0u);
  }
  // Waking one: it pairs with everything else (49 pairs), nothing more is tested.
  sc.each([&](Scene<S>& s) { s.set_sleeping(30, false); });
  for (auto& s : sc.s) {
    const PairResult r = s.find_pairs();
    EXPECT_EQ(r.pairs.size(), 49u);
    EXPECT_EQ(r.stats.inactive_pairs_tested, 0u);
    if (s.broad_phase() != BroadPhaseKind::AllPairs) {
      EXPECT_LE(r.stats.pairs_tested, 49u);
    }
  }
}

TYPED_TEST(BroadTyped, FilteredPairsDroppedBeforeGeometry) {
  using S = TypeParam;
  Scenes<S> sc;
  sc.each([&](Scene<S>& s) {
    s.add(1, Shape<S>::sphere(S(1)), pose_at<S>(Eigen::Vector3d::Zero()), {BodyType::Dynamic, {1u, 1u}});
    s.add(2, Shape<S>::sphere(S(1)), pose_at<S>(Eigen::Vector3d::Zero()), {BodyType::Dynamic, {2u, 2u}});  // masks exclude 1
    s.add(3, Shape<S>::sphere(S(1)), pose_at<S>(Eigen::Vector3d::Zero()), {BodyType::Static, {1u, 1u}});
    s.ignore_pair(1, 3);
  });
  for (auto& s : sc.s) {
    const auto r = s.collide();
    EXPECT_FALSE(r.colliding);
    EXPECT_EQ(r.stats.pairs_filtered, 3u);  // {1,2}, {2,3} by masks, {1,3} ignored
    EXPECT_EQ(r.stats.pairs_tested, 0u);
    EXPECT_EQ(r.stats.narrow_tests, 0u);
  }
  // Removing an object clears its ignore entries: a new object under id 3 collides with 1.
  sc.each([&](Scene<S>& s) {
    s.remove(3);
    s.add(3, Shape<S>::sphere(S(1)), pose_at<S>(Eigen::Vector3d::Zero()), {BodyType::Static, {1u, 1u}});
  });
  for (auto& s : sc.s) EXPECT_EQ(s.collide().pairs, (std::vector<ObjectPair>{{1, 3}}));
  // ignore, then unignore; then a filter change on the static object
  for (auto& s : sc.s) {
    s.ignore_pair(3, 1);
    EXPECT_TRUE(s.find_pairs().pairs.empty());
    s.unignore_pair(1, 3);
    EXPECT_EQ(s.find_pairs().pairs, (std::vector<ObjectPair>{{1, 3}}));
    s.set_filter(3, {1u, 0u});
    EXPECT_TRUE(s.find_pairs().pairs.empty());
    s.set_filter(3, {1u, 1u});
    EXPECT_EQ(s.find_pairs().pairs, (std::vector<ObjectPair>{{1, 3}}));
  }
}

TYPED_TEST(BroadTyped, BooleanQueryStopsAtFirstHitAndContactsOnlyWhenAsked) {
  using S = TypeParam;
  Scenes<S> sc;
  for (ObjectId i = 0; i < 30; ++i)
    sc.each([&](Scene<S>& s) { s.add(i, Shape<S>::sphere(S(1)), pose_at<S>(Eigen::Vector3d(0.05 * double(i), 0, 0))); });
  for (auto& s : sc.s) {
    BroadPhaseStats st;
    EXPECT_TRUE(s.any_collision(&st));
    EXPECT_EQ(st.narrow_tests, 1u);
    EXPECT_EQ(st.pairs_found, 1u);
    EXPECT_EQ(st.contacts, 0u);
    const auto plain = s.collide();
    EXPECT_EQ(plain.pairs.size(), 30u * 29u / 2u);
    EXPECT_TRUE(plain.contacts.empty());
    EXPECT_EQ(plain.stats.contacts, 0u);
    SceneCollideOptions o;
    o.contacts = true;
    const auto with = s.collide(o);
    EXPECT_EQ(with.contacts.size(), with.pairs.size());
    EXPECT_EQ(with.stats.contacts, with.pairs.size());
  }
}

TYPED_TEST(BroadTyped, BadInputThrowsAndLeavesSceneUnchanged) {
  using S = TypeParam;
  const auto mesh = octahedron<S>(S(1));
  for (auto kind : {BroadPhaseKind::AllPairs, BroadPhaseKind::StaticDynamic, BroadPhaseKind::Hierarchical}) {
    SceneOptions o;
    o.broad_phase = kind;
    Scene<S> s(o);
    s.add(1, Shape<S>::sphere(S(1)), pose_at<S>(Eigen::Vector3d::Zero()));
    s.add(2, Shape<S>::mesh_of(*mesh), pose_at<S>(Eigen::Vector3d(1, 0, 0)), {BodyType::Static});
    s.add(3, Shape<S>::box(Vec3<S>::Ones()), pose_at<S>(Eigen::Vector3d(0, 1, 0)));
    const auto before = sorted_pairs(s.find_pairs().pairs);
    const auto pose1 = s.pose(1);
    RigidTransform<S> nan_pose = pose_at<S>(Eigen::Vector3d::Zero());
    nan_pose.t.x() = std::numeric_limits<S>::quiet_NaN();
    RigidTransform<S> scaled = pose_at<S>(Eigen::Vector3d::Zero());
    scaled.R *= S(2);
    RigidTransform<S> mirrored = pose_at<S>(Eigen::Vector3d::Zero());
    mirrored.R(0, 0) = S(-1);
    RigidTransform<S> inf_rot = pose_at<S>(Eigen::Vector3d::Zero());
    inf_rot.R(1, 2) = std::numeric_limits<S>::infinity();
    EXPECT_THROW(s.set_pose(1, nan_pose), InvalidInput);
    EXPECT_THROW(s.set_pose(1, inf_rot), InvalidInput);
    EXPECT_THROW(s.set_pose(1, scaled), InvalidInput);
    EXPECT_THROW(s.set_pose(1, mirrored), InvalidInput);
    EXPECT_THROW(s.add(4, Shape<S>::sphere(S(1)), nan_pose), InvalidInput);
    EXPECT_THROW(s.add(1, Shape<S>::sphere(S(1)), pose1), InvalidInput);  // duplicate id
    EXPECT_THROW(s.add(4, Shape<S>::sphere(S(-1)), pose1), InvalidInput);
    EXPECT_THROW(s.add(4, Shape<S>::sphere(std::numeric_limits<S>::quiet_NaN()), pose1), InvalidInput);
    EXPECT_THROW(s.add(4, Shape<S>::particle(std::numeric_limits<S>::infinity()), pose1), InvalidInput);
    EXPECT_THROW(s.add(4, Shape<S>::box(Vec3<S>(1, -1, 1)), pose1), InvalidInput);
    EXPECT_THROW(s.add(4, Shape<S>::box(Vec3<S>(1, std::numeric_limits<S>::quiet_NaN(), 1)), pose1), InvalidInput);
    Shape<S> null_mesh;
    null_mesh.kind = ShapeKind::Mesh;
    EXPECT_THROW(s.add(4, null_mesh, pose1), InvalidInput);
    EXPECT_THROW(s.set_pose(99, pose1), InvalidInput);
    EXPECT_THROW(s.set_position(99, Vec3<S>::Zero()), InvalidInput);
    EXPECT_THROW(s.remove(99), InvalidInput);
    EXPECT_THROW(s.set_sleeping(99, true), InvalidInput);
    EXPECT_THROW(s.set_sleeping(2, true), InvalidInput);  // static
    EXPECT_THROW(s.ignore_pair(1, 1), InvalidInput);
    EXPECT_THROW(s.ignore_pair(1, 99), InvalidInput);
    EXPECT_THROW(s.set_filter(99, {}), InvalidInput);
    EXPECT_THROW(s.bounds(99), InvalidInput);
    EXPECT_EQ(s.size(), 3u);
    EXPECT_FALSE(s.contains(4));
    EXPECT_EQ(s.pose(1).t, pose1.t);
    EXPECT_EQ(sorted_pairs(s.find_pairs().pairs), before);
    // A rotation rounded to float is still a rotation for a double scene.
    const Eigen::Matrix3f rf = Eigen::AngleAxisf(0.3f, Eigen::Vector3f(1, 2, 3).normalized()).toRotationMatrix();
    EXPECT_NO_THROW(s.set_pose(3, RigidTransform<S>(rf.cast<S>(), Vec3<S>(0, 1, 0))));
    // Removing twice
    s.remove(3);
    EXPECT_THROW(s.remove(3), InvalidInput);
    EXPECT_EQ(s.size(), 2u);
    EXPECT_EQ(sorted_pairs(s.find_pairs().pairs), (std::vector<ObjectPair>{{1, 2}}));
  }
}

// DynamicTree on its own: random inserts, removals and moves keep it valid and its self pairs
// (with the exact box test applied) equal to brute force.
TEST(DynamicTree, RandomEditsStayValidAndBalanced) {
  Rng rng(5);
  DynamicTree<double> tree;
  std::vector<std::int32_t> leaf(1000, -1);
  std::vector<Aabb<double>> box(1000);
  for (int i = 0; i < 1000; ++i) {
    const Eigen::Vector3d c = rng.vec(0, 50), e = rng.vec(0, 1);
    box[std::size_t(i)] = {c - e, c + e};
    leaf[std::size_t(i)] = tree.insert(i, box[std::size_t(i)], i % 2 == 0);
  }
  ASSERT_TRUE(tree.valid());
  {  // incremental insertion with rotations builds a tree close to a top-down build
    DynamicTree<double> rebuilt = tree;
    rebuilt.rebuild();
    ASSERT_TRUE(rebuilt.valid());
    EXPECT_LE(tree.sah_cost(), 1.5 * rebuilt.sah_cost());
    EXPECT_LE(tree.height(), 3 * 10);
  }
  for (int round = 0; round < 20; ++round) {
    for (int k = 0; k < 100; ++k) {
      const std::size_t i = rng.index(1000);
      if (leaf[i] >= 0 && rng.uniform() < 0.2) {
        tree.remove(leaf[i]);
        leaf[i] = -1;
      } else if (leaf[i] < 0) {
        leaf[i] = tree.insert(std::int32_t(i), box[i], i % 2 == 0);
      } else {
        const Eigen::Vector3d d = rng.vec(-2, 2);
        box[i] = {box[i].min + d, box[i].max + d};
        tree.update(leaf[i], box[i]);
      }
    }
    tree.maybe_rebuild();
    ASSERT_TRUE(tree.valid());
    std::set<std::pair<int, int>> got, want;
    BroadPhaseStats st;
    tree.self_pairs(
        [&](std::int32_t a, std::int32_t b) {
          if (overlap(box[std::size_t(a)], box[std::size_t(b)])) got.insert({std::min(a, b), std::max(a, b)});
          return true;
        },
        st);
    for (int a = 0; a < 1000; ++a)
      for (int b = a + 1; b < 1000; ++b)
        if (leaf[std::size_t(a)] >= 0 && leaf[std::size_t(b)] >= 0 && (a % 2 == 0 || b % 2 == 0) &&
            overlap(box[std::size_t(a)], box[std::size_t(b)]))
          want.insert({a, b});
    EXPECT_FALSE(want.empty());
    ASSERT_EQ(got, want);
  }
  tree.rebuild();
  EXPECT_TRUE(tree.valid());
}

// DynamicTree::fresh_pairs: after random edits, the pairs of overlapping fat boxes with at least
// one fresh leaf (inserted or reinserted since the last call, active or not, including leaves
// removed and node ids reused in between), each once, as brute force finds them; and on 2 or 3
// threads (a second tree under the same edits) the same calls in the same order, the same counts.
TEST(DynamicTree, FreshPairsAreThePairsOfFreshLeaves) {
  Rng rng(9);
  DynamicTree<double> tree, twin;  // twin: fresh_pairs on several threads
  const int n = 600;
  std::vector<std::int32_t> leaf(n, -1);
  std::vector<bool> fresh(n, false);
  auto insert = [&](int i) {
    const Eigen::Vector3d c = rng.vec(0, 30), e = rng.vec(0, 1);
    leaf[std::size_t(i)] = tree.insert(i, {c - e, c + e}, i % 3 == 0);
    ASSERT_EQ(twin.insert(i, {c - e, c + e}, i % 3 == 0), leaf[std::size_t(i)]);
    tree.mark_fresh(leaf[std::size_t(i)]);
    twin.mark_fresh(leaf[std::size_t(i)]);
    fresh[std::size_t(i)] = true;
  };
  for (int i = 0; i < n; ++i) insert(i);
  for (int round = 0; round < 12; ++round) {
    std::vector<std::pair<int, int>> got, got_twin;
    BroadPhaseStats st, st_twin;
    tree.fresh_pairs([&](std::int32_t a, std::int32_t b) { got.push_back({a, b}); }, st);
    twin.fresh_pairs([&](std::int32_t a, std::int32_t b) { got_twin.push_back({a, b}); }, st_twin, 2 + round % 2);
    ASSERT_EQ(got_twin, got) << "round " << round;
    EXPECT_EQ(st_twin.bv_tests, st.bv_tests);
    for (auto& pr : got)
      if (pr.first > pr.second) std::swap(pr.first, pr.second);
    std::sort(got.begin(), got.end());
    std::vector<std::pair<int, int>> want;
    for (int a = 0; a < n; ++a)
      for (int b = a + 1; b < n; ++b)
        if (leaf[std::size_t(a)] >= 0 && leaf[std::size_t(b)] >= 0 && (fresh[std::size_t(a)] || fresh[std::size_t(b)]) &&
            overlap(tree.box(leaf[std::size_t(a)]), tree.box(leaf[std::size_t(b)])))
          want.push_back({a, b});
    EXPECT_FALSE(want.empty());
    ASSERT_EQ(got, want) << "round " << round;
    std::fill(fresh.begin(), fresh.end(), false);
    for (int k = 0; k < 240; ++k) {
      const std::size_t i = rng.index(std::size_t(n));
      const double u = rng.uniform();
      if (leaf[i] >= 0 && u < 0.25) {  // removed, perhaps after being marked
        tree.remove(leaf[i]);
        twin.remove(leaf[i]);
        leaf[i] = -1;
        fresh[i] = false;
      } else if (leaf[i] < 0) {
        insert(int(i));
      } else {
        const Eigen::Vector3d d = rng.vec(-1.5, 1.5);
        const Aabb<double> moved{tree.box(leaf[i]).min + d, tree.box(leaf[i]).max + d};
        const bool reinserted = tree.update(leaf[i], moved);
        ASSERT_EQ(twin.update(leaf[i], moved), reinserted);
        if (reinserted) {
          tree.mark_fresh(leaf[i]);
          twin.mark_fresh(leaf[i]);
          fresh[i] = true;
        }
      }
    }
    tree.maybe_rebuild();
    twin.maybe_rebuild();
    ASSERT_TRUE(tree.valid());
  }
}

// Narrow phase per pair of kinds, with known answers.
TYPED_TEST(BroadTyped, NarrowDispatch) {
  using S = TypeParam;
  const auto mesh = octahedron<S>(S(1));
  const auto sph = Shape<S>::sphere(S(0.5));
  const auto box = Shape<S>::box(Vec3<S>(S(1), S(0.5), S(0.25)));
  const auto msh = Shape<S>::mesh_of(*mesh);
  const auto pt = Shape<S>::particle();
  const auto at = [](double x, double y = 0, double z = 0) { return pose_at<S>(Eigen::Vector3d(x, y, z)); };
  ShapeContact<S> c;
  // sphere–sphere
  EXPECT_TRUE(shapes_intersect(sph, at(0), sph, at(0.9), &c));
  EXPECT_NEAR(double(c.depth), 0.1, 1e-5);
  EXPECT_NEAR(double(c.normal.x()), 1.0, 1e-6);
  EXPECT_TRUE(shapes_intersect(sph, at(0), sph, at(1.0)));  // touching
  EXPECT_FALSE(shapes_intersect(sph, at(0), sph, at(1.01)));
  EXPECT_TRUE(shapes_intersect(pt, at(0.4), sph, at(0)));
  EXPECT_TRUE(shapes_intersect(pt, at(1), pt, at(1)));
  EXPECT_FALSE(shapes_intersect(pt, at(1), pt, at(1.001)));
  // sphere–box, both orders; the normal points from the first towards the second
  EXPECT_TRUE(shapes_intersect(sph, at(1.4), box, at(0), &c));
  EXPECT_NEAR(double(c.depth), 0.1, 1e-5);
  EXPECT_NEAR(double(c.normal.x()), -1.0, 1e-6);
  EXPECT_TRUE(shapes_intersect(box, at(0), sph, at(1.4), &c));
  EXPECT_NEAR(double(c.normal.x()), 1.0, 1e-6);
  EXPECT_FALSE(shapes_intersect(sph, at(1.6), box, at(0)));
  EXPECT_FALSE(shapes_intersect(sph, at(1.4, 0.4, 0.6), box, at(0)));  // near the edge, outside
  EXPECT_TRUE(shapes_intersect(sph, at(0, 0, 0.1), box, at(0), &c));   // centre inside: out through the nearest face
  EXPECT_NEAR(double(c.normal.z()), -1.0, 1e-6);
  // box–box
  EXPECT_TRUE(shapes_intersect(box, at(0), box, at(1.9, 0.9, 0.4), &c));
  EXPECT_NEAR(double(c.depth), 0.1, 1e-5);
  EXPECT_FALSE(shapes_intersect(box, at(0), box, at(2.1)));
  Eigen::Matrix3d rz = Eigen::AngleAxisd(M_PI / 4, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  EXPECT_FALSE(shapes_intersect(box, at(0), box, pose_at<S>(Eigen::Vector3d(0, 1.6, 0), rz)));
  EXPECT_TRUE(shapes_intersect(box, at(0), box, pose_at<S>(Eigen::Vector3d(0, 1.5, 0), rz)));
  // sphere–mesh (surface): touching a vertex, inside (no contact with the surface), outside
  EXPECT_TRUE(shapes_intersect(sph, at(1.45), msh, at(0), &c));
  EXPECT_NEAR(double(c.normal.x()), -1.0, 1e-5);
  EXPECT_TRUE(shapes_intersect(msh, at(0), sph, at(1.45), &c));
  EXPECT_NEAR(double(c.normal.x()), 1.0, 1e-5);
  EXPECT_FALSE(shapes_intersect(sph, at(1.55), msh, at(0)));
  EXPECT_FALSE(shapes_intersect(Shape<S>::sphere(S(0.1)), at(0), msh, at(0)));
  EXPECT_TRUE(shapes_intersect(pt, at(0.5, 0.5, 0), msh, at(0, 0, 0)));  // on the face x + y + z = 1
  // box–mesh
  EXPECT_TRUE(shapes_intersect(box, at(1.9), msh, at(0)));
  EXPECT_FALSE(shapes_intersect(box, at(2.1), msh, at(0)));
  EXPECT_FALSE(shapes_intersect(Shape<S>::box(Vec3<S>::Constant(S(0.1))), at(0), msh, at(0)));  // inside
  EXPECT_TRUE(shapes_intersect(msh, at(0), box, pose_at<S>(Eigen::Vector3d(0, 0, 1.2), rz)));
  // mesh–mesh
  EXPECT_TRUE(shapes_intersect(msh, at(0), msh, at(1.9), &c));
  EXPECT_TRUE(shapes_intersect(msh, at(0), msh, at(2.0)));  // vertex on vertex
  EXPECT_FALSE(shapes_intersect(msh, at(0), msh, at(2.1)));
  EXPECT_TRUE(shapes_intersect(msh, at(0), msh, pose_at<S>(Eigen::Vector3d(1.5, 0, 0), rz)));
  // contacts of the mesh pairs: unit normals pointing from the first shape towards the second
  for (const auto& [sa, sb, pb] :
       {std::make_tuple(box, msh, at(1.9)), std::make_tuple(msh, box, at(1.9)), std::make_tuple(msh, msh, at(1.9)),
        std::make_tuple(sph, msh, at(1.45)), std::make_tuple(msh, sph, at(1.45))}) {
    ShapeContact<S> k;
    ASSERT_TRUE(shapes_intersect(sa, at(0), sb, pb, &k));
    EXPECT_NEAR(double(k.normal.norm()), 1.0, 1e-5);
    EXPECT_GT(double(k.normal.x()), 0.0);
    EXPECT_TRUE(all_finite(k.point));
    EXPECT_GE(double(k.depth), 0.0);
  }
}

// Narrow tests agree with brute force over the triangles (sphere–mesh) and with sampling (box–box).
TYPED_TEST(BroadTyped, NarrowRandomCrossCheck) {
  using S = TypeParam;
  const auto mesh = octahedron<S>(S(1));
  Rng rng(9);
  int hits = 0;
  for (int k = 0; k < 2000; ++k) {
    const auto pose = pose_at<S>(rng.vec(-0.5, 0.5), rng.rotation());
    const Vec3<S> c = rng.vec(-2, 2).cast<S>();
    const S r = S(rng.uniform(0, 1));
    const bool got =
        shapes_intersect(Shape<S>::sphere(r), RigidTransform<S>(Mat3<S>::Identity(), c), Shape<S>::mesh_of(*mesh), pose);
    const Vec3<S> lc = pose.R.transpose() * (c - pose.t);
    S best = std::numeric_limits<S>::infinity();
    for (int t = 0; t < mesh->num_triangles(); ++t) {
      const auto& tri = mesh->triangle(t);
      best = std::min(best, std::sqrt(closest_point_on_triangle(lc, tri).squared_distance));
    }
    if (std::abs(best - r) > S(1e-4)) {
      EXPECT_EQ(got, best <= r) << k;
    }
    hits += got;
  }
  EXPECT_GT(hits, 100);
  // mesh–mesh and box–mesh against brute force over the triangles
  int mm_hits = 0, bm_hits = 0;
  const Vec3<S> h(S(0.6), S(0.3), S(0.2));
  for (int k = 0; k < 1000; ++k) {
    const auto pa = pose_at<S>(rng.vec(-0.5, 0.5), rng.rotation());
    const auto pb = pose_at<S>(rng.vec(-1.5, 1.5), rng.rotation());
    const RigidTransform<S> b_to_a = relative_transform(pa, pb);
    bool want = false, want_box = false;
    for (int i = 0; i < mesh->num_triangles(); ++i) {
      const auto& tb = mesh->triangle(i);
      const Triangle<S> tb_in_a(b_to_a.apply(tb.a), b_to_a.apply(tb.b), b_to_a.apply(tb.c));
      for (int j = 0; j < mesh->num_triangles(); ++j) want = want || triangles_intersect(mesh->triangle(j), tb_in_a);
      // box at pa, mesh at pb: triangle in the box frame
      want_box = want_box || detail::triangle_box_overlap(tb_in_a.a, tb_in_a.b, tb_in_a.c, h);
    }
    EXPECT_EQ(shapes_intersect(Shape<S>::mesh_of(*mesh), pa, Shape<S>::mesh_of(*mesh), pb), want) << k;
    EXPECT_EQ(shapes_intersect(Shape<S>::box(h), pa, Shape<S>::mesh_of(*mesh), pb), want_box) << k;
    mm_hits += want;
    bm_hits += want_box;
  }
  EXPECT_GT(mm_hits, 100);
  EXPECT_GT(bm_hits, 100);
}

}  // namespace
