// SPDX-License-Identifier: MIT
// verify_cloth_state: exact intersections (crossing, touching, adjacent triangles that share only
// what they should, folds over a shared edge, an edge poking through past a shared vertex) and
// the minimum distance of non-adjacent primitives against hand-computed values.
#include "impact/cloth/verify_state.hpp"
#include "impact/geometry/mesh_generators.hpp"

#include <gtest/gtest.h>

namespace {

using namespace impact;

template <class S>
class Verify : public ::testing::Test {};
using Scalars = ::testing::Types<float, double>;
TYPED_TEST_SUITE(Verify, Scalars);

TYPED_TEST(Verify, FlatGridIsCleanAndTwoSheetsReportTheirGap) {
  using S = TypeParam;
  auto g = make_grid<S>(6, 6, S(1));
  const auto rep = verify_cloth_state(g.F, g.V, ClothObstacles<S>{}, ObstacleTime::End, ClothVerifyOptions{0.5, 16});
  EXPECT_EQ(rep.intersections, 0u);
  // Non-adjacent primitives of a flat 6x6 grid over side 1: vertex to a non-incident face, at
  // least one cell's short distance... the closest are a vertex and the far edge of the next cell.
  EXPECT_GT(rep.min_distance, 0.1);
  // Two sheets 0.01 apart.
  const auto n = g.V.rows();
  Vertices<S> V(2 * n, 3);
  V.topRows(n) = g.V;
  V.bottomRows(n) = g.V;
  V.bottomRows(n).col(2).array() += S(0.01);
  Faces F(2 * g.F.rows(), 3);
  F.topRows(g.F.rows()) = g.F;
  F.bottomRows(g.F.rows()) = g.F.array() + int(n);
  const auto rep2 = verify_cloth_state(F, V, ClothObstacles<S>{}, ObstacleTime::End, ClothVerifyOptions{0.5, 16});
  EXPECT_EQ(rep2.intersections, 0u);
  EXPECT_NEAR(rep2.min_distance, 0.01, 1e-6);
  // Push one vertex of the top sheet through the bottom one.
  V(n + 8, 2) = S(-0.01);
  const auto rep3 = verify_cloth_state(F, V, ClothObstacles<S>{});
  EXPECT_GT(rep3.intersections, 0u);
}

TYPED_TEST(Verify, AdjacentTrianglesCountOnlyWhenTheyShareMore) {
  using S = TypeParam;
  Vertices<S> V(5, 3);
  // Shared edge (0, 1); vertex 2 on one side, vertex 3 above (a proper dihedral).
  V << 0, 0, 0, 1, 0, 0, 0.5, 1, 0, 0.5, -1, 0, 0.5, 0.5, 0;
  Faces F(2, 3);
  F << 0, 1, 2, 1, 0, 3;
  EXPECT_EQ(verify_cloth_state(F, V, ClothObstacles<S>{}).intersections, 0u);
  // Fold: 3 coplanar and on the same side as 2.
  V.row(3) << S(0.5), S(0.3), S(0);
  EXPECT_EQ(verify_cloth_state(F, V, ClothObstacles<S>{}).intersections, 1u);
  // Same side but lifted out of the plane: no longer intersecting.
  V(3, 2) = S(0.01);
  EXPECT_EQ(verify_cloth_state(F, V, ClothObstacles<S>{}).intersections, 0u);
  // Shared vertex 0: triangles (0,1,2) and (0,3,4).
  F << 0, 1, 2, 0, 3, 4;
  V << 0, 0, 0, 1, 0, 0, 0, 1, 0, -1, 0, 0.5, 0, -1, 0.5;  // apart
  EXPECT_EQ(verify_cloth_state(F, V, ClothObstacles<S>{}).intersections, 0u);
  V.row(3) << S(0.5), S(0.5), S(0.5);  // (0,3,4)'s far edge pierces (0,1,2)
  V.row(4) << S(0.5), S(0.5), S(-0.5);
  EXPECT_EQ(verify_cloth_state(F, V, ClothObstacles<S>{}).intersections, 1u);
  // Edge (0, 3) lies in the plane of (0,1,2) inside its corner, 4 above: they share a segment.
  V.row(3) << S(0.3), S(0.3), S(0);
  V.row(4) << S(0), S(-1), S(1);
  EXPECT_EQ(verify_cloth_state(F, V, ClothObstacles<S>{}).intersections, 1u);
  // The same edge in the plane but pointing away from the corner: only the vertex is shared.
  V.row(3) << S(-0.3), S(-0.3), S(0);
  EXPECT_EQ(verify_cloth_state(F, V, ClothObstacles<S>{}).intersections, 0u);
}

TYPED_TEST(Verify, ObstaclesAreCheckedAgainstTheClothNotEachOther) {
  using S = TypeParam;
  auto g = make_grid<S>(2, 2, S(1));
  Vertices<S> ob(3, 3), ob2(3, 3);
  ob << -1, -1, -0.001, 1, -1, -0.001, 0, 1, -0.001;
  ob2 = ob;  // a second obstacle on top of the first: ignored
  Faces of(1, 3);
  of << 0, 1, 2;
  ClothObstacles<S> obs;
  obs.kinematic.push_back({&ob, &ob, &of});
  obs.kinematic.push_back({&ob2, &ob2, &of});
  auto rep = verify_cloth_state(g.F, g.V, obs, ObstacleTime::End, ClothVerifyOptions{0.1, 16});
  EXPECT_EQ(rep.intersections, 0u);
  EXPECT_NEAR(rep.min_distance, 0.001, 1e-6);
  Vertices<S> ob1 = ob;
  ob1(2, 2) = S(0.5), ob1(0, 2) = ob1(1, 2) = S(-0.5);  // at the end it is tilted through the cloth
  obs.kinematic[0].x1 = &ob1;
  EXPECT_GT(verify_cloth_state(g.F, g.V, obs, ObstacleTime::End).intersections, 0u);
  EXPECT_EQ(verify_cloth_state(g.F, g.V, obs, ObstacleTime::Start).intersections, 0u);
}

}  // namespace
