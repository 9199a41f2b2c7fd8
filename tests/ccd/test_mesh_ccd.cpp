// SPDX-License-Identifier: MIT
// Mesh-level CCD against a brute-force loop over all primitive pairs (the same primitive tests,
// so the sets of colliding pairs must be equal): two meshes, self CCD skipping adjacent
// primitives, refit between steps, minimum separation. Float and double.
#include "impact/ccd/mesh_ccd.hpp"
#include "sheets.hpp"
#include "support/mesh_ccd_pairs.hpp"

#include <gtest/gtest.h>

#include <map>
#include <random>
#include <set>

namespace {

using impact::test::jitter;
using impact::test::Sheet;
using impact::test::sheet;

using Key = impact::test::MeshCcdKey;

template <class S> std::set<Key> keys(const impact::MeshCcdResult<S>& r) { return impact::test::contact_keys(r); }

template <class S>
std::set<Key> brute_force(const impact::MeshMotion<S>& a, const impact::MeshMotion<S>& b, bool self,
                          const impact::CcdOptions& o) {
  std::set<Key> k;
  impact::test::for_each_primitive_pair(
      *a.faces, *b.faces, self,
      [&](int mesh, std::int32_t v, std::int32_t f) {
        const impact::MeshMotion<S>& mv = mesh == 0 ? a : b;
        const impact::MeshMotion<S>& mf = mesh == 0 ? b : a;
        const auto& F = *mf.faces;
        const auto r = impact::vertex_face_ccd(mv.p0(v), mf.p0(F(f, 0)), mf.p0(F(f, 1)), mf.p0(F(f, 2)), mv.p1(v), mf.p1(F(f, 0)),
                                               mf.p1(F(f, 1)), mf.p1(F(f, 2)), o);
        if (r.hit) k.insert({0, mesh, v, f, 0});
      },
      [&](std::int32_t a0, std::int32_t a1, std::int32_t b0, std::int32_t b1) {
        const auto r = impact::edge_edge_ccd(a.p0(a0), a.p0(a1), b.p0(b0), b.p0(b1), a.p1(a0), a.p1(a1), b.p1(b0), b.p1(b1), o);
        if (r.hit) k.insert({1, a0, a1, b0, b1});
      });
  return k;
}

template <class S>
class MeshCcdTest : public ::testing::Test {};
using Scalars = ::testing::Types<float, double>;
TYPED_TEST_SUITE(MeshCcdTest, Scalars);

TYPED_TEST(MeshCcdTest, TwoMeshesMatchBruteForce) {
  using S = TypeParam;
  std::mt19937 rng(17);
  const Sheet<S> A = sheet<S>(6, S(0), S(0), S(0)), B = sheet<S>(5, S(0.15), S(0.1), S(0.2));
  for (double d : {0.0, 0.02}) {
    impact::CcdOptions o;
    o.min_separation = d;
    // Step 1: A rises through B; build. Step 2: it goes on rising; refit.
    impact::Vertices<S> A0 = jitter<S>(A.V, rng, S(0.02), S(0)), A1 = jitter<S>(A.V, rng, S(0.02), S(0.3));
    const impact::Vertices<S> B0 = jitter<S>(B.V, rng, S(0.02), S(0)), B1 = jitter<S>(B.V, rng, S(0.02), S(-0.05));
    auto ma = impact::make_mesh_motion(A0, A1, A.F);
    auto mb = impact::make_mesh_motion(B0, B1, B.F);
    auto ta = impact::SweptMeshBvh<S>::build(ma, d);
    auto tb = impact::SweptMeshBvh<S>::build(mb, d);
    auto r = impact::mesh_ccd(ma, ta, mb, tb, o);
    const auto bf = brute_force(ma, mb, false, o);
    EXPECT_FALSE(bf.empty());
    EXPECT_EQ(keys(r), bf);
    EXPECT_EQ(r.hit, !bf.empty());
    for (const auto& c : r.contacts) EXPECT_LE(r.toi, c.result.toi);

    // Next step: A moves on from A1; refit its tree instead of rebuilding.
    const impact::Vertices<S> A2 = jitter<S>(A1, rng, S(0.02), S(0.1));
    auto ma2 = impact::make_mesh_motion(A1, A2, A.F);
    ta.refit(ma2);
    r = impact::mesh_ccd(ma2, ta, mb, tb, o);
    EXPECT_EQ(keys(r), brute_force(ma2, mb, false, o));
  }
}

TYPED_TEST(MeshCcdTest, SelfMatchesBruteForce) {
  using S = TypeParam;
  std::mt19937 rng(23);
  const Sheet<S> A = sheet<S>(6, S(0), S(0), S(0));
  for (double d : {0.0, 0.01}) {
    impact::CcdOptions o;
    o.min_separation = d;
    // Crumple: vertices move by up to 1.5 grid cells, so the sheet passes through itself.
    const impact::Vertices<S> V0 = A.V, V1 = jitter<S>(A.V, rng, S(0.3), S(0));
    auto m = impact::make_mesh_motion(V0, V1, A.F);
    auto t = impact::SweptMeshBvh<S>::build(m, d);
    auto r = impact::mesh_self_ccd(m, t, o);
    const auto bf = brute_force(m, m, true, o);
    EXPECT_FALSE(bf.empty());
    EXPECT_EQ(keys(r), bf);
    // Refit for a second step.
    const impact::Vertices<S> V2 = jitter<S>(V1, rng, S(0.3), S(0));
    auto m2 = impact::make_mesh_motion(V1, V2, A.F);
    t.refit(m2);
    EXPECT_EQ(keys(impact::mesh_self_ccd(m2, t, o)), brute_force(m2, m2, true, o));
  }
}

// The number of distinct primitive pairs (adjacent ones skipped in self CCD) whose swept boxes,
// each grown by half the separation, overlap: the candidates mesh_ccd must test, no more (its
// primitive filter) and no fewer (a pair of boxes apart may still be within reach).
template <class S>
std::size_t box_overlapping_pairs(const impact::MeshMotion<S>& a, const impact::MeshMotion<S>& b, bool self, double d) {
  const S grow = impact::SweptMeshBvh<S>::half_separation(d);
  const auto box = [&](const impact::MeshMotion<S>& m, std::initializer_list<std::int32_t> vs) {
    impact::Aabb<S> x;
    for (auto v : vs) x.extend(impact::swept_aabb(m.p0(v), m.p1(v), grow));
    return x;
  };
  std::size_t n = 0;
  impact::test::for_each_primitive_pair(
      *a.faces, *b.faces, self,
      [&](int mesh, std::int32_t v, std::int32_t f) {
        const impact::MeshMotion<S>& mv = mesh == 0 ? a : b;
        const impact::MeshMotion<S>& mf = mesh == 0 ? b : a;
        const auto& F = *mf.faces;
        n += impact::overlap(box(mv, {v}), box(mf, {F(f, 0), F(f, 1), F(f, 2)})) ? 1 : 0;
      },
      [&](std::int32_t a0, std::int32_t a1, std::int32_t b0, std::int32_t b1) {
        n += impact::overlap(box(a, {a0, a1}), box(b, {b0, b1})) ? 1 : 0;
      });
  return n;
}

TYPED_TEST(MeshCcdTest, TestsExactlyThePairsWhoseBoxesOverlap) {
  using S = TypeParam;
  std::mt19937 rng(5);
  const Sheet<S> A = sheet<S>(7, S(0), S(0), S(0)), B = sheet<S>(6, S(0.15), S(0.1), S(0.2));
  for (double d : {0.0, 0.03}) {
    impact::CcdOptions o;
    o.min_separation = d;
    const impact::Vertices<S> A0 = jitter<S>(A.V, rng, S(0.02), S(0)), A1 = jitter<S>(A.V, rng, S(0.05), S(0.25));
    const impact::Vertices<S> B0 = jitter<S>(B.V, rng, S(0.02), S(0)), B1 = jitter<S>(B.V, rng, S(0.05), S(-0.05));
    const auto ma = impact::make_mesh_motion(A0, A1, A.F), mb = impact::make_mesh_motion(B0, B1, B.F);
    // trees grown for a larger separation than the query's: the filter uses the query's
    const auto ta = impact::SweptMeshBvh<S>::build(ma, 0.1), tb = impact::SweptMeshBvh<S>::build(mb, 0.1);
    const auto r = impact::mesh_ccd(ma, ta, mb, tb, o);
    EXPECT_EQ(r.primitive_tests, box_overlapping_pairs(ma, mb, false, d));
    EXPECT_EQ(keys(r), brute_force(ma, mb, false, o));
    const auto self = impact::mesh_self_ccd(ma, ta, o);
    EXPECT_EQ(self.primitive_tests, box_overlapping_pairs(ma, ma, true, d));
    // the filter removes most of what the triangle pairs give (9 edge pairs and 6 vertex-face
    // pairs each)
    EXPECT_LT(r.primitive_tests, 15 * r.triangle_pairs / 2);
  }
}

TYPED_TEST(MeshCcdTest, ContactsExactlyAtTheSeparationAreFound) {
  // A vertex that ends exactly min_separation above a face (a box face exactly on the other box's
  // face), and an edge that ends exactly min_separation beside another: both are contacts.
  using S = TypeParam;
  for (double d : {0.0, 0.25, 1.0 / 1024, 0.1}) {
    const S z = static_cast<S>(d);  // rounded: the contact is at distance z <= d or just above d
    if (static_cast<double>(z) > d) continue;
    impact::Faces F(1, 3);
    F << 0, 1, 2;
    impact::Vertices<S> floor(3, 3), v0(3, 3), v1(3, 3);
    floor << S(0), S(0), S(0), S(1), S(0), S(0), S(0), S(1), S(0);
    // the second triangle: its vertex 0 comes down onto the floor's interior point (0.25, 0.25)
    v0 << S(0.25), S(0.25), S(1), S(0.75), S(0.25), S(2), S(0.25), S(0.75), S(2);
    v1 = v0;
    v1.col(2).array() -= S(1) - z;
    const auto ma = impact::make_mesh_motion(floor, floor, F), mb = impact::make_mesh_motion(v0, v1, F);
    impact::CcdOptions o;
    o.min_separation = d;
    const auto ta = impact::SweptMeshBvh<S>::build(ma, d), tb = impact::SweptMeshBvh<S>::build(mb, d);
    const auto r = impact::mesh_ccd(ma, ta, mb, tb, o);
    EXPECT_TRUE(r.hit) << "vertex-face, d = " << d;
    EXPECT_EQ(keys(r).count({0, 1, 0, 0, 0}), 1u) << "vertex-face, d = " << d;

    // edge-edge: a segment along x at height 0 and one along y coming down to height z
    impact::Faces G(1, 3);
    G << 0, 1, 2;
    impact::Vertices<S> e0(3, 3), w0(3, 3), w1(3, 3);
    e0 << S(-1), S(0), S(0), S(1), S(0), S(0), S(0), S(-1), S(-3);  // edge 0-1 on the x axis, apex below
    w0 << S(0), S(-1), S(1), S(0), S(1), S(1), S(0), S(0), S(4);    // edge 0-1 along y, apex above
    w1 = w0;
    w1.col(2).array() -= S(1) - z;
    const auto me = impact::make_mesh_motion(e0, e0, G), mw = impact::make_mesh_motion(w0, w1, G);
    const auto te = impact::SweptMeshBvh<S>::build(me, d), tw = impact::SweptMeshBvh<S>::build(mw, d);
    const auto q = impact::mesh_ccd(me, te, mw, tw, o);
    EXPECT_EQ(keys(q).count({1, 0, 1, 0, 1}), 1u) << "edge-edge, d = " << d;
  }
}

TEST(MeshCcd, EveryVertexAndEdgeHasOneOwner) {
  // Random faces over 12 vertices, with repeated corners (a, a, b), repeated triangles and
  // unreferenced vertices: each referenced vertex and each distinct edge is owned by one slot.
  std::mt19937 rng(3);
  for (int round = 0; round < 50; ++round) {
    impact::Faces F(1 + static_cast<int>(rng() % 30), 3);
    for (Eigen::Index f = 0; f < F.rows(); ++f)
      for (int k = 0; k < 3; ++k) F(f, k) = static_cast<std::int32_t>(rng() % 12);
    const auto owns = impact::detail::primitive_owners(F, 12);
    ASSERT_EQ(owns.size(), static_cast<std::size_t>(F.rows()));
    std::map<std::int32_t, int> vertex_owners;
    std::map<std::array<std::int32_t, 2>, int> edge_owners;
    for (Eigen::Index f = 0; f < F.rows(); ++f)
      for (int k = 0; k < 3; ++k) {
        const std::int32_t v = F(f, k), w = F(f, (k + 1) % 3);
        vertex_owners[v] += (owns[std::size_t(f)] >> k) & 1;
        edge_owners[{std::min(v, w), std::max(v, w)}] += (owns[std::size_t(f)] >> (3 + k)) & 1;
      }
    for (const auto& [v, n] : vertex_owners) EXPECT_EQ(n, 1) << "vertex " << v;
    for (const auto& [e, n] : edge_owners) EXPECT_EQ(n, 1) << "edge " << e[0] << "-" << e[1];
  }
}

TEST(MeshCcd, FlatSheetHasNoSelfContact) {
  // A sheet translating rigidly never touches itself: adjacent primitives are skipped.
  const Sheet<double> A = sheet<double>(5, 0.0, 0.0, 0.0);
  impact::Vertices<double> V1 = A.V;
  V1.col(2).array() += 0.5;
  auto m = impact::make_mesh_motion(A.V, V1, A.F);
  auto t = impact::SweptMeshBvh<double>::build(m);
  const auto r = impact::mesh_self_ccd(m, t);
  EXPECT_FALSE(r.hit);
  EXPECT_GT(r.triangle_pairs, 0u);
}

TEST(MeshCcd, InvalidInputThrows) {
  const Sheet<double> A = sheet<double>(3, 0.0, 0.0, 0.0);
  impact::Vertices<double> V1 = A.V.topRows(4);
  EXPECT_THROW(impact::make_mesh_motion(A.V, V1, A.F), impact::InvalidInput);
}

}  // namespace
