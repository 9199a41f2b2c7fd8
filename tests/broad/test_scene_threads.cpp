// SPDX-License-Identifier: MIT
// Scene queries from many threads and on many threads (label "concurrency": also run under
// ThreadSanitizer).
//  - Concurrent queries (issue 12, D1): eight threads call find_pairs / collide / any_collision at
//    once on a scene that was just edited (the first query after the edits applies them) and again
//    on the unedited scene; every answer must equal a brute-force pair set written here (world
//    boxes from Scene::bounds, the pair rule of broad_phase.hpp by hand). Before the fix, AllPairs
//    shared its scratch lists between callers (wrong pair sets, a heap use-after-free under ASan)
//    and the tree broad phases flushed their caches inside every query (a data race under TSan).
//  - Parallel queries: find_pairs and collide on 1, 2, 3 and 8 threads give the same pairs and
//    contacts in the same order, bit for bit, and the same work counters, over random edit steps
//    (moves, sleeping, filters, ignored pairs, adds and removes), for every broad phase.
#include "impact/broad/scene.hpp"
#include "scene_fixtures.hpp"
#include "support/random.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cstring>
#include <memory>
#include <thread>
#include <vector>

using namespace impact;
using impact::test::Rng;
using impact::test::octahedron;
using impact::test::pose_at;
using impact::test::sorted_pairs;

namespace {

constexpr BroadPhaseKind kinds[] = {BroadPhaseKind::AllPairs, BroadPhaseKind::StaticDynamic, BroadPhaseKind::Hierarchical};

/// n objects (spheres, boxes, meshes) in a box of side L, a third static, no filters.
struct World {
  std::vector<ObjectId> ids;
  std::vector<bool> is_static;
};

template <class S>
World populate(Scene<S>& s, const MeshBvh<Sphere<S>>& mesh, int n, double L, std::uint64_t seed) {
  Rng rng(seed);
  World w;
  for (int i = 0; i < n; ++i) {
    const double u = rng.uniform();
    const Shape<S> shape = u < 0.5 ? Shape<S>::sphere(S(rng.uniform(0.1, 1.0)))
                           : u < 0.8 ? Shape<S>::box(rng.vec(0.1, 0.8).cast<S>())
                                     : Shape<S>::mesh_of(mesh);
    const bool st = rng.uniform() < 0.35;
    const ObjectId id = ObjectId(1000 + 3 * i);
    s.add(id, shape, pose_at<S>(rng.vec(0, L), rng.rotation()), {st ? BodyType::Static : BodyType::Dynamic});
    w.ids.push_back(id);
    w.is_static.push_back(st);
  }
  return w;
}

/// The oracle: every pair with a dynamic member whose closed world boxes overlap (no filters,
/// nothing sleeping in these scenes), brute force.
template <class S>
std::vector<ObjectPair> brute_force_pairs(const Scene<S>& s, const World& w) {
  std::vector<ObjectPair> out;
  for (std::size_t i = 0; i < w.ids.size(); ++i)
    for (std::size_t j = i + 1; j < w.ids.size(); ++j) {
      if (w.is_static[i] && w.is_static[j]) continue;
      const Aabb<S>& a = s.bounds(w.ids[i]);
      const Aabb<S>& b = s.bounds(w.ids[j]);
      bool hit = true;
      for (int k = 0; k < 3; ++k) hit = hit && a.min[k] <= b.max[k] && b.min[k] <= a.max[k];
      if (hit) out.push_back({std::min(w.ids[i], w.ids[j]), std::max(w.ids[i], w.ids[j])});
    }
  std::sort(out.begin(), out.end());
  return out;
}

/// Runs `queries` from `threads` threads at once (released together) and counts wrong answers.
template <class Q>
int run_concurrently(int threads, Q&& query) {
  std::atomic<int> ready{0}, wrong{0};
  std::vector<std::thread> pool;
  for (int t = 0; t < threads; ++t)
    pool.emplace_back([&] {
      ready.fetch_add(1);
      while (ready.load() < threads) std::this_thread::yield();
      if (!query()) wrong.fetch_add(1);
    });
  for (auto& t : pool) t.join();
  return wrong.load();
}

// D1: concurrent queries on one scene, right after edits and on the unedited scene.
TEST(SceneConcurrency, QueriesFromManyThreadsMatchBruteForce) {
  using S = double;
  const auto mesh = octahedron<S>(S(0.6));
  for (const BroadPhaseKind kind : kinds) {
    SceneOptions o;
    o.broad_phase = kind;
    o.threads = 1;  // the callers' own threads only: the serial query path
    Scene<S> scene(o);
    const World w = populate(scene, *mesh, 400, 14.0, 11);
    Rng rng(5);
    for (int round = 0; round < 3; ++round) {
      // Edits (not concurrent), then queries from 8 threads; the first of them applies the edits.
      for (std::size_t i = 0; i < w.ids.size(); ++i)
        if (!w.is_static[i] && rng.uniform() < 0.5)
          scene.set_pose(w.ids[i], pose_at<S>(scene.pose(w.ids[i]).t + rng.vec(-0.7, 0.7), rng.rotation()));
      if (round == 2) scene.set_pose(w.ids[0], pose_at<S>(rng.vec(0, 14)));  // maybe a static one
      const auto expect = brute_force_pairs(scene, w);
      ASSERT_GT(expect.size(), 50u);
      // the narrow phase's answer, serially, after the concurrent rounds below have run
      std::vector<ObjectPair> colliding;
      for (int pass = 0; pass < 2; ++pass) {
        const int wrong = run_concurrently(8, [&] {
          bool ok = true;
          for (int rep = 0; rep < 2; ++rep) {
            ok = ok && sorted_pairs(scene.find_pairs().pairs) == expect;
            std::vector<ObjectPair> seen;
            BroadPhaseStats st;
            scene.for_each_pair(
                [&](ObjectId a, ObjectId b) {
                  seen.push_back({a, b});
                  return true;
                },
                st);
            ok = ok && sorted_pairs(seen) == expect;
          }
          return ok;
        });
        EXPECT_EQ(wrong, 0) << "broad phase " << int(kind) << " round " << round << " pass " << pass;
      }
      colliding = sorted_pairs(scene.collide().pairs);
      ASSERT_FALSE(colliding.empty());
      const int wrong = run_concurrently(8, [&] {
        SceneCollideOptions c;
        c.contacts = true;
        const auto r = scene.collide(c);
        return sorted_pairs(r.pairs) == colliding && r.contacts.size() == r.pairs.size() && scene.any_collision();
      });
      EXPECT_EQ(wrong, 0) << "collide, broad phase " << int(kind) << " round " << round;
    }
  }
}

/// Bitwise equality of two results (pairs, contacts and counters, in order).
template <class S>
void expect_same(const SceneCollideResult<S>& a, const SceneCollideResult<S>& b, const char* what) {
  ASSERT_EQ(a.colliding, b.colliding) << what;
  ASSERT_EQ(a.pairs, b.pairs) << what;
  ASSERT_EQ(a.contacts.size(), b.contacts.size()) << what;
  for (std::size_t k = 0; k < a.contacts.size(); ++k) {
    ASSERT_EQ(a.contacts[k].a, b.contacts[k].a) << what;
    ASSERT_EQ(a.contacts[k].b, b.contacts[k].b) << what;
    ASSERT_EQ(0, std::memcmp(a.contacts[k].contact.point.data(), b.contacts[k].contact.point.data(), 3 * sizeof(S))) << what;
    ASSERT_EQ(0, std::memcmp(a.contacts[k].contact.normal.data(), b.contacts[k].contact.normal.data(), 3 * sizeof(S))) << what;
    ASSERT_EQ(0, std::memcmp(&a.contacts[k].contact.depth, &b.contacts[k].contact.depth, sizeof(S))) << what;
  }
}

void expect_same_stats(const BroadPhaseStats& a, const BroadPhaseStats& b, const char* what) {
  EXPECT_EQ(a.bv_tests, b.bv_tests) << what;
  EXPECT_EQ(a.pairs_tested, b.pairs_tested) << what;
  EXPECT_EQ(a.pairs_filtered, b.pairs_filtered) << what;
  EXPECT_EQ(a.pairs_found, b.pairs_found) << what;
  EXPECT_EQ(a.refits, b.refits) << what;
  EXPECT_EQ(a.reinserts, b.reinserts) << what;
  EXPECT_EQ(a.static_queries, b.static_queries) << what;
  EXPECT_EQ(a.rebuilds, b.rebuilds) << what;
  EXPECT_EQ(a.narrow_tests, b.narrow_tests) << what;
  EXPECT_EQ(a.contacts, b.contacts) << what;
}

template <class S>
class SceneThreadsTyped : public ::testing::Test {};
using Scalars = ::testing::Types<float, double>;
TYPED_TEST_SUITE(SceneThreadsTyped, Scalars);

// The same answers, in the same order, for 1, 2, 3 and 8 threads, over random edits.
TYPED_TEST(SceneThreadsTyped, ResultsDoNotDependOnThreadCount) {
  using S = TypeParam;
  const auto mesh = octahedron<S>(S(0.6));
  const int counts[] = {1, 2, 3, 8};
  for (const BroadPhaseKind kind : kinds) {
    std::vector<Scene<S>> scenes;
    for (const int t : counts) {
      SceneOptions o;
      o.broad_phase = kind;
      o.threads = t;
      o.parallel_min_objects = 0;  // parallel however small
      scenes.emplace_back(o);
    }
    ASSERT_EQ(scenes[0].query_threads(), 1);
    ASSERT_EQ(scenes[3].query_threads(), 8);
    World w;
    for (auto& s : scenes) w = populate(s, *mesh, 700, 16.0, 21);
    Rng rng(3);
    for (int step = 0; step < 4; ++step) {
      // the same edits on every scene
      for (int e = 0; e < 120; ++e) {
        const std::size_t i = rng.index(w.ids.size());
        const ObjectId id = w.ids[i];
        const double u = rng.uniform();
        if (u < 0.75) {
          const auto p = pose_at<S>(scenes[0].pose(id).t.template cast<double>() + rng.vec(-1, 1), rng.rotation());
          for (auto& s : scenes) s.set_pose(id, p);
        } else if (u < 0.85 && !w.is_static[i]) {
          const bool sleep = rng.uniform() < 0.5;
          for (auto& s : scenes) s.set_sleeping(id, sleep);
        } else if (u < 0.93) {
          const ObjectId other = w.ids[rng.index(w.ids.size())];
          if (other != id)
            for (auto& s : scenes) s.ignore_pair(id, other);
        } else {
          const CollisionFilter f{1u + std::uint32_t(rng.index(3)), 0xffffffffu ^ std::uint32_t(rng.index(4))};
          for (auto& s : scenes) s.set_filter(id, f);
        }
      }
      if (step == 2) {  // remove a few
        for (int k = 0; k < 5; ++k) {
          const std::size_t i = rng.index(w.ids.size());
          for (auto& s : scenes) s.remove(w.ids[i]);
          w.ids.erase(w.ids.begin() + std::ptrdiff_t(i));
          w.is_static.erase(w.is_static.begin() + std::ptrdiff_t(i));
        }
      }
      const PairResult ref = scenes[0].find_pairs();
      ASSERT_GT(ref.pairs.size(), 100u);
      for (std::size_t k = 1; k < scenes.size(); ++k) {
        const PairResult r = scenes[k].find_pairs();
        ASSERT_EQ(r.pairs, ref.pairs) << "kind " << int(kind) << " threads " << counts[k] << " step " << step;
        expect_same_stats(r.stats, ref.stats, "find_pairs");
      }
      SceneCollideOptions c;
      c.contacts = true;
      const auto cref = scenes[0].collide(c);
      ASSERT_GT(cref.pairs.size(), 10u);
      SceneCollideOptions first;
      first.stop_at_first = true;
      const auto fref = scenes[0].collide(first);
      ASSERT_EQ(fref.pairs.size(), 1u);
      for (std::size_t k = 1; k < scenes.size(); ++k) {
        const auto r = scenes[k].collide(c);
        expect_same(r, cref, "collide");
        expect_same_stats(r.stats, cref.stats, "collide");
        const auto f = scenes[k].collide(first);
        expect_same(f, fref, "stop_at_first");
        expect_same_stats(f.stats, fref.stats, "stop_at_first");
      }
    }
  }
}

// Scenes below parallel_min_objects stay serial; an empty scene and one object are fine.
TEST(SceneThreads, SmallScenesAndEdges) {
  SceneOptions o;
  o.threads = 8;
  o.parallel_min_objects = 0;
  for (const BroadPhaseKind kind : kinds) {
    o.broad_phase = kind;
    Scene<double> s(o);
    EXPECT_TRUE(s.find_pairs().pairs.empty());
    EXPECT_FALSE(s.any_collision());
    s.add(1, Shape<double>::sphere(1), pose_at<double>(Eigen::Vector3d::Zero()));
    EXPECT_TRUE(s.find_pairs().pairs.empty());
    s.add(2, Shape<double>::sphere(1), pose_at<double>(Eigen::Vector3d(1, 0, 0)), {BodyType::Static});
    const auto r = s.find_pairs();
    ASSERT_EQ(r.pairs.size(), 1u);
    EXPECT_EQ(r.pairs[0], (ObjectPair{1, 2}));
    EXPECT_TRUE(s.any_collision());
  }
  SceneOptions d;
  Scene<double> s(d);
  EXPECT_EQ(s.query_threads(), 1);  // empty: below the default parallel_min_objects
  s.set_threads(1);
  EXPECT_EQ(s.query_threads(), 1);
}

}  // namespace
