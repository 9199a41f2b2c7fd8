// SPDX-License-Identifier: MIT
// Mesh against convex shape (convex/mesh_convex.hpp) checked against brute force over every
// triangle, two ways:
//  - an oracle independent of GJK, EPA, MPR and the closed forms: the certified distance bracket of
//    the ellipsoid method (tests/support/convex_oracle.hpp) of each triangle against the shape,
//    read through their support functions; triangles are visited in order of the gap between
//    their own box and the shape's box (computed here) and the loop stops when that gap exceeds
//    the best upper bound found, which is exact pruning;
//  - the pairwise convex queries (convex/query.hpp) on each TriangleShape, which answer spheres and
//    capsules by GJK on the core and the other shapes by libccd MPR: the tree must find the same
//    triangles (away from touching) and the closed forms must give the pairwise depths.
// Plus analytic cases (a sphere, a box and a capsule on a flat grid, a shape inside a closed mesh),
// near-touching, scaled and translated poses, float against double, work counters, and bad input.
#include "impact/convex/mesh_convex.hpp"
#include "impact/geometry/mesh_generators.hpp"
#include "support/convex_oracle.hpp"
#include "support/meshes.hpp"
#include "support/sanitizer.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <type_traits>
#include <vector>

namespace impact_mesh_convex_test {

using namespace impact;
using impact::test::zoo;
using Pose = RigidTransform<double>;
using V3 = Eigen::Vector3d;

/// The gap between two boxes (0 when they overlap), computed here (not the library's).
double mc_box_gap(const Aabb<double>& a, const Aabb<double>& b) {
  double s = 0;
  for (int i = 0; i < 3; ++i) {
    const double e = std::max({a.min[i] - b.max[i], b.min[i] - a.max[i], 0.0});
    s += e * e;
  }
  return std::sqrt(s);
}

struct McOracle {
  double lower = 0, upper = 0;          // bracket of the distance of the mesh's surface to the shape
  int closest = -1;                     // a triangle attaining `upper`
  std::vector<int> intersecting;        // triangles certified to overlap by more than the margin
  std::vector<int> near;                // triangles not certified apart by the margin
  std::vector<double> depth;            // per entry of `intersecting`: the least overlap found
};

/// The independent oracle over every triangle of m (world: mesh under pm), see the file comment.
/// `margin`: the distance below which a triangle counts as near touching.
template <class Shape>
McOracle mc_oracle(const TriangleMesh<double>& m, const Pose& pm, const Shape& s, const Pose& ps, double margin) {
  const Aabb<double> sb = bounding_box(s, ps);
  std::vector<std::pair<double, int>> order;
  for (int t = 0; t < m.F.rows(); ++t) {
    const Triangle<double> tri = m.triangle(t);
    const V3 a = pm.apply(tri.a), b = pm.apply(tri.b), c = pm.apply(tri.c);
    order.emplace_back(mc_box_gap(Aabb<double>(a.cwiseMin(b).cwiseMin(c), a.cwiseMax(b).cwiseMax(c)), sb), t);
  }
  std::sort(order.begin(), order.end());
  McOracle o;
  o.lower = o.upper = std::numeric_limits<double>::infinity();
  for (const auto& [gap, t] : order) {
    if (gap > o.upper + margin) break;
    const TriangleShape<double> tri(m.triangle(t));
    const auto br = test::distance_bracket(tri, pm, s, ps, IMPACT_TEST_SANITIZED ? 600 : 1000);
    if (br.upper < o.upper) {
      o.upper = br.upper;
      o.closest = t;
    }
    o.lower = std::min(o.lower, br.lower);
    // not apart (the bracket's upper bound is ~0): the direction search's least overlap, an upper
    // bound of the depth within its grid's accuracy, certifies an overlap beyond the margin
    if (br.upper < 1e-9 * shape_size(s)) {
      const double value = test::signed_distance_oracle(tri, pm, s, ps, IMPACT_TEST_SANITIZED ? 500 : 1500, 1).value;
      if (value < -margin) {
        o.intersecting.push_back(t);
        o.depth.push_back(-value);
      }
    }
    if (br.lower <= margin) o.near.push_back(t);
  }
  // past the loop every other triangle's box (hence the triangle) is farther than upper + margin:
  // the smallest lower bound of the visited triangles bounds the mesh's distance
  return o;
}

/// Random poses of a shape about a mesh: its centre near a random point of the mesh's surface
/// (a vertex pushed along a random direction by up to `reach`), random rotation.
std::vector<Pose> mc_poses_near(const TriangleMesh<double>& m, int n, double reach, std::uint64_t seed) {
  test::Rng rng(seed);
  std::vector<Pose> out;
  for (int i = 0; i < n; ++i) {
    const V3 v = m.V.row(static_cast<Eigen::Index>(rng.index(std::uint64_t(m.V.rows())))).transpose();
    out.push_back({rng.rotation(), v + rng.vec(-reach, reach)});
  }
  return out;
}

/// The exact penetration depth of a triangle and a box or hull (the least overlap over the
/// candidate axes of their Minkowski difference); -1 for curved shapes.
template <class Shape>
double mc_polytope_depth(const TriangleShape<double>& t, const Pose& pt, const Shape& s, const Pose& ps) {
  if constexpr (std::is_same_v<Shape, Box<double>> || std::is_same_v<Shape, ConvexHull<double>>) {
    std::vector<V3> normals, edges_t, edges_s;
    const Triangle<double>& tri = t.triangle;
    normals.push_back(pt.R * (tri.b - tri.a).cross(tri.c - tri.a));
    edges_t = {pt.R * (tri.b - tri.a), pt.R * (tri.c - tri.b), pt.R * (tri.a - tri.c)};
    test::polytope_features(s, ps, normals, edges_s);
    return test::polytope_depth(normals, edges_t, edges_s, [&](const V3& n) { return test::overlap_along(t, pt, s, ps, n); });
  } else {
    return -1;
  }
}

template <class BV, class Shape>
void mc_check_against_oracle(const char* name, const TriangleMesh<double>& m, const Shape& s, std::uint64_t seed, double reach = 1.2) {
  const MeshBvh<BV> tree(m);
  test::Rng rng(seed);
  const Pose pm{rng.rotation(), rng.vec(-2, 2)};
  const double size = shape_size(s);
  const double margin = 1e-6 * size;
  TriangleMesh<double> world = m;  // the mesh moved by pm, for the poses
  for (Eigen::Index i = 0; i < m.V.rows(); ++i) world.V.row(i) = pm.apply(m.V.row(i).transpose()).transpose();
  int separated = 0, hit = 0, contacts_checked = 0;
  for (const Pose& ps : mc_poses_near(world, IMPACT_TEST_SANITIZED ? 3 : 10, reach * size, seed + 1)) {
    const McOracle o = mc_oracle(m, pm, s, ps, margin);
    const bool ours = mesh_convex_collides(tree, pm, s, ps);
    const auto d = mesh_convex_distance(tree, pm, s, ps);
    const auto c = mesh_convex_contacts(tree, pm, s, ps);
    EXPECT_EQ(ours, c.colliding) << name;
    EXPECT_EQ(ours, d.intersecting) << name;
    if (o.lower > margin) {  // certified apart
      ++separated;
      EXPECT_FALSE(ours) << name << ": distance in [" << o.lower << ", " << o.upper << "]";
      EXPECT_GE(d.distance, o.lower - 1e-9 * size) << name;
      EXPECT_LE(d.distance, o.upper + 1e-9 * size) << name;
      // the witness points: on the reported triangle and on the shape, d apart
      EXPECT_NEAR((d.point_mesh - d.point_shape).norm(), d.distance, 1e-9 * size) << name;
      const Triangle<double> tri = m.triangle(d.triangle);
      const Triangle<double> wt(pm.apply(tri.a), pm.apply(tri.b), pm.apply(tri.c));
      EXPECT_LT(closest_point_on_triangle(d.point_mesh, wt).squared_distance, 1e-18 * size * size) << name;
    }
    if (!o.intersecting.empty()) {
      ++hit;
      EXPECT_TRUE(ours) << name;
      EXPECT_EQ(d.distance, 0.0) << name;
      // every certified triangle is reported, with a depth in the oracle's bracket
      std::set<int> reported;
      for (const auto& tc : c.contacts) reported.insert(tc.triangle);
      for (std::size_t k = 0; k < o.intersecting.size(); ++k) {
        const int t = o.intersecting[k];
        ASSERT_TRUE(reported.count(t)) << name << ": triangle " << t << " overlaps by " << o.depth[k];
        for (const auto& tc : c.contacts)
          if (tc.triangle == t) {
            ++contacts_checked;
            const TriangleShape<double> ts(m.triangle(t));
            // both are upper bounds of the depth: ours must not exceed the search's. The search
            // stalls on the ridges of a flat set's support (1e-4 to 1e-2 of the size above the
            // exact sphere depths here), so it does not bound ours from below; for a box or a
            // hull the least overlap over the candidate axes (the triangle's normal and edges,
            // the other's face normals and edges) is the exact depth, for spheres and capsules
            // the closed forms meet the pairwise GJK path (MatchesPairwiseQueries)
            EXPECT_LE(tc.contact.depth, o.depth[k] + 1e-7 * size) << name << " triangle " << t;
            const double exact = mc_polytope_depth(ts, pm, s, ps);
            if (exact >= 0) {
              EXPECT_NEAR(tc.contact.depth, exact, 1e-7 * size) << name << " triangle " << t;
            }
            EXPECT_NEAR(tc.contact.normal.norm(), 1.0, 1e-12) << name;
            // translating the shape by depth * normal leaves the triangle and the shape touching
            const V3 n = tc.contact.normal;
            const double overlap = test::overlap_along(ts, pm, s, ps, n);
            EXPECT_NEAR(overlap, tc.contact.depth, 1e-7 * size) << name;
          }
      }
    }
    // no triangle certified apart is reported
    const std::set<int> near(o.near.begin(), o.near.end());
    for (const auto& tc : c.contacts) EXPECT_TRUE(near.count(tc.triangle)) << name << ": triangle " << tc.triangle << " is apart";
  }
  // coverage of both cases (the few poses of a sanitizer build may miss one: memory is what that
  // run checks)
  if (!IMPACT_TEST_SANITIZED) {
    EXPECT_GT(separated, 0) << name;
    EXPECT_GT(hit, 0) << name;
    EXPECT_GT(contacts_checked, 0) << name;
  }
}

/// A closed mesh with uneven triangles: an icosphere of radius 1 with its vertices moved in and
/// out by up to 15 % (still closed, some long thin triangles), and a sheet of large triangles.
TriangleMesh<double> mc_bumpy_sphere() {
  TriangleMesh<double> m = make_icosphere(1.0, 2);
  test::Rng rng(4242);
  for (Eigen::Index i = 0; i < m.V.rows(); ++i) m.V.row(i) *= rng.uniform(0.85, 1.15);
  return m;
}

TEST(MeshConvex, MatchesIndependentOracle) {
  const auto& z = zoo();
  const TriangleMesh<double> m = mc_bumpy_sphere();
  const Sphere<double> offset_sphere{V3(0.1, -0.2, 0.15), 0.35};
  mc_check_against_oracle<Aabb<double>>("sphere", m, z.sphere, 1);
  mc_check_against_oracle<Obb<double>>("offset sphere", m, offset_sphere, 2);
  mc_check_against_oracle<Aabb<double>>("capsule", m, z.capsule, 3);
  mc_check_against_oracle<Sphere<double>>("cylinder", m, z.cylinder, 4);
  mc_check_against_oracle<Aabb<double>>("cone", m, z.cone, 5);
  mc_check_against_oracle<Obb<double>>("box", m, z.box, 6);
  mc_check_against_oracle<Aabb<double>>("hull", m, z.hull, 7);
}

TEST(MeshConvex, MatchesIndependentOracleOnSoups) {
  const auto& z = zoo();
  // triangles about the shapes' size and slivers (1e-6 wide needles, tiny and huge ones)
  const TriangleMesh<double> soup = test::random_soup<double>(IMPACT_TEST_SANITIZED ? 40 : 100, 91, 1.5, 0.5);
  const TriangleMesh<double> bad = test::degenerate_soup<double>(IMPACT_TEST_SANITIZED ? 40 : 60, 92);
  mc_check_against_oracle<Aabb<double>>("soup capsule", soup, z.capsule, 11, 3.0);
  mc_check_against_oracle<Obb<double>>("soup box", soup, z.box, 12, 3.0);
  mc_check_against_oracle<Aabb<double>>("slivers sphere", bad, z.sphere, 13);
  mc_check_against_oracle<Aabb<double>>("slivers capsule", bad, z.capsule, 14);
  mc_check_against_oracle<Obb<double>>("slivers cone", bad, z.cone, 15);
}

/// The pairwise queries (convex_intersect / convex_penetration on each TriangleShape): same set of
/// triangles away from touching, and for spheres and capsules (closed forms here, GJK there) the
/// same depths and normals.
template <class Shape>
void mc_check_against_pairwise(const char* name, const TriangleMesh<double>& m, const Shape& s, std::uint64_t seed) {
  const MeshBvh<Aabb<double>> tree(m);
  const double size = shape_size(s);
  const Pose pm = Pose::identity();
  int compared = 0;
  for (const Pose& ps : mc_poses_near(m, IMPACT_TEST_SANITIZED ? 5 : 20, size, seed)) {
    const auto c = mesh_convex_contacts(tree, pm, s, ps);
    std::set<int> reported;
    for (const auto& tc : c.contacts) reported.insert(tc.triangle);
    double best = std::numeric_limits<double>::infinity();
    for (int t = 0; t < m.F.rows(); ++t) {
      const TriangleShape<double> ts(m.triangle(t));
      const auto d = convex_distance(ts, pm, s, ps);
      best = std::min(best, d.distance);
      const auto p = convex_penetration(ts, pm, s, ps);
      if (d.distance > 1e-6 * size) {
        EXPECT_FALSE(reported.count(t)) << name;
        EXPECT_FALSE(convex_intersect(ts, pm, s, ps)) << name;
      } else if (p.intersecting && p.depth > 1e-6 * size) {
        ASSERT_TRUE(reported.count(t)) << name << ": triangle " << t << " depth " << p.depth;
        EXPECT_TRUE(convex_intersect(ts, pm, s, ps)) << name;
        for (const auto& tc : c.contacts)
          if (tc.triangle == t) {
            ++compared;
            EXPECT_NEAR(tc.contact.depth, p.depth, 1e-8 * size) << name << " triangle " << t;
            if (p.depth > 1e-3 * size) {
              // EPA's normal at a curved minimum (cylinders, cones) is only within about the square
              // root of its depth tolerance of the exact one (the deepest-point shortcut's)
              constexpr bool curved = std::is_same_v<Shape, Cylinder<double>> || std::is_same_v<Shape, Cone<double>>;
              EXPECT_LT((tc.contact.normal - p.normal).norm(), curved ? 1e-4 : 1e-6) << name << " triangle " << t;
            }
            if constexpr (std::is_same_v<Shape, Sphere<double>> || std::is_same_v<Shape, Capsule<double>>) {
              EXPECT_LT((tc.contact.point - p.point).norm(), 1e-6 * size) << name;
            } else {  // other points on the same supporting planes: point_a() on the triangle's
              const V3 n = tc.contact.normal;
              EXPECT_NEAR(n.dot(tc.contact.point_a()), n.dot(support(ts, pm, n)), 1e-9 * size) << name;
              EXPECT_NEAR(n.dot(tc.contact.point_b()), n.dot(support(s, ps, V3(-n))), 1e-9 * size) << name;
            }
          }
      }
    }
    const auto d = mesh_convex_distance(tree, pm, s, ps);
    EXPECT_NEAR(d.distance, best, 1e-9 * size) << name;
  }
  EXPECT_GT(compared, 0) << name;
}

TEST(MeshConvex, MatchesPairwiseQueries) {
  const auto& z = zoo();
  const TriangleMesh<double> m = mc_bumpy_sphere();
  mc_check_against_pairwise("sphere", m, z.sphere, 21);
  mc_check_against_pairwise("capsule", m, z.capsule, 22);
  mc_check_against_pairwise("box", m, z.box, 23);
  mc_check_against_pairwise("hull", m, z.hull, 24);
  mc_check_against_pairwise("cylinder", m, z.cylinder, 25);  // the deepest-point shortcut and EPA in the shape's frame
  mc_check_against_pairwise("cone", m, z.cone, 26);
}

// The deepest-point shortcut (convex/deepest_point.hpp): exact on triangles one vertex of which
// decides (through a cylinder's side and cap, a cone's base and side), declined where no single
// point decides, and wherever it answers its bracket [depth - depth_gap, depth] meets the pairwise
// EPA's and the depth is the overlap along its normal.
template <class Shape>
void mc_check_shortcut_against_epa(const Shape& s, std::uint64_t seed) {
  test::Rng rng(seed);
  const double size = shape_size(s);
  ConvexContact<double> c;
  int answered = 0;
  for (int i = 0; i < 400; ++i) {
    const V3 centre = rng.vec(-0.7, 0.7) * size;
    const TriangleShape<double> t(centre + 0.2 * size * rng.vec(-1, 1), centre + 0.2 * size * rng.vec(-1, 1), centre + 0.2 * size * rng.vec(-1, 1));
    const double tol = 1e-10 * std::max(size, shape_size(t));
    if (!detail::triangle_deepest_point_contact(t, s, tol, c)) continue;
    ++answered;
    const auto e = convex_penetration(t, Pose::identity(), s, Pose::identity());
    ASSERT_TRUE(e.intersecting) << i;
    EXPECT_LE(c.depth - c.depth_gap, e.depth + 1e-12 * size) << i;  // certified lower bound below EPA's upper bound
    EXPECT_GE(c.depth, e.depth - e.depth_gap - 1e-12 * size) << i;  // upper bound above EPA's certified lower bound
    EXPECT_LE(c.depth_gap, tol) << i;
    EXPECT_NEAR(c.depth, c.normal.dot(support(t, c.normal)) - c.normal.dot(support(s, V3(-c.normal))), 1e-14 * size) << i;  // f(normal)
    EXPECT_NEAR(c.normal.norm(), 1.0, 1e-15) << i;
  }
  EXPECT_GT(answered, 30);
}

TEST(MeshConvex, DeepestPointShortcut) {
  const Cylinder<double> cyl(1.0, 2.0);
  ConvexContact<double> c;
  // one vertex 0.1 inside the side, the others outside
  ASSERT_TRUE(detail::triangle_deepest_point_contact(TriangleShape<double>(V3(0.9, 0, 0), V3(1.5, 0.2, 0.1), V3(1.5, -0.2, -0.1)), cyl, 1e-10, c));
  EXPECT_NEAR(c.depth, 0.1, 1e-15);
  EXPECT_LE(c.depth_gap, 1e-15);
  EXPECT_NEAR(c.normal.x(), -1.0, 1e-15);
  EXPECT_NEAR(c.point_a().x(), 0.9, 1e-15);  // the deciding vertex
  EXPECT_NEAR(c.point_b().x(), 1.0, 1e-15);  // on the side
  // one vertex 0.05 below the top cap
  ASSERT_TRUE(detail::triangle_deepest_point_contact(TriangleShape<double>(V3(0, 0, 1.95), V3(0.2, 0, 2.5), V3(0, 0.2, 2.5)), cyl, 1e-10, c));
  EXPECT_NEAR(c.depth, 0.05, 1e-15);
  EXPECT_NEAR(c.normal.z(), -1.0, 1e-15);
  // a triangle across the whole cylinder: its face decides, no single point (the answer is EPA's)
  EXPECT_FALSE(detail::triangle_deepest_point_contact(TriangleShape<double>(V3(-3, -3, 0.5), V3(3, -3, 0.5), V3(0, 3, 0.5)), cyl, 1e-10, c));
  // a triangle outside: nothing to certify
  EXPECT_FALSE(detail::triangle_deepest_point_contact(TriangleShape<double>(V3(3, 0, 0), V3(4, 0, 0), V3(3, 1, 0)), cyl, 1e-10, c));
  // cone (base radius 1 at z = -1, apex (0, 0, 1)): one vertex 0.05 above the base
  const Cone<double> cone(1.0, 1.0);
  ASSERT_TRUE(detail::triangle_deepest_point_contact(TriangleShape<double>(V3(0, 0, -0.95), V3(0.2, 0, -1.5), V3(0, 0.2, -1.5)), cone, 1e-10, c));
  EXPECT_NEAR(c.depth, 0.05, 1e-14);
  EXPECT_NEAR(c.normal.z(), 1.0, 1e-15);
  // one vertex 0.1 inside the side at height 0 (the side's line is 2x + z = 1 in the (radius, z) plane)
  const double L = std::sqrt(5.0);
  const V3 u(2 / L, 0, 1 / L);  // the side's outward normal at azimuth x
  const V3 v = V3(0.5, 0, 0) - 0.1 * u;
  ASSERT_TRUE(detail::triangle_deepest_point_contact(TriangleShape<double>(v, v + V3(0.5, 0.3, 0.2), v + V3(0.5, -0.3, 0.2)), cone, 1e-10, c));
  EXPECT_NEAR(c.depth, 0.1, 1e-14);
  EXPECT_LT((c.normal + u).norm(), 1e-14);
  mc_check_shortcut_against_epa(cyl, 31);
  mc_check_shortcut_against_epa(cone, 32);
  mc_check_shortcut_against_epa(zoo().cylinder, 33);
  mc_check_shortcut_against_epa(zoo().cone, 34);
}

// fast_contacts (one MPR per triangle): the same triangles as the default contacts (EPA) away from
// touching, each depth an upper bound of EPA's that translating the shape by depth * normal closes
// exactly (the settled overlap along the normal), and the depth_gap the whole depth.
template <class Shape>
void mc_check_fast_contacts(const char* name, const TriangleMesh<double>& m, const Shape& s, std::uint64_t seed) {
  const MeshBvh<Aabb<double>> tree(m);
  const double size = shape_size(s);
  MeshConvexOptions<double> fast;
  fast.fast_contacts = true;
  int compared = 0;
  for (const Pose& ps : mc_poses_near(m, IMPACT_TEST_SANITIZED ? 4 : 12, size, seed)) {
    const auto c = mesh_convex_contacts(tree, Pose::identity(), s, ps);
    const auto f = mesh_convex_contacts(tree, Pose::identity(), s, ps, fast);
    for (const auto& tc : c.contacts) {
      const auto it = std::find_if(f.contacts.begin(), f.contacts.end(), [&](const auto& x) { return x.triangle == tc.triangle; });
      if (tc.contact.depth - tc.contact.depth_gap > 1e-6 * size) {
        ASSERT_TRUE(it != f.contacts.end()) << name << ": triangle " << tc.triangle;
      }
      if (it == f.contacts.end()) continue;
      ++compared;
      const ConvexContact<double>& q = it->contact;
      EXPECT_GE(q.depth, tc.contact.depth - tc.contact.depth_gap - 1e-9 * size) << name;
      EXPECT_EQ(q.depth_gap, q.depth) << name;
      const TriangleShape<double> ts(m.triangle(tc.triangle));
      EXPECT_NEAR(test::overlap_along(ts, Pose::identity(), s, ps, q.normal), q.depth, 1e-9 * size) << name;
    }
  }
  EXPECT_GT(compared, 0) << name;
}

TEST(MeshConvex, FastContactsAreSettledUpperBounds) {
  const auto& z = zoo();
  const TriangleMesh<double> m = mc_bumpy_sphere();
  mc_check_fast_contacts("cylinder", m, z.cylinder, 51);
  mc_check_fast_contacts("cone", m, z.cone, 52);
  mc_check_fast_contacts("hull", m, z.hull, 53);
}

// A flat grid in z = 0 (normals +z), shapes resting on it: depth and normal known exactly.
TEST(MeshConvex, AnalyticContactsOnAPlane) {
  const MeshBvh<Aabb<double>> grid(make_grid<double>(8, 8, 4.0));
  const Pose pm = Pose::identity();
  const Sphere<double> ball{V3::Zero(), 0.5};
  for (const double h : {0.3, -0.3, 0.5, 0.5 + 1e-9}) {  // above, below, touching, just apart
    const Pose ps{Eigen::Matrix3d::Identity(), V3(0.13, -0.41, h)};
    const auto c = mesh_convex_contacts(grid, pm, ball, ps);
    if (h > 0.5) {
      EXPECT_FALSE(c.colliding);
      EXPECT_FALSE(mesh_convex_collides(grid, pm, ball, ps));
      EXPECT_NEAR(mesh_convex_distance(grid, pm, ball, ps).distance, 1e-9, 1e-15);
      continue;
    }
    ASSERT_TRUE(c.colliding) << h;
    EXPECT_TRUE(mesh_convex_collides(grid, pm, ball, ps));
    const auto& deep = c.contacts[static_cast<std::size_t>(c.deepest())].contact;
    EXPECT_NEAR(deep.depth, 0.5 - std::abs(h), 1e-14) << h;
    EXPECT_NEAR(deep.normal.z(), h > 0 ? 1.0 : -1.0, 1e-14) << h;  // from the triangle towards the ball's centre side
    EXPECT_NEAR(deep.point_a().z(), 0.0, 1e-14);                    // the triangle's deepest point lies on it
  }
  // a box resting 0.1 deep, tilted by a small angle about x: depth along +z = the lowest corner's
  const Box<double> box(V3(0.3, 0.2, 0.1));
  const double angle = 0.05;
  const Eigen::Matrix3d R = Eigen::AngleAxisd(angle, V3::UnitX()).toRotationMatrix();
  const double reach = 0.2 * std::sin(angle) + 0.1 * std::cos(angle);  // half height of the box along z
  const Pose pb{R, V3(0.05, 0.07, reach - 0.1)};
  const auto cb = mesh_convex_contacts(grid, pm, box, pb);
  ASSERT_TRUE(cb.colliding);
  // (triangles partly under the box may be left sideways: their normals lie near the plane)
  for (const auto& tc : cb.contacts) EXPECT_LE(tc.contact.depth, 0.1 + 1e-9);
  EXPECT_NEAR(cb.contacts[static_cast<std::size_t>(cb.deepest())].contact.depth, 0.1, 1e-9);
  EXPECT_NEAR(cb.contacts[static_cast<std::size_t>(cb.deepest())].contact.normal.z(), 1.0, 1e-9);
  // a capsule lying on the grid 0.05 deep: depth 0.05 along +z on every triangle under its core
  const Capsule<double> cap(0.25, 0.6);
  const Pose pc{Eigen::AngleAxisd(M_PI / 2, V3::UnitY()).toRotationMatrix(), V3(0.1, 0.2, 0.2)};
  const auto cc = mesh_convex_contacts(grid, pm, cap, pc);
  ASSERT_TRUE(cc.colliding);
  EXPECT_NEAR(cc.contacts[static_cast<std::size_t>(cc.deepest())].contact.depth, 0.05, 1e-14);
  EXPECT_NEAR(cc.contacts[static_cast<std::size_t>(cc.deepest())].contact.normal.z(), 1.0, 1e-14);
  // the distance from the grid's corner region: a cylinder above a corner, exactly 0.25 up
  const Cylinder<double> cyl(0.2, 0.3);
  const auto dc = mesh_convex_distance(grid, pm, cyl, Pose{Eigen::Matrix3d::Identity(), V3(1.9, 1.9, 0.55)});
  EXPECT_NEAR(dc.distance, 0.25, 1e-9);
  EXPECT_NEAR(dc.point_mesh.z(), 0.0, 1e-9);
  EXPECT_NEAR(dc.point_shape.z(), 0.25, 1e-9);
}

// A surface mesh: a shape wholly inside a closed mesh does not collide (as FCL and the mesh–mesh
// queries); its distance is the gap to the surface.
TEST(MeshConvex, ShapeInsideAClosedMesh) {
  const MeshBvh<Obb<double>> ball(make_icosphere(2.0, 3));
  const Sphere<double> s{V3::Zero(), 0.5};
  const Pose pm = Pose::identity();
  const Pose ps{Eigen::Matrix3d::Identity(), V3(0.2, 0.1, -0.1)};
  EXPECT_FALSE(mesh_convex_collides(ball, pm, s, ps));
  EXPECT_TRUE(mesh_convex_contacts(ball, pm, s, ps).contacts.empty());
  const auto d = mesh_convex_distance(ball, pm, s, ps);
  // the icosphere's faces lie within [2 cos(max half angle), 2] of the centre
  const double c = ps.t.norm();
  EXPECT_LT(d.distance, 2.0 - c - 0.5);
  EXPECT_GT(d.distance, 2.0 * 0.99 - c - 0.5);
}

// Scaled (2^-20 .. 2^20) and translated copies of one configuration give the scaled answers.
TEST(MeshConvex, ScaleAndTranslationInvariant) {
  const auto& z = zoo();
  const TriangleMesh<double> m = mc_bumpy_sphere();
  const std::vector<Pose> poses = mc_poses_near(m, IMPACT_TEST_SANITIZED ? 4 : 12, 0.5, 31);
  for (const double k : {std::ldexp(1.0, -20), std::ldexp(1.0, 20)}) {
    TriangleMesh<double> mk = m;
    mk.V *= k;
    const MeshBvh<Aabb<double>> t1(m), tk(mk);
    const V3 shift = V3(3, -2, 5) * k;
    const Pose pm{Eigen::Matrix3d::Identity(), shift};
    const Box<double> box(z.box.half * k);
    const Capsule<double> cap(z.capsule.radius * k, z.capsule.half_length * k);
    for (const Pose& p : poses) {
      const Pose pk{p.R, p.t * k + shift};
      const auto d1 = mesh_convex_distance(t1, Pose::identity(), z.box, p);
      const auto dk = mesh_convex_distance(tk, pm, box, pk);
      EXPECT_NEAR(dk.distance / k, d1.distance, 1e-8) << k;
      if (d1.distance > 1e-6) {
        EXPECT_EQ(d1.triangle, dk.triangle);
      }
      const auto c1 = mesh_convex_contacts(t1, Pose::identity(), z.capsule, p);
      const auto ck = mesh_convex_contacts(tk, pm, cap, pk);
      if (c1.colliding && c1.contacts[static_cast<std::size_t>(c1.deepest())].contact.depth > 1e-6) {
        ASSERT_TRUE(ck.colliding);
        EXPECT_NEAR(ck.contacts[static_cast<std::size_t>(ck.deepest())].contact.depth / k,
                    c1.contacts[static_cast<std::size_t>(c1.deepest())].contact.depth, 1e-8);
      }
      EXPECT_EQ(mesh_convex_collides(tk, pm, cap, pk), ck.colliding);
    }
  }
}

// Near touching: a box face parallel to a grid triangle at gaps of 1e-3 .. 1e-12 of its size.
TEST(MeshConvex, NearTouching) {
  const MeshBvh<Aabb<double>> grid(make_grid<double>(4, 4, 4.0));
  const Box<double> box(V3(0.3, 0.3, 0.3));
  for (const double gap : {1e-3, 1e-6, 1e-8}) {
    const Pose pb{Eigen::AngleAxisd(0.3, V3::UnitZ()).toRotationMatrix(), V3(0.21, 0.33, 0.3 + gap)};
    EXPECT_FALSE(mesh_convex_collides(grid, Pose::identity(), box, pb)) << gap;
    EXPECT_NEAR(mesh_convex_distance(grid, Pose::identity(), box, pb).distance, gap, 1e-10) << gap;
    const Pose pin{pb.R, V3(0.21, 0.33, 0.3 - gap)};
    EXPECT_TRUE(mesh_convex_collides(grid, Pose::identity(), box, pin)) << gap;
    const auto c = mesh_convex_contacts(grid, Pose::identity(), box, pin);
    ASSERT_TRUE(c.colliding) << gap;
    // the 13 separating axes: exact to rounding
    EXPECT_NEAR(c.contacts[static_cast<std::size_t>(c.deepest())].contact.depth, gap, 1e-14) << gap;
    // a cone standing on its base (EPA): an upper bound of the depth within its tolerance (1e-8 of
    // the size), with a certified lower bound depth - depth_gap
    const Cone<double> cone(0.3, 0.4);
    const Pose pc{Eigen::AngleAxisd(0.7, V3::UnitZ()).toRotationMatrix(), V3(0.21, 0.33, 0.4 - gap)};
    EXPECT_FALSE(mesh_convex_collides(grid, Pose::identity(), cone, Pose{pc.R, V3(0.21, 0.33, 0.4 + gap)})) << gap;
    EXPECT_NEAR(mesh_convex_distance(grid, Pose::identity(), cone, Pose{pc.R, V3(0.21, 0.33, 0.4 + gap)}).distance, gap, 1e-10) << gap;
    const auto cc = mesh_convex_contacts(grid, Pose::identity(), cone, pc);
    ASSERT_TRUE(cc.colliding) << gap;
    const auto& deep = cc.contacts[static_cast<std::size_t>(cc.deepest())].contact;
    EXPECT_GE(deep.depth, gap - 1e-15) << gap;
    EXPECT_LE(deep.depth - deep.depth_gap, gap + 1e-15) << gap;
    EXPECT_LE(deep.depth - gap, 2e-8 * shape_size(cone)) << gap;
  }
  // exactly touching counts (closed forms): a sphere resting on the grid
  const Sphere<double> s{V3::Zero(), 0.5};
  EXPECT_TRUE(mesh_convex_collides(grid, Pose::identity(), s, Pose{Eigen::Matrix3d::Identity(), V3(0.1, 0.2, 0.5)}));
}

// float trees and shapes give the double answers to float's accuracy.
TEST(MeshConvex, FloatMatchesDouble) {
  const auto& z = zoo();
  const TriangleMesh<double> m = mc_bumpy_sphere();
  TriangleMesh<float> mf;
  mf.V = m.V.cast<float>();
  mf.F = m.F;
  const MeshBvh<Aabb<double>> td(m);
  const MeshBvh<Aabb<float>> tf(mf);
  const Cone<float> cone(float(z.cone.radius), float(z.cone.half_length));
  const Capsule<float> cap(float(z.capsule.radius), float(z.capsule.half_length));
  int compared = 0;
  for (const Pose& p : mc_poses_near(m, IMPACT_TEST_SANITIZED ? 6 : 20, 0.8, 41)) {
    const RigidTransform<float> pf{p.R.cast<float>(), p.t.cast<float>()};
    const auto dd = mesh_convex_distance(td, Pose::identity(), z.cone, p);
    const auto df = mesh_convex_distance(tf, RigidTransform<float>::identity(), cone, pf);
    EXPECT_NEAR(double(df.distance), dd.distance, 1e-4);
    const auto cd = mesh_convex_contacts(td, Pose::identity(), z.capsule, p);
    const auto cf = mesh_convex_contacts(tf, RigidTransform<float>::identity(), cap, pf);
    if (dd.distance > 1e-3) {
      EXPECT_FALSE(mesh_convex_collides(tf, RigidTransform<float>::identity(), cone, pf));
    }
    if (cd.colliding && cd.contacts[static_cast<std::size_t>(cd.deepest())].contact.depth > 1e-3) {
      ++compared;
      ASSERT_TRUE(cf.colliding);
      EXPECT_NEAR(double(cf.contacts[static_cast<std::size_t>(cf.deepest())].contact.depth),
                  cd.contacts[static_cast<std::size_t>(cd.deepest())].contact.depth, 1e-4);
    }
  }
  EXPECT_GT(compared, 0);
}

// Work counters on fixed inputs: a far shape costs one node test; a near one tests a few triangles
// of the 1280; the distance query never tests more triangles than the contacts' walk needs plus
// those within the best distance.
TEST(MeshConvex, WorkCounters) {
  const MeshBvh<Aabb<double>> ball(make_icosphere(1.0, 3));
  const Box<double> box(V3(0.1, 0.1, 0.1));
  QueryStats st;
  EXPECT_FALSE(mesh_convex_collides(ball, Pose::identity(), box, Pose{Eigen::Matrix3d::Identity(), V3(5, 0, 0)}, {}, &st));
  EXPECT_EQ(st.bv_tests, 1u);
  EXPECT_EQ(st.primitive_tests, 0u);
  const Pose near{Eigen::Matrix3d::Identity(), V3(1.05, 0.02, 0.01)};
  EXPECT_TRUE(mesh_convex_collides(ball, Pose::identity(), box, near, {}, &st));
  EXPECT_GE(st.primitive_tests, 1u);
  EXPECT_LT(st.primitive_tests, 40u);
  const auto d = mesh_convex_distance(ball, Pose::identity(), box, Pose{Eigen::Matrix3d::Identity(), V3(1.5, 0.02, 0.01)});
  EXPECT_GT(d.distance, 0.3);
  EXPECT_LT(d.stats.primitive_tests, 40u);
  EXPECT_LT(d.stats.bv_tests, 200u);
  // max_contacts stops the walk
  MeshConvexOptions<double> o;
  o.max_contacts = 1;
  const auto c = mesh_convex_contacts(ball, Pose::identity(), Box<double>(V3(0.3, 0.3, 0.3)), Pose{Eigen::Matrix3d::Identity(), V3(1, 0, 0)}, o);
  EXPECT_EQ(c.contacts.size(), 1u);
  EXPECT_TRUE(c.truncated);
}

TEST(MeshConvex, BadInputThrows) {
  const MeshBvh<Aabb<double>> ball(make_icosphere(1.0, 1));
  const Box<double> box(V3(0.1, 0.1, 0.1));
  const Pose ok = Pose::identity();
  Pose nan_pose = ok;
  nan_pose.t.x() = std::nan("");
  Pose scaled = ok;
  scaled.R *= 2;
  EXPECT_THROW(mesh_convex_collides(ball, nan_pose, box, ok), InvalidInput);
  EXPECT_THROW(mesh_convex_distance(ball, ok, box, nan_pose), InvalidInput);
  EXPECT_THROW(mesh_convex_contacts(ball, scaled, box, ok), InvalidInput);
  Capsule<double> cap(0.2, 0.3);
  cap.radius = std::nan("");
  EXPECT_THROW(mesh_convex_collides(ball, ok, cap, ok), InvalidInput);
  Sphere<double> s{V3::Zero(), -1.0};
  EXPECT_THROW(mesh_convex_distance(ball, ok, s, ok), InvalidInput);
  MeshConvexOptions<double> bad;
  bad.max_contacts = 0;
  EXPECT_THROW(mesh_convex_contacts(ball, ok, box, ok, bad), InvalidInput);
  MeshConvexOptions<double> bad_tol;
  bad_tol.convex.relative_tolerance = 0;
  EXPECT_THROW(mesh_convex_distance(ball, ok, box, ok, bad_tol), InvalidInput);
  bad_tol.convex.relative_tolerance = std::nan("");
  EXPECT_THROW(mesh_convex_collides(ball, ok, box, ok, bad_tol), InvalidInput);
  MeshConvexOptions<double> bad_it;
  bad_it.convex.max_iterations = 0;
  EXPECT_THROW(mesh_convex_contacts(ball, ok, box, ok, bad_it), InvalidInput);
  // an empty mesh cannot make a tree
  EXPECT_THROW(MeshBvh<Aabb<double>>(Vertices<double>(0, 3), Faces(0, 3)), InvalidInput);
  // a NaN triangle as a shape
  const TriangleShape<double> t(V3(0, 0, 0), V3(1, 0, 0), V3(0, std::nan(""), 0));
  EXPECT_THROW(mesh_convex_collides(ball, ok, t, ok), InvalidInput);
}

}  // namespace impact_mesh_convex_test
