// SPDX-License-Identifier: MIT
// Mesh-level CCD against a brute-force loop over all primitive pairs (the same primitive tests,
// so the sets of colliding pairs must be equal): two meshes, self CCD skipping adjacent
// primitives, refit between steps, minimum separation. Float and double.
#include "impact/ccd/mesh_ccd.hpp"
#include "sheets.hpp"

#include <gtest/gtest.h>

#include <random>
#include <set>

namespace {

using impact::test::jitter;
using impact::test::Sheet;
using impact::test::sheet;

std::set<std::array<std::int32_t, 2>> unique_edges(const impact::Faces& F) {
  std::set<std::array<std::int32_t, 2>> e;
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      std::int32_t a = F(f, k), b = F(f, (k + 1) % 3);
      if (a > b) std::swap(a, b);
      e.insert({a, b});
    }
  return e;
}

using Key = std::array<std::int32_t, 5>;  // kind, then ids

template <class S>
std::set<Key> keys(const impact::MeshCcdResult<S>& r) {
  std::set<Key> k;
  for (const auto& c : r.contacts) {
    if (c.kind == impact::MeshCcdKind::VertexFace)
      k.insert({0, c.vertex_mesh, c.vertex, c.face, 0});
    else
      k.insert({1, c.a0, c.a1, c.b0, c.b1});
  }
  return k;
}

template <class S>
std::set<Key> brute_force(const impact::MeshMotion<S>& a, const impact::MeshMotion<S>& b, bool self,
                          const impact::CcdOptions& o) {
  std::set<Key> k;
  auto vf = [&](int mesh, const impact::MeshMotion<S>& mv, const impact::MeshMotion<S>& mf) {
    std::set<std::int32_t> verts;
    for (Eigen::Index f = 0; f < mv.faces->rows(); ++f)
      for (int j = 0; j < 3; ++j) verts.insert((*mv.faces)(f, j));
    const auto& F = *mf.faces;
    for (std::int32_t v : verts)
      for (std::int32_t f = 0; f < F.rows(); ++f) {
        if (self && (F(f, 0) == v || F(f, 1) == v || F(f, 2) == v)) continue;
        const auto r = impact::vertex_face_ccd(mv.p0(v), mf.p0(F(f, 0)), mf.p0(F(f, 1)), mf.p0(F(f, 2)), mv.p1(v), mf.p1(F(f, 0)),
                                               mf.p1(F(f, 1)), mf.p1(F(f, 2)), o);
        if (r.hit) k.insert({0, mesh, v, f, 0});
      }
  };
  vf(0, a, b);
  if (!self) vf(1, b, a);
  const auto ea = unique_edges(*a.faces), eb = unique_edges(*b.faces);
  for (const auto& x : ea)
    for (const auto& y : eb) {
      if (self && (x[0] == y[0] || x[0] == y[1] || x[1] == y[0] || x[1] == y[1] || !(x < y))) continue;
      const auto r = impact::edge_edge_ccd(a.p0(x[0]), a.p0(x[1]), b.p0(y[0]), b.p0(y[1]), a.p1(x[0]), a.p1(x[1]), b.p1(y[0]),
                                           b.p1(y[1]), o);
      if (r.hit) k.insert({1, x[0], x[1], y[0], y[1]});
    }
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
