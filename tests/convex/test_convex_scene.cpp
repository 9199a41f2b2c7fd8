// SPDX-License-Identifier: MIT
// Convex shapes as scene objects (convex/scene_shapes.hpp, ConvexScene) checked against an oracle
// independent of GJK, EPA, MPR and the closed forms: per pair of objects, the certified distance
// bracket of the ellipsoid method and the direction search's least overlap (tests/support/
// convex_oracle.hpp, which read the shapes through their support functions only), over every
// triangle for a mesh. Every broad phase, after adds and after moves; contacts (translating b by
// depth along the normal separates the pair, and the depth is at least the oracle's); filters,
// sleeping, static pairs and the ignore list; float against double; bad input.
// Convex shapes as particle colliders (convex/convex_collider.hpp): the closed-form point queries
// against the direction search; analytic bounces and resting contact; no particle ever inside a
// collider (backtracking and projection, point and ball particles, moving colliders, float and
// double) with the independent oracle on the final positions; bad input.
#include "impact/convex/convex_collider.hpp"
#include "impact/convex/scene_shapes.hpp"
#include "impact/response/particle_step.hpp"
#include "impact/geometry/mesh_generators.hpp"
#include "support/convex_oracle.hpp"
#include "support/sanitizer.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <string>
#include <vector>

namespace impact_convex_scene_test {

using namespace impact;
using impact::test::zoo;
using Pose = RigidTransform<double>;
using V3 = Eigen::Vector3d;

/// A pair of objects: apart or touching beyond the margin, or too near touching to tell.
enum class CsTruth { Apart, Touching, Unsure };

constexpr double kCsMargin = 1e-6;

/// The oracle's verdict on two convex sets (support functions only).
template <class A, class B>
CsTruth cs_truth_convex(const A& a, const Pose& pa, const B& b, const Pose& pb) {
  const auto br = test::distance_bracket(a, pa, b, pb, IMPACT_TEST_SANITIZED ? 600 : 1200);
  if (br.lower > kCsMargin) return CsTruth::Apart;
  if (br.upper > kCsMargin) return CsTruth::Unsure;
  const double value = test::signed_distance_oracle(a, pa, b, pb, IMPACT_TEST_SANITIZED ? 400 : 1500, 1).value;
  return value < -kCsMargin ? CsTruth::Touching : CsTruth::Unsure;
}

/// The least overlap the direction search finds (an approximation of the penetration depth).
template <class A, class B>
double cs_oracle_depth(const A& a, const Pose& pa, const B& b, const Pose& pb) {
  return -test::signed_distance_oracle(a, pa, b, pb, IMPACT_TEST_SANITIZED ? 400 : 1500, 1).value;
}

/// Calls f with the convex-layer shape of a non-mesh scene shape (a particle or sphere is a ball,
/// of radius 0 for a point particle; a core box the convex layer's box).
template <class F>
auto cs_visit(const ConvexSceneShape<double>& s, F&& f) {
  if (s.is_convex()) return detail::with_convex_shape(s, f);
  if (s.core.kind == ShapeKind::Box) {
    Box<double> b(V3::Ones());
    b.half = s.core.half;
    return f(b);
  }
  return f(Sphere<double>(V3::Zero(), s.core.radius));
}

/// The oracle's verdict on two scene objects; a mesh (a surface) touches a shape when one of its
/// triangles does.
CsTruth cs_truth(const ConvexSceneShape<double>& a, const Pose& pa, const ConvexSceneShape<double>& b, const Pose& pb) {
  const bool mesh_a = !a.is_convex() && a.core.kind == ShapeKind::Mesh;
  const bool mesh_b = !b.is_convex() && b.core.kind == ShapeKind::Mesh;
  if (mesh_a && mesh_b) return CsTruth::Unsure;  // core pairs are the core's tests'
  if (mesh_a || mesh_b) {
    const ConvexSceneShape<double>& m = mesh_a ? a : b;
    const Pose& pm = mesh_a ? pa : pb;
    return cs_visit(mesh_a ? b : a, [&](const auto& x) {
      const Pose& px = mesh_a ? pb : pa;
      const TriangleMesh<double>& tm = m.core.mesh->mesh();
      CsTruth out = CsTruth::Apart;
      for (int t = 0; t < tm.F.rows(); ++t) {
        const CsTruth v = cs_truth_convex(TriangleShape<double>(tm.triangle(t)), pm, x, px);
        if (v == CsTruth::Touching) return CsTruth::Touching;
        if (v == CsTruth::Unsure) out = CsTruth::Unsure;
      }
      return out;
    });
  }
  return cs_visit(a, [&](const auto& x) { return cs_visit(b, [&](const auto& y) { return cs_truth_convex(x, pa, y, pb); }); });
}

/// The objects of the test scenes: one of every kind, two of some, about 1 across.
struct CsObjects {
  TriangleMesh<double> ball_mesh = make_icosphere<double>(0.6, 1);
  MeshBvh<Sphere<double>> ball_tree{ball_mesh};
  std::vector<ConvexSceneShape<double>> shapes;
  CsObjects() {
    const auto& z = zoo();
    shapes = {z.capsule,
              z.cylinder,
              z.cone,
              ConvexSceneShape<double>::hull_of(z.hull),
              Capsule<double>(0.2, 0.0),  // a capsule of half length 0: a ball
              Shape<double>::sphere(0.4),
              Shape<double>::particle(0.0),
              Shape<double>::particle(0.15),
              z.box,
              Shape<double>::box(V3(0.5, 0.0, 0.3)),  // flat
              Shape<double>::mesh_of(ball_tree),
              Cone<double>(0.2, 0.4),
              ConvexSceneShape<double>::hull_of(z.hull)};
  }
};

std::vector<Pose> cs_poses(std::size_t n, double reach, std::uint64_t seed) {
  test::Rng rng(seed);
  std::vector<Pose> out;
  for (std::size_t i = 0; i < n; ++i) out.push_back(test::random_pose(rng, V3::Constant(-reach), V3::Constant(reach)));
  return out;
}

/// Checks the scene's pairs (and contacts) against the oracle; returns how many pairs it decided.
int cs_check_scene(const ConvexScene<double>& scene, const CsObjects& objs, const std::vector<Pose>& poses, const char* what) {
  const auto plain = scene.collide();
  SceneCollideOptions with_contacts;
  with_contacts.contacts = true;
  const auto full = scene.collide(with_contacts);
  const std::set<ObjectPair> got(plain.pairs.begin(), plain.pairs.end());
  const std::set<ObjectPair> got_c(full.pairs.begin(), full.pairs.end());
  EXPECT_EQ(plain.pairs.size(), got.size()) << what << ": a pair reported twice";
  EXPECT_EQ(full.contacts.size(), full.pairs.size()) << what;
  int decided = 0;
  for (std::size_t i = 0; i < objs.shapes.size(); ++i)
    for (std::size_t j = i + 1; j < objs.shapes.size(); ++j) {
      const CsTruth t = cs_truth(objs.shapes[i], poses[i], objs.shapes[j], poses[j]);
      if (t == CsTruth::Unsure) continue;
      ++decided;
      const ObjectPair p{ObjectId(i), ObjectId(j)};
      const bool want = t == CsTruth::Touching;
      EXPECT_EQ(got.count(p) == 1, want) << what << ": objects " << i << " and " << j;
      EXPECT_EQ(got_c.count(p) == 1, want) << what << " (contacts): objects " << i << " and " << j;
    }
  // contacts of convex pairs: the pair's own query (convex/query.hpp) with the normal from a towards
  // b whatever the order of the kinds (the dispatch); b moved by depth + 1e-5 along the normal is
  // apart by the oracle (the normal's direction, the depth an upper bound); and the depth is near
  // the oracle's least overlap (loosely: libccd's EPA, which answers sphere-cylinder and the
  // general pairs, is off by up to 7e-2 of the size on a few poses, docs/convex-notes.md)
  for (const auto& c : full.contacts) {
    const auto& sa = objs.shapes[c.a];
    const auto& sb = objs.shapes[c.b];
    EXPECT_NEAR(c.contact.normal.norm(), 1.0, 1e-12);
    EXPECT_GE(c.contact.depth, 0.0);
    const bool mesh = (!sa.is_convex() && sa.core.kind == ShapeKind::Mesh) || (!sb.is_convex() && sb.core.kind == ShapeKind::Mesh);
    if (mesh || (!sa.is_convex() && !sb.is_convex())) continue;
    cs_visit(sa, [&](const auto& x) {
      cs_visit(sb, [&](const auto& y) {
        // the scene runs a pair with the core shape, else the lower variant index, first
        ConvexContact<double> own;
        if (sa.convex.index() > sb.convex.index()) {
          own = detail::penetration_unchecked(y, poses[c.b], x, poses[c.a], ConvexQueryOptions<double>{});
          own.normal = -own.normal;
        } else {
          own = detail::penetration_unchecked(x, poses[c.a], y, poses[c.b], ConvexQueryOptions<double>{});
        }
        EXPECT_EQ(own.depth, c.contact.depth) << what << ": contact " << c.a << "-" << c.b;
        EXPECT_EQ(own.normal, c.contact.normal) << what << ": contact " << c.a << "-" << c.b;
        Pose moved = poses[c.b];
        moved.t += (c.contact.depth + 1e-5) * c.contact.normal;
        EXPECT_GT(test::distance_bracket(x, poses[c.a], y, moved).lower, 0.0) << what << ": contact " << c.a << "-" << c.b;
        const double od = cs_oracle_depth(x, poses[c.a], y, poses[c.b]);
        EXPECT_NEAR(c.contact.depth, od, 0.1) << what << ": contact " << c.a << "-" << c.b;
      });
    });
  }
  return decided;
}

TEST(ConvexScene, PairsAndContactsMatchAnIndependentOracleInEveryBroadPhase) {
  const CsObjects objs;
  const std::size_t n = objs.shapes.size();
  for (const BroadPhaseKind kind : {BroadPhaseKind::AllPairs, BroadPhaseKind::StaticDynamic, BroadPhaseKind::Hierarchical}) {
    SceneOptions o;
    o.broad_phase = kind;
    ConvexScene<double> scene(o);
    std::vector<Pose> poses = cs_poses(n, 0.9, 11);
    for (std::size_t i = 0; i < n; ++i) {
      ObjectOptions oo;
      oo.body = i == 10 ? BodyType::Static : BodyType::Dynamic;  // the mesh
      scene.add(ObjectId(i), objs.shapes[i], poses[i], oo);
    }
    const int decided = cs_check_scene(scene, objs, poses, "added");
    EXPECT_GE(decided, int(n * (n - 1) / 2) - 8);
    if (IMPACT_TEST_SANITIZED && kind != BroadPhaseKind::Hierarchical) continue;
    // every object moves (the static mesh too): the incremental trees are updated
    poses = cs_poses(n, 0.9, 12);
    for (std::size_t i = 0; i < n; ++i) scene.set_pose(ObjectId(i), poses[i]);
    cs_check_scene(scene, objs, poses, "moved");
  }
}

TEST(ConvexScene, StaticSleepingFilteredAndIgnoredPairsAreSkipped) {
  const auto& z = zoo();
  ConvexScene<double> scene;
  const Pose at(Eigen::Matrix3d::Identity(), V3::Zero());
  const Pose near(Eigen::Matrix3d::Identity(), V3(0.3, 0, 0));
  ObjectOptions fixed;
  fixed.body = BodyType::Static;
  scene.add(1, z.cylinder, at, fixed);
  scene.add(2, z.cone, near, fixed);  // static-static: never a pair
  EXPECT_FALSE(scene.any_collision());
  ObjectOptions asleep;
  asleep.sleeping = true;
  scene.add(3, z.capsule, near, asleep);  // sleeping against static: skipped
  EXPECT_FALSE(scene.any_collision());
  scene.set_sleeping(3, false);
  auto r = scene.collide();
  EXPECT_EQ(std::set<ObjectPair>(r.pairs.begin(), r.pairs.end()), (std::set<ObjectPair>{{1, 3}, {2, 3}}));
  scene.ignore_pair(1, 3);
  CollisionFilter f;
  f.group = 2;
  f.mask = 0xffffffffu & ~1u;  // not group 1: the cone and cylinder
  scene.set_filter(3, f);
  EXPECT_FALSE(scene.any_collision());
  scene.unignore_pair(1, 3);
  scene.set_filter(3, CollisionFilter{});
  r = scene.collide();
  EXPECT_EQ(r.pairs.size(), 2u);
  EXPECT_EQ(r.stats.narrow_tests, 2u);
  EXPECT_EQ(r.stats.solver_limits, 0u);
  // apart by 0.01 along x: the boxes' pads do not make a pair of it
  scene.remove(2);
  scene.set_pose(3, Pose(Eigen::Matrix3d::Identity(), V3(z.cylinder.radius + z.capsule.radius + 0.01, 0, 0)));
  EXPECT_FALSE(scene.any_collision());
  scene.set_pose(3, Pose(Eigen::Matrix3d::Identity(), V3(z.cylinder.radius + z.capsule.radius - 0.01, 0, 0)));
  SceneCollideOptions co;
  co.contacts = true;
  r = scene.collide(co);
  ASSERT_EQ(r.contacts.size(), 1u);  // closed form: capsule side against cylinder side, 0.01 deep along x
  EXPECT_NEAR(r.contacts[0].contact.depth, 0.01, 1e-9);
  EXPECT_NEAR(r.contacts[0].contact.normal.x(), 1.0, 1e-9);
}

TEST(ConvexScene, FloatAgreesWithDouble) {
  const CsObjects objs;
  ConvexScene<double> sd;
  ConvexScene<float> sf;
  const std::vector<Pose> poses = cs_poses(objs.shapes.size(), 0.9, 21);
  const auto& z = zoo();
  const ConvexHull<float> hull_f = convex_hull<float>(z.hull.vertices.cast<float>());
  for (std::size_t i = 0; i < objs.shapes.size(); ++i) {
    if (!objs.shapes[i].is_convex() && objs.shapes[i].core.kind == ShapeKind::Mesh) continue;
    sd.add(ObjectId(i), objs.shapes[i], poses[i]);
    const ConvexSceneShape<double>& s = objs.shapes[i];
    ConvexSceneShape<float> f;
    switch (s.convex.index()) {
      case 0:
        f.core.kind = s.core.kind;
        f.core.radius = float(s.core.radius);
        f.core.half = s.core.half.cast<float>();
        break;
      case 1:
        f = Capsule<float>(float(std::get<1>(s.convex).radius), float(std::get<1>(s.convex).half_length));
        break;
      case 2:
        f = Cylinder<float>(float(std::get<2>(s.convex).radius), float(std::get<2>(s.convex).half_length));
        break;
      case 3:
        f = Cone<float>(float(std::get<3>(s.convex).radius), float(std::get<3>(s.convex).half_length));
        break;
      default:
        f = ConvexSceneShape<float>::hull_of(hull_f);
        break;
    }
    sf.add(ObjectId(i), f, RigidTransform<float>(poses[i].R.cast<float>(), poses[i].t.cast<float>()));
  }
  SceneCollideOptions co;
  co.contacts = true;
  const auto rd = sd.collide(co);
  const auto rf = sf.collide(co);
  int compared = 0;
  for (std::size_t i = 0; i < objs.shapes.size(); ++i)
    for (std::size_t j = i + 1; j < objs.shapes.size(); ++j) {
      if (!sd.contains(i) || !sd.contains(j)) continue;
      const CsTruth t = cs_truth(objs.shapes[i], poses[i], objs.shapes[j], poses[j]);
      if (t == CsTruth::Unsure) continue;
      const ObjectPair p{ObjectId(i), ObjectId(j)};
      const bool in_d = std::count(rd.pairs.begin(), rd.pairs.end(), p) == 1;
      const bool in_f = std::count(rf.pairs.begin(), rf.pairs.end(), p) == 1;
      // float: pairs within its tolerance (1e-5 of the sizes) of touching may go either way
      if (std::abs(cs_visit(objs.shapes[i], [&](const auto& x) {
            return cs_visit(objs.shapes[j], [&](const auto& y) { return cs_oracle_depth(x, poses[i], y, poses[j]); });
          })) < 1e-3)
        continue;
      EXPECT_EQ(in_d, in_f) << i << "-" << j;
      ++compared;
    }
  EXPECT_GE(compared, 20);
  for (const auto& cd : rd.contacts)
    for (const auto& cf : rf.contacts)
      if (cd.a == cf.a && cd.b == cf.b && cd.contact.depth > 1e-2) {
        EXPECT_NEAR(double(cf.contact.depth), cd.contact.depth, 2e-3);
      }
}

TEST(ConvexScene, BadInputThrowsAndLeavesTheSceneUnchanged) {
  const auto& z = zoo();
  ConvexScene<double> scene;
  const Pose at(Eigen::Matrix3d::Identity(), V3::Zero());
  scene.add(1, z.capsule, at);
  Capsule<double> bad = z.capsule;
  bad.radius = std::nan("");
  EXPECT_THROW(scene.add(2, bad, at), InvalidInput);
  Cylinder<double> flat = z.cylinder;
  flat.half_length = 0;
  EXPECT_THROW(scene.add(2, flat, at), InvalidInput);
  Cone<double> negative = z.cone;
  negative.radius = -1;
  EXPECT_THROW(scene.add(2, negative, at), InvalidInput);
  const ConvexHull<double> empty;
  EXPECT_THROW(scene.add(2, ConvexSceneShape<double>::hull_of(empty), at), InvalidInput);
  ConvexSceneShape<double> null_hull = ConvexSceneShape<double>::hull_of(z.hull);
  null_hull.convex = static_cast<const ConvexHull<double>*>(nullptr);
  EXPECT_THROW(scene.add(2, null_hull, at), InvalidInput);
  EXPECT_THROW(scene.add(1, z.cone, at), InvalidInput);  // duplicate id
  Pose nan_pose = at;
  nan_pose.t.x() = std::nan("");
  EXPECT_THROW(scene.add(2, z.cone, nan_pose), InvalidInput);
  EXPECT_THROW(scene.set_pose(1, nan_pose), InvalidInput);
  EXPECT_EQ(scene.size(), 1u);
  EXPECT_FALSE(scene.contains(2));
  EXPECT_EQ(scene.pose(1).t, V3::Zero());
  EXPECT_EQ(scene.bounds(1).max.z(), scene.bounds(1).max.z());
  EXPECT_GT(scene.bounds(1).max.z(), z.capsule.radius + z.capsule.half_length - 1e-9);
  EXPECT_LT(scene.bounds(1).max.z(), z.capsule.radius + z.capsule.half_length + 1e-6);
  ConvexQueryOptions<double> o;
  o.relative_tolerance = 0;
  EXPECT_THROW(ConvexSceneShapes<double>{o}, InvalidInput);
  o = {};
  o.max_iterations = 0;
  EXPECT_THROW(ConvexSceneShapes<double>{o}, InvalidInput);
}


// ---------------------------------------------------------------------------------------------
// Particle colliders

/// Calls f with each collider shape of the zoo (capsule, cylinder, cone, hull).
template <class F>
void cs_for_each_collider_shape(F&& f) {
  const auto& z = zoo();
  f(z.capsule);
  f(z.cylinder);
  f(z.cone);
  f(z.hull);
}

TEST(ConvexCollider, PointQueriesMatchTheDirectionSearch) {
  cs_for_each_collider_shape([](const auto& shape) {
    test::Rng rng(5);
    const Pose id;
    for (int i = 0; i < (IMPACT_TEST_SANITIZED ? 10 : 40); ++i) {
      const V3 q = rng.vec(-0.9, 0.9);
      const ShapePointQuery<double> pq = point_query(shape, q);
      // the signed distance of the point (a ball of radius 0) and the shape by the oracles: outside,
      // the ellipsoid method's certified bracket; inside, the direction search's least overlap
      const Sphere<double> point(q, 0.0);
      const auto br = test::distance_bracket(point, id, shape, id);
      if (br.lower > 1e-6) {
        EXPECT_GE(pq.distance, br.lower - 1e-12) << "point " << q.transpose();
        EXPECT_LE(pq.distance, br.upper + 1e-12) << "point " << q.transpose();
      } else {
        EXPECT_NEAR(pq.distance, test::signed_distance_oracle(point, id, shape, id).value, 1e-6) << "point " << q.transpose();
      }
      EXPECT_NEAR(pq.normal.norm(), 1.0, 1e-12);
      EXPECT_LT((q - pq.distance * pq.normal - pq.point).norm(), 1e-12);  // q = point + distance normal
      // the point is on the boundary, and the normal is the outward one there (the support
      // function in that direction reaches the point's plane)
      EXPECT_NEAR(point_query(shape, pq.point).distance, 0.0, 1e-9);
      EXPECT_NEAR(pq.normal.dot(support(shape, pq.normal)), pq.normal.dot(pq.point), 1e-9);
    }
  });
}

template <class S>
using CsColliders = ColliderSet<S, Aabb<S>, ConvexCollider<S, Capsule<S>>, ConvexCollider<S, Cylinder<S>>, ConvexCollider<S, Cone<S>>,
                                ConvexCollider<S, ConvexHull<S>>>;

template <class S>
CsColliders<S> cs_colliders(const ConvexHull<S>& hull, Strategy strategy, S restitution, S friction) {
  const auto& z = zoo();
  CsColliders<S> set;
  const Material<S> m{restitution, friction};
  auto place = [&](auto& c, double x, double y, std::uint64_t seed) {
    test::Rng rng(seed);
    c.motion.pose = RigidTransform<S>(rng.rotation().cast<S>(), Vec3<S>(S(x), S(y), S(0)));
    c.strategy = strategy;
    return c;
  };
  ConvexCollider<S, Capsule<S>> cap(Capsule<S>(S(z.capsule.radius), S(z.capsule.half_length)), m);
  ConvexCollider<S, Cylinder<S>> cyl(Cylinder<S>(S(z.cylinder.radius), S(z.cylinder.half_length)), m);
  ConvexCollider<S, Cone<S>> cone(Cone<S>(S(z.cone.radius), S(z.cone.half_length)), m);
  ConvexCollider<S, ConvexHull<S>> h(hull, m);
  set.template extra_of<ConvexCollider<S, Capsule<S>>>().push_back(place(cap, -1.0, -1.0, 1));
  set.template extra_of<ConvexCollider<S, Cylinder<S>>>().push_back(place(cyl, 1.0, -1.0, 2));
  set.template extra_of<ConvexCollider<S, Cone<S>>>().push_back(place(cone, -1.0, 1.0, 3));
  set.template extra_of<ConvexCollider<S, ConvexHull<S>>>().push_back(place(h, 1.0, 1.0, 4));
  return set;
}

/// The oracle's signed distance of a particle's centre to a collider (world), as a double.
template <class S, class C>
double cs_particle_distance(const C& c, const Vec3<S>& x) {
  const RigidTransform<double> pose(c.motion.pose.R.template cast<double>(), c.motion.pose.t.template cast<double>());
  const Sphere<double> point(x.template cast<double>(), 0.0);
  if constexpr (std::is_same_v<S, double>) {
    return test::signed_distance_oracle(point, Pose(), c.shape, pose, IMPACT_TEST_SANITIZED ? 200 : 600, 1).value;
  } else {
    return double(point_query(c.shape, Vec3<S>(c.motion.pose.R.transpose() * (x - c.motion.pose.t))).distance);
  }
}

/// A rain of particles on the four colliders (gravity, random velocities, radius 0 and 0.05):
/// after every step no particle is inside a collider (by the point query; at the end by the
/// oracle in double), the step hit something, and kinetic energy never grows with restitution <= 1.
template <class S>
void cs_rain(Strategy strategy, S restitution, S friction, bool moving) {
  const ConvexHull<S> hull = convex_hull<S>(zoo().hull.vertices.template cast<S>());
  CsColliders<S> set = cs_colliders<S>(hull, strategy, restitution, friction);
  if (moving)
    set.for_each_extra([](const auto& c) {
      auto& m = const_cast<ColliderMotion<S>&>(c.motion);
      m.linear_velocity = Vec3<S>(S(0), S(0), S(0.5));
      m.angular_velocity = Vec3<S>(S(0.3), S(-0.2), S(1.0));
    });
  test::Rng rng(99);
  std::vector<Particle<S>> ps(IMPACT_TEST_SANITIZED ? 60 : 300);
  for (std::size_t i = 0; i < ps.size(); ++i) {  // each above one of the colliders at (+-1, +-1, 0)
    const double cx = i % 4 < 2 ? -1.0 : 1.0, cy = i % 2 ? 1.0 : -1.0;
    ps[i].position = Vec3<S>(S(cx + rng.uniform(-0.5, 0.5)), S(cy + rng.uniform(-0.5, 0.5)), S(rng.uniform(0.8, 2.0)));
    ps[i].velocity = Vec3<S>(S(rng.uniform(-0.3, 0.3)), S(rng.uniform(-0.3, 0.3)), S(rng.uniform(-3, 0)));
    ps[i].radius = i % 2 ? S(0.05) : S(0);
  }
  StepOptions<S> opt;
  opt.strategy = strategy;
  opt.gravity = Vec3<S>(S(0), S(0), S(-9.81));
  const S dt = S(0.01);
  const S slack = std::is_same_v<S, float> ? S(2e-4) : S(1e-9);
  StepStats total;
  for (int step = 0; step < 100; ++step) {  // 1 s: every particle reaches the colliders' height
    total += step_particles(ps, set, dt, opt);
    set.advance(dt);
    int inside = 0;
    for (const auto& p : ps)
      set.for_each_extra([&](const auto& c) {
        const Vec3<S> q = c.motion.pose.R.transpose() * (p.position - c.motion.pose.t);
        if (point_query(c.shape, q).distance < p.radius - slack) ++inside;
      });
    ASSERT_EQ(inside, 0) << "step " << step;
  }
  // the rain reaches the colliders (more than a fifth of the particles hit one)
  EXPECT_GT(total.impacts + total.projections, ps.size() / 5);
  // the final positions by the independent oracle (double; float: the closed form)
  int inside = 0;
  for (std::size_t i = 0; i < ps.size(); i += (IMPACT_TEST_SANITIZED ? 3 : 1))
    set.for_each_extra([&](const auto& c) {
      if (cs_particle_distance<S>(c, ps[i].position) < double(ps[i].radius) - double(slack) - 1e-7) ++inside;
    });
  EXPECT_EQ(inside, 0);
}

TEST(ConvexCollider, NoParticleEndsInsideBacktracking) { cs_rain<double>(Strategy::Backtrack, 0.5, 0.2, false); }
TEST(ConvexCollider, NoParticleEndsInsideProjection) { cs_rain<double>(Strategy::Project, 0.5, 0.2, false); }
TEST(ConvexCollider, NoParticleEndsInsideMovingColliders) { cs_rain<double>(Strategy::Backtrack, 1.0, 0.0, true); }
TEST(ConvexCollider, NoParticleEndsInsideFloat) { cs_rain<float>(Strategy::Backtrack, 0.5, 0.2, false); }

TEST(ConvexCollider, ValidateNamesTheColliderOnlyOnFailure) {
  ConvexCollider<double, Cylinder<double>> c(Cylinder<double>(0.4, 0.5), Material<double>{0.5, 0.0});
  EXPECT_NO_THROW(c.validate("step", "collider 7"));
  c.shape.radius = std::nan("");  // changed after construction: only validate catches it
  try {
    c.validate("step", "collider 7");
    ADD_FAILURE() << "a NaN radius passed validate";
  } catch (const InvalidInput& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("step: collider 7"), std::string::npos) << what;
    EXPECT_NE(what.find("cylinder.radius"), std::string::npos) << what;
  }
}

TEST(ConvexCollider, AnalyticBounceAndRest) {
  // a point dropped on the flat top of an upright cylinder (cap at z = 0.5) from z = 1.5 at rest:
  // it arrives with speed sqrt(2 g 1.0) and leaves with e times it, from the cap
  const Cylinder<double> cyl(0.4, 0.5);
  ColliderSet<double, Aabb<double>, ConvexCollider<double, Cylinder<double>>> set;
  set.extra_of<ConvexCollider<double, Cylinder<double>>>().emplace_back(cyl, Material<double>{0.5, 0.0});
  StepOptions<double> opt;
  opt.gravity = V3(0, 0, -9.81);
  const double g = 9.81, v_in = std::sqrt(2 * g * 1.0);
  Particle<double> p;
  p.position = V3(0.1, -0.2, 1.5);
  // step exactly to the impact time and a little past it
  const double t_hit = v_in / g;
  StepOptions<double> bounce = opt;
  bounce.rest_speed_factor = 0;  // (the default rest speed, 2 g dt, would call this impact a rest)
  StepStats st = step_particle(p, set, t_hit + 0.01, bounce);
  EXPECT_EQ(st.impacts, 1u);
  EXPECT_NEAR(p.velocity.z(), 0.5 * v_in - g * 0.01, 1e-9);
  EXPECT_NEAR(p.position.z(), 0.5 + 0.5 * v_in * 0.01 - g * 0.01 * 0.01 / 2, 1e-9);
  EXPECT_NEAR(p.position.x(), 0.1, 1e-12);
  // a ball of radius 0.1 on the hemispherical top of an upright capsule, off its axis by 0.05:
  // it hits the sphere of radius 0.4 about (0, 0, 0.6) where the centre is 0.4 from it
  const Capsule<double> cap(0.3, 0.6);
  ColliderSet<double, Aabb<double>, ConvexCollider<double, Capsule<double>>> cs;
  cs.extra_of<ConvexCollider<double, Capsule<double>>>().emplace_back(cap, Material<double>{1.0, 0.0});
  Particle<double> b;
  b.radius = 0.1;
  b.position = V3(0.05, 0, 2.0);
  b.velocity = V3(0, 0, -4);
  StepOptions<double> o2;
  step_particle(b, cs, 1.0, o2);
  const double zc = 0.6 + std::sqrt(0.4 * 0.4 - 0.05 * 0.05);  // centre at the impact
  const V3 n = (V3(0.05, 0, zc) - V3(0, 0, 0.6)).normalized();
  const V3 v_out = V3(0, 0, -4) - 2 * V3(0, 0, -4).dot(n) * n;  // elastic reflection
  EXPECT_LT((b.velocity - v_out).norm(), 1e-9);
  const double t_impact = (2.0 - zc) / 4.0;
  EXPECT_LT((b.position - (V3(0.05, 0, zc) + v_out * (1.0 - t_impact))).norm(), 1e-9);
  // resting: a ball left on the cylinder's cap under gravity with friction comes to rest on it
  ColliderSet<double, Aabb<double>, ConvexCollider<double, Cylinder<double>>> rs;
  rs.extra_of<ConvexCollider<double, Cylinder<double>>>().emplace_back(cyl, Material<double>{0.0, 0.5});
  Particle<double> r;
  r.radius = 0.05;
  r.position = V3(0, 0, 0.6);
  r.velocity = V3(0.05, 0, 0);
  for (int i = 0; i < 50; ++i) step_particle(r, rs, 0.01, opt);
  EXPECT_EQ(r.velocity, V3::Zero());
  EXPECT_NEAR(r.position.z(), 0.55, 1e-9);
}

TEST(ConvexCollider, BadInputThrowsAndNothingMoves) {
  const auto& z = zoo();
  ColliderSet<double, Aabb<double>, ConvexCollider<double, Capsule<double>>, ConvexCollider<double, ConvexHull<double>>> set;
  set.extra_of<ConvexCollider<double, Capsule<double>>>().emplace_back(z.capsule);
  std::vector<Particle<double>> ps(3);
  for (std::size_t i = 0; i < ps.size(); ++i) {
    ps[i].position = V3(0, 0, 2.0 + double(i));
    ps[i].velocity = V3(0, 0, -1);
  }
  const auto before = ps;
  StepOptions<double> opt;
  auto same = [&] {
    for (std::size_t i = 0; i < ps.size(); ++i)
      if (ps[i].position != before[i].position || ps[i].velocity != before[i].velocity) return false;
    return true;
  };
  set.extra_of<ConvexCollider<double, Capsule<double>>>()[0].shape.radius = std::nan("");
  EXPECT_THROW(step_particles(ps, set, 0.1, opt), InvalidInput);
  EXPECT_TRUE(same());
  set.extra_of<ConvexCollider<double, Capsule<double>>>()[0].shape.radius = 0.3;
  set.extra_of<ConvexCollider<double, Capsule<double>>>()[0].material.restitution = 2;
  EXPECT_THROW(step_particles(ps, set, 0.1, opt), InvalidInput);
  set.extra_of<ConvexCollider<double, Capsule<double>>>()[0].material.restitution = 0.5;
  set.extra_of<ConvexCollider<double, Capsule<double>>>()[0].motion.pose.t.x() = std::nan("");
  EXPECT_THROW(step_particles(ps, set, 0.1, opt), InvalidInput);
  set.extra_of<ConvexCollider<double, Capsule<double>>>()[0].motion.pose.t.x() = 0;
  set.extra_of<ConvexCollider<double, ConvexHull<double>>>().emplace_back(ConvexHull<double>{});  // not built
  EXPECT_THROW(step_particles(ps, set, 0.1, opt), InvalidInput);
  EXPECT_TRUE(same());
  set.extra_of<ConvexCollider<double, ConvexHull<double>>>().clear();
  EXPECT_EQ(set.size(), 1u);
  EXPECT_EQ(step_particles(ps, set, 0.1, opt).impacts, 0u);  // valid again: it steps
  EXPECT_FALSE(same());
}

}  // namespace impact_convex_scene_test
