// SPDX-License-Identifier: MIT
// The separating-axis test of a triangle against a convex hull (convex/triangle_hull_sat.hpp)
// against the brute-force least overlap over every candidate axis of the pair (tests/support:
// the face normals of both and the cross products of every pair of edges, each both ways, the
// overlap from the support functions), which prunes nothing by the Gauss map: its sign decides
// the boolean and its value is the exact depth. Hulls: the zoo's 40-point ellipsoid, a cube (merged
// square faces: parallel edges), 12 random points; triangles from a tenth to three times the
// hull's size, and degenerate ones (a segment, three collinear points, a point).
#include "impact/convex/triangle_hull_sat.hpp"
#include "impact/convex/triangle_shape.hpp"
#include "support/convex_oracle.hpp"
#include "support/random.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

namespace impact_triangle_hull_sat_test {

using namespace impact;
using V3 = Eigen::Vector3d;
using Pose = RigidTransform<double>;

double exact_depth(const Triangle<double>& tri, const ConvexHull<double>& h) {
  const Pose id;
  const TriangleShape<double> t(tri);
  std::vector<V3> normals{(tri.b - tri.a).cross(tri.c - tri.a)}, edges_h;
  const std::vector<V3> edges_t{tri.b - tri.a, tri.c - tri.b, tri.a - tri.c};
  test::polytope_features(h, id, normals, edges_h);
  return test::polytope_depth(normals, edges_t, edges_h, [&](const V3& n) { return test::overlap_along(t, id, h, id, n); });
}

struct SatCounts {
  int contacts = 0, apart = 0;
};

void check_hull(const std::string& name, const ConvexHull<double>& h, std::uint64_t seed, SatCounts& counts) {
  ASSERT_TRUE(detail::use_triangle_hull_sat(h)) << name;
  test::Rng rng(seed);
  const double size = h.size;
  const Pose id;
  for (int i = 0; i < 200; ++i) {
    const double scale = size * (i % 3 == 0 ? 0.1 : (i % 3 == 1 ? 1.0 : 3.0));
    const V3 centre = h.centroid + rng.vec(-1.2, 1.2) * size;
    Triangle<double> tri(centre + rng.vec(-1, 1) * scale, centre + rng.vec(-1, 1) * scale, centre + rng.vec(-1, 1) * scale);
    if (i % 10 == 7) tri.c = tri.a;                                 // a segment
    if (i % 10 == 8) tri.c = tri.a + 0.375 * (tri.b - tri.a);       // collinear
    if (i % 20 == 9) tri.b = tri.c = tri.a;                         // a point
    const double exact = exact_depth(tri, h);
    const ConvexContact<double> c = detail::triangle_hull_sat(tri, h);
    if (std::abs(exact) > 1e-9 * size) {
      EXPECT_EQ(c.intersecting, exact > 0) << name << " pose " << i << " exact " << exact;
    }
    if (exact < 0) ++counts.apart;
    if (!c.intersecting) continue;
    ++counts.contacts;
    const TriangleShape<double> t(tri);
    EXPECT_NEAR(c.depth, std::max(exact, 0.0), 1e-9 * size) << name << " pose " << i;
    EXPECT_NEAR(c.normal.norm(), 1.0, 1e-12) << name;
    // translating the hull by depth * normal leaves the two touching
    EXPECT_NEAR(test::overlap_along(t, id, h, id, c.normal), c.depth, 1e-9 * size) << name << " pose " << i;
    // the point's two ends lie on the supporting planes of the triangle and the hull
    const V3 n = c.normal;
    EXPECT_NEAR(n.dot(c.point_a()), n.dot(support(t, id, n)), 1e-9 * size) << name << " pose " << i;
    EXPECT_NEAR(n.dot(c.point_b()), n.dot(support(h, id, V3(-n))), 1e-9 * size) << name << " pose " << i;
  }
}

TEST(TriangleHullSat, MatchesBruteForceLeastOverlap) {
  SatCounts counts;
  check_hull("ellipsoid", test::zoo().hull, 1, counts);
  Vertices<double> cube(8, 3);
  for (int k = 0; k < 8; ++k) cube.row(k) = V3(k & 1 ? 0.5 : -0.5, k & 2 ? 0.3 : -0.3, k & 4 ? 0.4 : -0.4).transpose();
  check_hull("cube", convex_hull(cube), 2, counts);
  test::Rng rng(3);
  Vertices<double> points(12, 3);
  for (int k = 0; k < 12; ++k) points.row(k) = rng.vec(-0.5, 0.5).transpose();
  check_hull("random", convex_hull(points), 4, counts);
  EXPECT_GE(counts.contacts, 80);  // both kinds occur
  EXPECT_GE(counts.apart, 80);
}

}  // namespace impact_triangle_hull_sat_test
