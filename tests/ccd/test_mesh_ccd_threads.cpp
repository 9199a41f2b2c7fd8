// SPDX-License-Identifier: MIT
// mesh_ccd / mesh_self_ccd on several threads (label "concurrency", also run under
// ThreadSanitizer): the contacts (in order, every field bit for bit), toi and counters are those
// of one thread for 2, 3 and 8 threads; the one-thread answer itself is
// checked against a brute-force loop over every primitive pair on a smaller case in
// test_mesh_ccd.cpp. Also: concurrent calls on shared trees.
#include "impact/ccd/mesh_ccd.hpp"
#include "sheets.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <thread>

namespace {

using impact::test::jitter;
using impact::test::Sheet;
using impact::test::sheet;

template <class S>
void expect_same(const impact::MeshCcdResult<S>& a, const impact::MeshCcdResult<S>& b, int threads) {
  ASSERT_EQ(a.contacts.size(), b.contacts.size()) << threads;
  EXPECT_EQ(a.hit, b.hit);
  EXPECT_EQ(0, std::memcmp(&a.toi, &b.toi, sizeof(S)));
  EXPECT_EQ(a.triangle_pairs, b.triangle_pairs);
  EXPECT_EQ(a.primitive_tests, b.primitive_tests);
  for (std::size_t k = 0; k < a.contacts.size(); ++k) {
    const auto &x = a.contacts[k], &y = b.contacts[k];
    ASSERT_TRUE(x.kind == y.kind && x.vertex_mesh == y.vertex_mesh && x.vertex == y.vertex && x.face == y.face && x.a0 == y.a0 &&
                x.a1 == y.a1 && x.b0 == y.b0 && x.b1 == y.b1)
        << "contact " << k << ", " << threads << " threads";
    ASSERT_EQ(0, std::memcmp(&x.result.toi, &y.result.toi, sizeof(S))) << k;
    ASSERT_EQ(x.result.hit, y.result.hit);
  }
}

template <class S>
class MeshCcdThreads : public ::testing::Test {};
using Scalars = ::testing::Types<float, double>;
TYPED_TEST_SUITE(MeshCcdThreads, Scalars);

TYPED_TEST(MeshCcdThreads, SameContactsForEveryThreadCount) {
  using S = TypeParam;
  std::mt19937 rng(31);
  const Sheet<S> A = sheet<S>(12, S(0)), B = sheet<S>(10, S(0.05));
  const impact::Vertices<S> A0 = jitter<S>(A.V, rng, 0.01, 0), A1 = jitter<S>(A.V, rng, 0.01, 0.12);
  const impact::Vertices<S> B0 = jitter<S>(B.V, rng, 0.01, 0), B1 = jitter<S>(B.V, rng, 0.01, -0.02);
  impact::CcdOptions o;
  o.min_separation = 0.001;
  const auto ma = impact::make_mesh_motion(A0, A1, A.F), mb = impact::make_mesh_motion(B0, B1, B.F);
  const auto ta = impact::SweptMeshBvh<S>::build(ma, o.min_separation), tb = impact::SweptMeshBvh<S>::build(mb, o.min_separation);
  const auto ref = impact::mesh_ccd(ma, ta, mb, tb, o, 1);
  ASSERT_GT(ref.primitive_tests, 2048u);  // above the serial cut-off
  ASSERT_GT(ref.triangle_pairs, 1400u);   // candidate lists joined on the threads (sorted_union: over 8,192 entries)
  ASSERT_GT(ref.contacts.size(), 20u);
  for (const int t : {2, 3, 8}) expect_same(impact::mesh_ccd(ma, ta, mb, tb, o, t), ref, t);

  // self CCD of a crumpling sheet
  const impact::Vertices<S> C1 = jitter<S>(A.V, rng, 0.1, 0);
  const auto mc = impact::make_mesh_motion(A.V, C1, A.F);
  const auto tc = impact::SweptMeshBvh<S>::build(mc, o.min_separation);
  const auto sref = impact::mesh_self_ccd(mc, tc, o, 1);
  ASSERT_GT(sref.primitive_tests, 2048u);
  ASSERT_GT(sref.triangle_pairs, 1400u);
  ASSERT_GT(sref.contacts.size(), 10u);
  for (const int t : {2, 3, 8}) expect_same(impact::mesh_self_ccd(mc, tc, o, t), sref, t);
}

// Four threads querying the same trees at once (each also running its own parallel calls).
TEST(MeshCcdConcurrency, SharedTreesFromManyThreads) {
  using S = double;
  std::mt19937 rng(5);
  const Sheet<S> A = sheet<S>(16, 0.0);
  const impact::Vertices<S> C1 = jitter<S>(A.V, rng, 0.08, 0);
  const auto m = impact::make_mesh_motion(A.V, C1, A.F);
  const auto t = impact::SweptMeshBvh<S>::build(m);
  const auto ref = impact::mesh_self_ccd(m, t, {}, 1);
  ASSERT_TRUE(ref.hit);
  std::vector<impact::MeshCcdResult<S>> out(4);
  std::vector<std::thread> pool;
  for (int k = 0; k < 4; ++k) pool.emplace_back([&, k] { out[std::size_t(k)] = impact::mesh_self_ccd(m, t, {}, 2); });
  for (auto& th : pool) th.join();
  for (const auto& r : out) expect_same(r, ref, 2);
}

}  // namespace
