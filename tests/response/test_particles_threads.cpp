// SPDX-License-Identifier: MIT
// step_particles on several threads (StepOptions::threads; label "concurrency", also run under
// ThreadSanitizer): the trajectories and the counters are the same, bit for bit, for 1, 2, 3 and 8
// threads and for the hardware default, under backtracking (with the free balls, a distance grid
// and a compact tree, the fast paths that read shared data) and projection, with point particles
// and balls, against a torus mesh inside a box. Also: one ColliderSet stepped from several threads
// at once (const queries on shared colliders).
#include "impact/geometry/mesh_generators.hpp"
#include "impact/response/particle_step.hpp"
#include "support/random.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <thread>

namespace impact {
namespace {

template <class S>
std::vector<Particle<S>> particles_in_box(std::uint64_t seed, std::size_t n) {
  test::Rng rng(seed);
  std::vector<Particle<S>> ps(n);
  for (auto& p : ps) {
    p.position = rng.in_box(Eigen::Vector3d(-1.5, -1.5, -0.6), Eigen::Vector3d(1.5, 1.5, 0.6)).template cast<S>();
    p.velocity = (rng.vec(-1, 1) * 3.0).template cast<S>();
    p.radius = rng.uniform() < 0.3 ? S(0.02) : S(0);
  }
  return ps;
}

template <class S>
void expect_bitwise_equal(const std::vector<Particle<S>>& a, const std::vector<Particle<S>>& b, const char* what) {
  ASSERT_EQ(a.size(), b.size());
  std::size_t differ = 0;
  for (std::size_t i = 0; i < a.size(); ++i)
    differ += std::memcmp(a[i].position.data(), b[i].position.data(), 3 * sizeof(S)) != 0 ||
              std::memcmp(a[i].velocity.data(), b[i].velocity.data(), 3 * sizeof(S)) != 0 || a[i].free_radius != b[i].free_radius;
  EXPECT_EQ(differ, 0u) << what;
}

template <class T> class ParticlesThreads : public ::testing::Test {};
using Scalars = ::testing::Types<float, double>;
TYPED_TEST_SUITE(ParticlesThreads, Scalars);

TYPED_TEST(ParticlesThreads, SameTrajectoriesForEveryThreadCount) {
  using S = TypeParam;
  const MeshBvh<Aabb<S>> torus(make_torus<S>(S(1), S(0.4), 32, 16));
  DistanceGridConfig<S> gcfg;
  gcfg.resolution = 24;
  const DistanceGrid<S> grid(torus, gcfg);
  const CompactBvh compact(torus.tree(), 4);
  const Aabb<S> container(Vec3<S>(S(-2), S(-2), S(-1)), Vec3<S>(S(2), S(2), S(1)));
  for (const Strategy strategy : {Strategy::Backtrack, Strategy::Project}) {
    ColliderSet<S> cs;
    cs.meshes.emplace_back(torus, ColliderSide::TwoSided, Material<S>::elastic());
    cs.meshes[0].strategy = strategy;
    cs.meshes[0].distance_grid = &grid;
    if (strategy == Strategy::Backtrack) cs.meshes[0].compact_tree = &compact;
    cs.boxes.emplace_back(container, ColliderSide::Inside, Material<S>::elastic());
    cs.boxes[0].strategy = Strategy::Backtrack;
    StepOptions<S> opt;
    opt.gravity = Vec3<S>(0, 0, S(-9.81));
    const S dt = S(0.01);
    const auto init = particles_in_box<S>(7, 3000);  // > 512: the parallel path
    std::vector<Particle<S>> ref = init;
    opt.threads = 1;
    StepStats ref_st;
    for (int s = 0; s < 12; ++s) ref_st += step_particles(ref, cs, dt, opt);
    EXPECT_GT(ref_st.impacts + ref_st.projections, 100u);  // the particles do hit things
    for (const int threads : {2, 3, 8, 0}) {
      std::vector<Particle<S>> ps = init;
      opt.threads = threads;
      StepStats st;
      for (int s = 0; s < 12; ++s) st += step_particles(ps, cs, dt, opt);
      expect_bitwise_equal(ps, ref, "threads");
      EXPECT_EQ(st.impacts, ref_st.impacts) << threads;
      EXPECT_EQ(st.projections, ref_st.projections) << threads;
      EXPECT_EQ(st.particles_hit, ref_st.particles_hit) << threads;
      EXPECT_EQ(st.budget_exhausted, ref_st.budget_exhausted) << threads;
    }
  }
}

// One collider set (mesh, grid, compact tree) shared by four threads stepping their own particles.
TEST(ParticlesConcurrency, SharedCollidersFromManyThreads) {
  using S = double;
  const MeshBvh<Aabb<S>> torus(make_torus<S>(1, 0.4, 32, 16));
  DistanceGridConfig<S> gcfg;
  gcfg.resolution = 24;
  const DistanceGrid<S> grid(torus, gcfg);
  const CompactBvh compact(torus.tree(), 4);
  ColliderSet<S> cs;
  cs.meshes.emplace_back(torus, ColliderSide::TwoSided, Material<S>::elastic());
  cs.meshes[0].distance_grid = &grid;
  cs.meshes[0].compact_tree = &compact;
  cs.boxes.emplace_back(Aabb<S>(Vec3<S>(-2, -2, -1), Vec3<S>(2, 2, 1)), ColliderSide::Inside, Material<S>::elastic());
  StepOptions<S> opt;
  opt.threads = 1;
  const auto init = particles_in_box<S>(9, 400);
  std::vector<Particle<S>> ref = init;
  for (int s = 0; s < 10; ++s) step_particles(ref, cs, 0.01, opt);
  std::vector<std::vector<Particle<S>>> out(4, init);
  std::vector<std::thread> pool;
  for (auto& ps : out)
    pool.emplace_back([&] {
      for (int s = 0; s < 10; ++s) step_particles(ps, cs, 0.01, opt);
    });
  for (auto& t : pool) t.join();
  for (const auto& ps : out) expect_bitwise_equal(ps, ref, "shared colliders");
}

}  // namespace
}  // namespace impact
