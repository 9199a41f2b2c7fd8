// SPDX-License-Identifier: MIT
// Stale free balls (response/particle_step.hpp, Particle::free_center / free_radius): a ball is
// computed for one collider set and one particle radius; when the set changes between calls (a
// mesh's pose moves, its vertices are edited in place, a collider is added) or the particle's
// radius grows, a ball kept from before must not let any leg skip its collision tests. Also legs that end exactly on a ball's boundary.
// The oracle is exact: an axis-aligned box mesh (half extents 1, translated by dyadic amounts, so
// its world coordinates are exact) is closed and two-sided, so every particle keeps its side, and
// whether a point is inside the box is a comparison of coordinates.
#include "impact/response/particle_step.hpp"
#include "support/random.hpp"

#include <gtest/gtest.h>

#include "support/sanitizer.hpp"

namespace impact {
namespace {

using StaleS = double;

/// Whether x is strictly inside the box [c - 1, c + 1]^3.
bool inside_unit_box(const Vec3<StaleS>& x, const Vec3<StaleS>& c) {
  return std::abs(x.x() - c.x()) < 1 && std::abs(x.y() - c.y()) < 1 && std::abs(x.z() - c.z()) < 1;
}

/// Distance from x to the surface of the box [c - 1, c + 1]^3.
StaleS distance_to_unit_box(const Vec3<StaleS>& x, const Vec3<StaleS>& c) {
  const Vec3<StaleS> q = (x - c).cwiseAbs() - Vec3<StaleS>::Ones();
  if (q.maxCoeff() <= 0) return -q.maxCoeff();
  return q.cwiseMax(Vec3<StaleS>::Zero()).norm();
}

/// Particles in [-4, 4]^3 with small random velocities (legs of about 1 % of the box: balls hold
/// many of them), none closer than 0.05 to the box at the origin.
std::vector<Particle<StaleS>> stale_particles(int n, std::uint64_t seed) {
  test::Rng rng(seed);
  std::vector<Particle<StaleS>> ps;
  while (int(ps.size()) < n) {
    Particle<StaleS> p;
    p.position = rng.vec(-4, 4);
    if (distance_to_unit_box(p.position, Vec3<StaleS>::Zero()) < 0.05) continue;
    p.velocity = rng.vec(-1, 1) * 2.0;
    ps.push_back(p);
  }
  return ps;
}

struct StaleScene {
  TriangleMesh<StaleS> box = make_box<StaleS>(Vec3<StaleS>::Ones());
  MeshBvh<Aabb<StaleS>> bvh{box};
  DistanceGrid<StaleS> grid;
  ColliderSet<StaleS> cs;
  explicit StaleScene(bool with_grid) {
    DistanceGridConfig<StaleS> cfg;
    cfg.resolution = 8;
    if (with_grid) grid = DistanceGrid<StaleS>(bvh, cfg);
    cs.meshes.emplace_back(bvh, ColliderSide::TwoSided, Material<StaleS>::elastic());
    if (with_grid) cs.meshes[0].distance_grid = &grid;
  }
};

constexpr StaleS kDt = StaleS(0.01);
const int kStaleParticles = IMPACT_TEST_SANITIZED ? 500 : 3000;

/// Steps every particle `steps` times (step_particles, or step_particle one at a time) and checks
/// that each keeps its side of the box centred at c, and, with a radius, ends no nearer than it.
void expect_sides_kept(std::vector<Particle<StaleS>>& ps, const ColliderSet<StaleS>& cs, const Vec3<StaleS>& c, int steps, bool one_at_a_time,
                       const char* what) {
  StepOptions<StaleS> opt;
  opt.threads = 1;
  std::vector<char> in(ps.size());
  std::vector<char> far(ps.size());
  for (std::size_t i = 0; i < ps.size(); ++i) {
    in[i] = inside_unit_box(ps[i].position, c);
    far[i] = distance_to_unit_box(ps[i].position, c) > ps[i].radius;
  }
  int crossed = 0, too_near = 0;
  for (int s = 0; s < steps; ++s) {
    if (one_at_a_time) {
      for (auto& p : ps) step_particle(p, cs, kDt, opt);
    } else {
      step_particles(ps, cs, kDt, opt);
    }
    for (std::size_t i = 0; i < ps.size(); ++i) {
      if (inside_unit_box(ps[i].position, c) != bool(in[i])) ++crossed;
      if (far[i] && ps[i].radius > 0 && distance_to_unit_box(ps[i].position, c) < ps[i].radius * (1 - 1e-9)) ++too_near;
    }
  }
  EXPECT_EQ(crossed, 0) << what;
  EXPECT_EQ(too_near, 0) << what;
}

/// Steps once against the set as it is, so that most particles hold a ball (checked).
void compute_balls(std::vector<Particle<StaleS>>& ps, const ColliderSet<StaleS>& cs) {
  StepOptions<StaleS> opt;
  opt.threads = 1;
  step_particles(ps, cs, kDt, opt);
  int with_ball = 0;
  for (const auto& p : ps) with_ball += p.free_radius > 0.05 ? 1 : 0;
  ASSERT_GT(with_ball, int(ps.size()) / 2);
}

TEST(FreeBallStale, MeshPoseMovedAfterTheBallsWereFound) {
  for (const bool with_grid : {true, false})
    for (const bool one_at_a_time : {false, true}) {
      StaleScene sc(with_grid);
      std::vector<Particle<StaleS>> ps = stale_particles(kStaleParticles, 71);
      compute_balls(ps, sc.cs);
      // the box jumps by 1.5 along x: its surface now runs through many particles' balls
      const Vec3<StaleS> t(1.5, 0.25, 0);
      sc.cs.meshes[0].motion.pose.t = t;
      expect_sides_kept(ps, sc.cs, t, 5, one_at_a_time, with_grid ? "grid" : "tree");
    }
}

TEST(FreeBallStale, MeshVerticesEditedInPlaceAfterTheBallsWereFound) {
  // the same MeshBvh (same address, same triangle count) moved by set_vertices: only its
  // revision tells the step that the balls were found for other coordinates; the collider is
  // refreshed and, with a grid, the grid rebuilt into the same object, as their contracts ask
  for (const bool with_grid : {true, false})
    for (const bool one_at_a_time : {false, true}) {
      StaleScene sc(with_grid);
      std::vector<Particle<StaleS>> ps = stale_particles(kStaleParticles, 75);
      compute_balls(ps, sc.cs);
      const Vec3<StaleS> t(1.5, 0.25, 0);
      sc.bvh.set_vertices(sc.box.V.rowwise() + t.transpose());  // dyadic: the moved box is exact
      sc.cs.meshes[0].refresh();  // the collider's normals and scale (the step throws without it)
      if (with_grid) {
        DistanceGridConfig<StaleS> cfg;
        cfg.resolution = 8;
        sc.grid = DistanceGrid<StaleS>(sc.bvh, cfg);
      }
      expect_sides_kept(ps, sc.cs, t, 5, one_at_a_time, with_grid ? "grid" : "tree");
    }
}

TEST(FreeBallStale, ColliderAddedAfterTheBallsWereFound) {
  StaleScene sc(true);
  std::vector<Particle<StaleS>> ps = stale_particles(kStaleParticles, 72);
  compute_balls(ps, sc.cs);
  // a plane x = 2.5 facing -x: particles beyond it were outside the set's reach, now they are in
  // its solid side; those in front of it must stay in front
  PlaneCollider<StaleS> plane;
  plane.plane = Plane<StaleS>(Vec3<StaleS>(-1, 0, 0), -2.5);
  plane.material = Material<StaleS>::elastic();
  sc.cs.planes.push_back(plane);
  std::vector<char> front(ps.size());
  for (std::size_t i = 0; i < ps.size(); ++i) front[i] = ps[i].position.x() < 2.5;
  StepOptions<StaleS> opt;
  opt.threads = 1;
  int crossed = 0;
  for (int s = 0; s < 5; ++s) {
    step_particles(ps, sc.cs, kDt, opt);
    for (std::size_t i = 0; i < ps.size(); ++i) crossed += front[i] && !(ps[i].position.x() < 2.5) ? 1 : 0;
  }
  EXPECT_EQ(crossed, 0);
}

TEST(FreeBallStale, RadiusGrownAfterTheBallsWereFound) {
  StaleScene sc(true);
  std::vector<Particle<StaleS>> ps = stale_particles(kStaleParticles, 73);
  compute_balls(ps, sc.cs);
  for (auto& p : ps) p.radius = 0.3;  // balls were found for points
  expect_sides_kept(ps, sc.cs, Vec3<StaleS>::Zero(), 5, false, "radius");
}

TEST(FreeBallStale, LegsEndingOnTheBallsBoundary) {
  // legs from the ball's centre to its boundary, towards the box's nearest point (and a few ulps
  // beyond): inside or just outside the ball, never through the surface
  StaleScene sc(true);
  std::vector<Particle<StaleS>> ps = stale_particles(kStaleParticles, 74);
  compute_balls(ps, sc.cs);
  std::vector<Particle<StaleS>> legs;
  for (const auto& p : ps) {
    if (!(p.free_radius > 0)) continue;
    const Vec3<StaleS> c = p.free_center;
    const Vec3<StaleS> q = c.cwiseMax(-Vec3<StaleS>::Ones()).cwiseMin(Vec3<StaleS>::Ones());  // nearest box point from outside
    if (inside_unit_box(c, Vec3<StaleS>::Zero()) || (q - c).squaredNorm() == 0) continue;
    const Vec3<StaleS> u = (q - c).normalized();
    for (int k = 0; k < 3; ++k) {
      Particle<StaleS> l = p;
      l.position = c;
      l.velocity = u * (p.free_radius * (1 + k * 4 * std::numeric_limits<StaleS>::epsilon())) / kDt;
      legs.push_back(l);
    }
  }
  ASSERT_GT(legs.size(), ps.size() / 2);
  expect_sides_kept(legs, sc.cs, Vec3<StaleS>::Zero(), 1, false, "boundary");
  for (const auto& l : legs) EXPECT_GE(distance_to_unit_box(l.position, Vec3<StaleS>::Zero()), 0.0);
}

}  // namespace
}  // namespace impact
