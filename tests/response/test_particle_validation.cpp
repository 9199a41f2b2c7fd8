// SPDX-License-Identifier: MIT
// Argument checks of the particle step (issue 12, D11): NaN or infinite velocities and positions,
// negative radii, dt NaN, infinite or negative, NaN gravity, negative max_iterations, a NaN or
// non-rigid collider pose, bad materials and shapes each throw InvalidInput naming the argument,
// and nothing is modified when they do (the particles and the colliders compare bitwise equal to
// their state before the call). spatial_order rejects a NaN position (it was an undefined
// float-to-integer cast). Float and double.
#include "impact/geometry/mesh_generators.hpp"
#include "impact/response/particle_step.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <limits>
#include <string>

namespace impact {
namespace {

template <class F> void expect_invalid(F&& f, std::initializer_list<const char*> needles) {
  try {
    f();
    ADD_FAILURE() << "no exception; expected InvalidInput mentioning " << *needles.begin();
  } catch (const InvalidInput& e) {
    for (const char* n : needles) EXPECT_NE(std::string(e.what()).find(n), std::string::npos) << e.what() << " lacks " << n;
  } catch (const std::exception& e) {
    ADD_FAILURE() << "wrong exception type: " << e.what();
  }
}

template <class T> class ParticleValidation : public ::testing::Test {};
using Scalars = ::testing::Types<float, double>;
TYPED_TEST_SUITE(ParticleValidation, Scalars);

template <class S> std::vector<Particle<S>> falling_particles(std::size_t n) {
  std::vector<Particle<S>> ps(n);
  for (std::size_t i = 0; i < n; ++i) {
    ps[i].position = Vec3<S>(S(0.01) * S(i % 37), S(0.02) * S(i % 11), S(0.5) + S(0.001) * S(i));
    ps[i].velocity = Vec3<S>(S(0.1), S(-0.2), S(-3));
  }
  return ps;
}

template <class S> bool same_bits(const std::vector<Particle<S>>& a, const std::vector<Particle<S>>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const Particle<S>&p = a[i], &q = b[i];
    if (std::memcmp(p.position.data(), q.position.data(), sizeof(S) * 3) || std::memcmp(p.velocity.data(), q.velocity.data(), sizeof(S) * 3) ||
        std::memcmp(p.free_center.data(), q.free_center.data(), sizeof(S) * 3) || std::memcmp(&p.radius, &q.radius, sizeof(S)) ||
        std::memcmp(&p.free_radius, &q.free_radius, sizeof(S)))
      return false;
  }
  return true;
}

/// A floor plane, a sphere, a box and a mesh (a thin box) below the particles.
template <class S> struct Scene {
  MeshBvh<Aabb<S>> slab{make_box<S>(Vec3<S>(S(1), S(1), S(0.05)))};
  ColliderSet<S> colliders;
  Scene() {
    colliders.planes.push_back(PlaneCollider<S>(Plane<S>(Vec3<S>::UnitZ(), S(-1))));
    colliders.spheres.push_back(SphereCollider<S>(Sphere<S>(Vec3<S>(S(3), 0, 0), S(0.5))));
    colliders.boxes.push_back(BoxCollider<S>(Aabb<S>(Vec3<S>(S(-3), S(-1), S(-1)), Vec3<S>(S(-2), S(1), S(1)))));
    colliders.meshes.push_back(MeshCollider<Aabb<S>>(slab, ColliderSide::Outside));
  }
};

// Runs step_particles and step_particle on a copy of `ps` and expects both to throw with the
// needles, leaving the particles bitwise unchanged.
template <class S>
void expect_step_rejects(const std::vector<Particle<S>>& ps, const ColliderSet<S>& cs, S dt, const StepOptions<S>& opt,
                         std::initializer_list<const char*> needles) {
  std::vector<Particle<S>> work = ps;
  expect_invalid([&] { step_particles(work, cs, dt, opt); }, needles);
  EXPECT_TRUE(same_bits(work, ps)) << "step_particles modified the particles before throwing";
  // the single-particle step checks the same (its particle: the last, the bad one in these tests)
  Particle<S> one = ps.back();
  expect_invalid([&] { step_particle(one, cs, dt, opt); }, {"step_particle"});
  EXPECT_TRUE(same_bits(std::vector<Particle<S>>{one}, std::vector<Particle<S>>{ps.back()}));
}

TYPED_TEST(ParticleValidation, BadParticlesThrowBeforeAnyMoves) {
  using S = TypeParam;
  Scene<S> sc;
  const S nan = std::numeric_limits<S>::quiet_NaN(), inf = std::numeric_limits<S>::infinity();
  const StepOptions<S> opt;
  const S dt = S(0.01);
  {  // valid particles step, also with an infinite free radius (the step stores one when nothing is in reach)
    auto ps = falling_particles<S>(200);
    ps[3].free_radius = inf;
    EXPECT_NO_THROW(step_particles(ps, sc.colliders, dt, opt));
  }
  // the last particle is bad: the 199 before it must not have moved
  auto bad = [&](auto set) {
    auto ps = falling_particles<S>(200);
    set(ps.back());
    return ps;
  };
  expect_step_rejects(bad([&](Particle<S>& p) { p.velocity.y() = nan; }), sc.colliders, dt, opt, {"particle 199 velocity"});
  expect_step_rejects(bad([&](Particle<S>& p) { p.velocity.x() = inf; }), sc.colliders, dt, opt, {"particle 199 velocity"});
  expect_step_rejects(bad([&](Particle<S>& p) { p.position.z() = nan; }), sc.colliders, dt, opt, {"particle 199 position"});
  expect_step_rejects(bad([&](Particle<S>& p) { p.radius = S(-0.1); }), sc.colliders, dt, opt, {"particle 199 radius"});
  expect_step_rejects(bad([&](Particle<S>& p) { p.radius = nan; }), sc.colliders, dt, opt, {"particle 199 radius"});
  expect_step_rejects(bad([&](Particle<S>& p) { p.free_radius = nan; }), sc.colliders, dt, opt, {"particle 199 free_radius"});
  expect_step_rejects(bad([&](Particle<S>& p) { p.free_center.x() = nan; }), sc.colliders, dt, opt, {"particle 199 free_center"});
  // finite but beyond CoordinateRange, and infinite: the fast check and the named ones agree
  const S lim = CoordinateRange<S>::max;
  expect_step_rejects(bad([&](Particle<S>& p) { p.position.x() = S(2) * lim; }), sc.colliders, dt, opt, {"particle 199 position"});
  expect_step_rejects(bad([&](Particle<S>& p) { p.position.y() = -inf; }), sc.colliders, dt, opt, {"particle 199 position"});
  expect_step_rejects(bad([&](Particle<S>& p) { p.free_center.y() = S(-2) * lim; }), sc.colliders, dt, opt, {"particle 199 free_center"});
  expect_step_rejects(bad([&](Particle<S>& p) { p.free_center.z() = inf; }), sc.colliders, dt, opt, {"particle 199 free_center"});
  expect_step_rejects(bad([&](Particle<S>& p) { p.radius = S(2) * lim; }), sc.colliders, dt, opt, {"particle 199 radius"});
  expect_step_rejects(bad([&](Particle<S>& p) { p.radius = inf; }), sc.colliders, dt, opt, {"particle 199 radius"});
  expect_step_rejects(bad([&](Particle<S>& p) { p.velocity.z() = S(4) * (lim / dt); }), sc.colliders, dt, opt, {"particle 199 velocity"});
  {  // with dt = 0 an infinite velocity is still rejected (inf * 0 is NaN), a finite one of any size is not
    expect_step_rejects(bad([&](Particle<S>& p) { p.velocity.x() = -inf; }), sc.colliders, S(0), opt, {"particle 199 velocity"});
    auto ps = bad([&](Particle<S>& p) { p.velocity.z() = S(4) * (lim / dt); });
    EXPECT_NO_THROW(step_particles(ps, sc.colliders, S(0), opt));
  }
}

TYPED_TEST(ParticleValidation, BadStepArgumentsThrow) {
  using S = TypeParam;
  Scene<S> sc;
  const S nan = std::numeric_limits<S>::quiet_NaN(), inf = std::numeric_limits<S>::infinity();
  const auto ps = falling_particles<S>(50);
  const StepOptions<S> good;
  expect_step_rejects(ps, sc.colliders, nan, good, {"dt"});
  expect_step_rejects(ps, sc.colliders, S(-0.01), good, {"dt"});
  expect_step_rejects(ps, sc.colliders, inf, good, {"dt"});
  auto with = [&](auto set) {
    StepOptions<S> o;
    set(o);
    return o;
  };
  const S dt = S(0.01);
  expect_step_rejects(ps, sc.colliders, dt, with([&](auto& o) { o.gravity = Vec3<S>(0, 0, nan); }), {"options.gravity"});
  expect_step_rejects(ps, sc.colliders, dt, with([&](auto& o) { o.gravity = Vec3<S>(0, 0, -inf); }), {"options.gravity"});
  expect_step_rejects(ps, sc.colliders, dt, with([&](auto& o) { o.max_iterations = -1; }), {"options.max_iterations"});
  expect_step_rejects(ps, sc.colliders, dt, with([&](auto& o) { o.rest_speed = nan; }), {"options.rest_speed"});
  expect_step_rejects(ps, sc.colliders, dt, with([&](auto& o) { o.surface_offset = S(-1); }), {"options.surface_offset"});
  expect_step_rejects(ps, sc.colliders, dt, with([&](auto& o) { o.offset_ulps = nan; }), {"options.offset_ulps"});
  expect_step_rejects(ps, sc.colliders, dt, with([&](auto& o) { o.free_ball_factor = inf; }), {"options.free_ball_factor"});
  expect_step_rejects(ps, sc.colliders, dt, with([&](auto& o) { o.strategy = Strategy::Inherit; }), {"options.strategy"});
  // dt = 0 and max_iterations = 0 are valid
  auto copy = ps;
  EXPECT_NO_THROW(step_particles(copy, sc.colliders, S(0), good));
  EXPECT_NO_THROW(step_particles(copy, sc.colliders, dt, with([&](auto& o) { o.max_iterations = 0; })));
}

TYPED_TEST(ParticleValidation, BadCollidersThrow) {
  using S = TypeParam;
  const S nan = std::numeric_limits<S>::quiet_NaN();
  const auto ps = falling_particles<S>(50);
  const StepOptions<S> opt;
  const S dt = S(0.01);
  {
    Scene<S> sc;
    sc.colliders.meshes[0].motion.pose.t.z() = nan;
    expect_step_rejects(ps, sc.colliders, dt, opt, {"mesh collider 3 motion.pose"});
  }
  {
    Scene<S> sc;
    sc.colliders.meshes[0].motion.pose.R *= S(3);
    expect_step_rejects(ps, sc.colliders, dt, opt, {"mesh collider 3 motion.pose.R", "rotation"});
  }
  {
    Scene<S> sc;
    sc.colliders.planes[0].motion.pose.R(0, 0) = nan;
    expect_step_rejects(ps, sc.colliders, dt, opt, {"plane collider 0 motion.pose"});
  }
  {
    Scene<S> sc;
    sc.colliders.spheres[0].motion.linear_velocity.x() = nan;
    expect_step_rejects(ps, sc.colliders, dt, opt, {"sphere collider 1 motion.linear_velocity"});
  }
  {
    Scene<S> sc;
    sc.colliders.boxes[0].motion.angular_velocity.y() = std::numeric_limits<S>::infinity();
    expect_step_rejects(ps, sc.colliders, dt, opt, {"box collider 2 motion.angular_velocity"});
  }
  {
    Scene<S> sc;
    sc.colliders.planes[0].plane.normal = Vec3<S>(0, 0, 2);
    expect_step_rejects(ps, sc.colliders, dt, opt, {"plane collider 0 plane.normal"});
  }
  {
    Scene<S> sc;
    sc.colliders.spheres[0].sphere.radius = S(-1);
    expect_step_rejects(ps, sc.colliders, dt, opt, {"sphere collider 1 sphere.radius"});
  }
  {
    Scene<S> sc;
    sc.colliders.boxes[0].box.axes *= S(2);
    expect_step_rejects(ps, sc.colliders, dt, opt, {"box collider 2 box"});
  }
  {
    Scene<S> sc;
    sc.colliders.meshes[0].material.restitution = S(1.5);
    expect_step_rejects(ps, sc.colliders, dt, opt, {"mesh collider 3 material.restitution"});
  }
  {
    Scene<S> sc;
    sc.colliders.planes[0].material.friction = nan;
    expect_step_rejects(ps, sc.colliders, dt, opt, {"plane collider 0 material.friction"});
  }
  {
    Scene<S> sc;
    sc.colliders.meshes[0].mesh = nullptr;
    expect_step_rejects(ps, sc.colliders, dt, opt, {"mesh collider 3 mesh"});
  }
  {
    Scene<S> sc;
    const MeshBvh<Aabb<S>> other(make_icosphere<S>(S(1), 1));
    const CompactBvh wrong(other.tree());
    sc.colliders.meshes[0].compact_tree = &wrong;
    expect_step_rejects(ps, sc.colliders, dt, opt, {"mesh collider 3 compact_tree"});
  }
  {
    Scene<S> sc;
    const WideBvh<S> wrong(make_icosphere<S>(S(1), 1));
    sc.colliders.meshes[0].wide_tree = &wrong;
    expect_step_rejects(ps, sc.colliders, dt, opt, {"mesh collider 3 wide_tree"});
  }
  {  // the mesh edited after the collider was made (its pseudo-normals and scale describe the old
     // surface): rejected until refresh(), which recomputes them
    Scene<S> sc;
    sc.slab.set_vertices(sc.slab.mesh().V * S(2));
    expect_step_rejects(ps, sc.colliders, dt, opt, {"mesh collider 3 mesh", "set_vertices", "refresh()"});
    sc.colliders.meshes[0].refresh();
    EXPECT_EQ(sc.colliders.meshes[0].mesh_revision(), sc.slab.revision());
    EXPECT_EQ(sc.colliders.meshes[0].scale(), S(2) * MeshCollider<Aabb<S>>(Scene<S>().slab).scale());
    EXPECT_NO_THROW(sc.colliders.validate("refreshed"));
  }
  {  // advance() with a NaN dt moves nothing
    Scene<S> sc;
    sc.colliders.spheres[0].motion.linear_velocity = Vec3<S>(1, 0, 0);
    const Vec3<S> before = sc.colliders.spheres[0].motion.pose.t;
    expect_invalid([&] { sc.colliders.advance(nan); }, {"ColliderSet::advance", "dt"});
    EXPECT_EQ(sc.colliders.spheres[0].motion.pose.t, before);
  }
}

TYPED_TEST(ParticleValidation, SpatialOrderRejectsNonFinitePositions) {
  using S = TypeParam;
  auto ps = falling_particles<S>(100);
  EXPECT_EQ(spatial_order(ps).size(), ps.size());
  ps[57].position.y() = std::numeric_limits<S>::quiet_NaN();
  expect_invalid([&] { spatial_order(ps); }, {"spatial_order", "particle 57 position"});
  ps[57].position.y() = -std::numeric_limits<S>::infinity();
  expect_invalid([&] { spatial_order(ps); }, {"spatial_order", "particle 57 position"});
  // finite positions spanning more than the largest double still give a permutation
  ps[57].position.y() = std::numeric_limits<S>::max();
  ps[58].position.y() = -std::numeric_limits<S>::max();
  std::vector<std::uint32_t> order = spatial_order(ps);
  std::sort(order.begin(), order.end());
  for (std::size_t i = 0; i < order.size(); ++i) EXPECT_EQ(order[i], i);
}

}  // namespace
}  // namespace impact
