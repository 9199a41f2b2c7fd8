// SPDX-License-Identifier: MIT
// Metamorphic tests over the query files with exact ground truth ($IMPACT_DATA_DIR/ccd-queries):
// every transform of ccd_transforms.hpp (time reversal, face vertex rotation and reflection,
// swapped and reversed edges, axis permutation, mirroring, scaling by 2^40 and 2^-40, exact
// translation) keeps the exact answer, so on every query: a contact stays a hit (zero false
// negatives), a miss stays a miss (no false positive gained), and in total no more false
// positives than the untransformed queries. Scaling by a power of two and exact translation
// must give the very same result (hit, toi, u, v and iteration counts): the search is scale-free
// and its error bounds relative to the query's extent. The worst-case time of each transform is
// measured by impact-ccd-bench (metamorphic section), not here. The unit label runs every fifth
// query; the binary built with IMPACT_CCD_METAMORPHIC_FULL (impact-ccd-metamorphic-full, label
// data-full, which the sanitizer run skips) runs them all.
#include "ccd/ccd_transforms.hpp"
#include "impact/ccd/edge_edge.hpp"
#include "impact/ccd/vertex_face.hpp"
#include "support/data.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

namespace {

using impact::test::CcdQueryRecord;

impact::CcdResult<double> run(const std::string& kind, const CcdQueryRecord& q, const impact::CcdOptions& o = {}) {
  const auto& p = q.points;
  if (kind == "vertex-face") return impact::vertex_face_ccd(p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7], o);
  return impact::edge_edge_ccd(p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7], o);
}

struct Query {
  std::string where;
  CcdQueryRecord q;
  impact::CcdResult<double> base;
};

#ifdef IMPACT_CCD_METAMORPHIC_FULL
constexpr std::size_t kStride = 1;
#else
constexpr std::size_t kStride = 5;
#endif

// Every kStride-th query of one kind (in file order), with its untransformed result.
std::vector<Query> load(const std::string& kind) {
  std::vector<Query> out;
  std::size_t n = 0;
  const char* env = std::getenv("IMPACT_DATA_DIR");
  const std::string root = std::string(env ? env : "") + "/ccd-queries";
  for (const auto& f : impact::test::find_ccd_query_files(root, kind)) {
    const auto qs = impact::test::read_ccd_queries(f);
    for (std::size_t i = 0; i < qs.size(); ++i)
      if (n++ % kStride == 0) out.push_back({f + " query " + std::to_string(i), qs[i], run(kind, qs[i])});
  }
  return out;
}

bool same_result(const impact::CcdResult<double>& a, const impact::CcdResult<double>& b) {
  return a.hit == b.hit && a.toi == b.toi && a.u == b.u && a.v == b.v && a.budget_exhausted == b.budget_exhausted &&
         a.iterations == b.iterations && a.recheck_iterations == b.recheck_iterations;
}

void check_kind(const std::string& kind) {
  IMPACT_REQUIRE_DATA(root, "ccd-queries/README.md");
  const auto queries = load(kind);
  ASSERT_FALSE(queries.empty());
  std::size_t base_fp = 0;
  for (const auto& x : queries) base_fp += !x.q.truth && x.base.hit;
  for (const auto& name : impact::test::ccd_transform_names()) {
    if (!impact::test::ccd_transform_applies(name, kind)) continue;
    const bool identical = name == "scale-up" || name == "scale-down" || name == "translate";
    std::size_t fp = 0, fn = 0, gained = 0, differ = 0, translated = 0;
    for (const auto& x : queries) {
      CcdQueryRecord t = x.q;
      ASSERT_TRUE(impact::test::apply_ccd_transform(name, kind, t)) << name << " " << x.where;
      translated += t.points[0] != x.q.points[0];
      const auto r = run(kind, t);
      if (x.q.truth && !r.hit) {
        ++fn;
        ADD_FAILURE() << name << ": false negative on " << x.where;
      }
      if (!x.q.truth && r.hit) ++fp;
      if (!x.base.hit && r.hit) {
        ++gained;
        ADD_FAILURE() << name << ": a miss became a hit on " << x.where;
      }
      if (identical && !same_result(r, x.base)) {
        ++differ;
        ADD_FAILURE() << name << ": result differs on " << x.where << ": hit " << r.hit << "/" << x.base.hit << " toi " << r.toi
                      << "/" << x.base.toi << " iterations " << r.iterations << "/" << x.base.iterations << " recheck "
                      << r.recheck_iterations << "/" << x.base.recheck_iterations;
      }
    }
    EXPECT_EQ(fn, 0u) << name;
    EXPECT_LE(fp, base_fp) << name;
    std::printf("[metamorphic] %-12s %-13s queries %zu FP %zu (untransformed %zu) FN %zu misses turned hits %zu results differing %zu\n",
                kind.c_str(), name.c_str(), queries.size(), fp, base_fp, fn, gained, differ);
    if (name == "translate") {
      EXPECT_GT(translated, queries.size() / 2);  // the translation is not vacuous
    }
  }
}

#ifdef IMPACT_CCD_METAMORPHIC_FULL
TEST(CcdMetamorphicFull, VertexFace) { check_kind("vertex-face"); }
TEST(CcdMetamorphicFull, EdgeEdge) { check_kind("edge-edge"); }
#else
TEST(CcdMetamorphic, VertexFace) { check_kind("vertex-face"); }
TEST(CcdMetamorphic, EdgeEdge) { check_kind("edge-edge"); }

// Scale-freedom over the whole double range on constructed queries: a point falling through a
// triangle (hit), beside it (miss) and an edge pair crossing, scaled by 2^k for k from -1070 to
// 1020 (the coordinates have few bits, so even subnormal ones are exact): the same result as at
// scale 1, bit for bit. Before, the tolerance was absolute and the coordinates had to be below
// 1e100.
TEST(CcdScaleFree, WholeDoubleRange) {
  using V = impact::Vec3<double>;
  const V vf[3][8] = {
      {V(0.25, 0.25, 1), V(0, 0, 0), V(1, 0, 0), V(0, 1, 0), V(0.25, 0.25, -1), V(0, 0, 0), V(1, 0, 0), V(0, 1, 0)},
      {V(0.75, 0.5, 1), V(0, 0, 0), V(1, 0, 0), V(0, 1, 0), V(0.75, 0.5, -1), V(0, 0, 0), V(1, 0, 0), V(0, 1, 0)},
      {V(-1, 0, 0), V(1, 0, 0), V(0.5, -1, 0.25), V(0.5, 1, 0.25), V(-1, 0, 0), V(1, 0, 0), V(0.5, -1, -0.75), V(0.5, 1, -0.75)}};
  impact::CcdOptions o;
  o.tolerance = 1e-3;  // coarse enough that the hit ends on the tolerance, not on rounding
  for (int c = 0; c < 3; ++c) {
    auto query = [&](int k) {
      V p[8];
      for (int j = 0; j < 8; ++j) p[j] = vf[c][j] * std::ldexp(1.0, k);
      return c < 2 ? impact::vertex_face_ccd(p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7], o)
                   : impact::edge_edge_ccd(p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7], o);
    };
    const auto ref = query(0);
    EXPECT_EQ(ref.hit, c != 1);
    for (int k = -1070; k <= 1020; k += 13) EXPECT_TRUE(same_result(query(k), ref)) << "case " << c << " scale 2^" << k;
  }
}

// The tolerance is relative to the query's extent: at toi the primitives are within
// 2 tolerance extent (d = 0), at any scale (an absolute tolerance of 0.1 at s = 1e-9 would stop
// anywhere). The point falls from z = s to -s onto the unit triangle scaled by s; extent 2 s;
// contact at t = 1/2.
TEST(CcdScaleFree, ToleranceIsRelativeToTheExtent) {
  using V = impact::Vec3<double>;
  for (double s : {1e-9, 1.0, 3.0, 1e9}) {
    for (double tol : {1e-1, 1e-3}) {
      impact::CcdOptions o;
      o.tolerance = tol;
      o.recheck_iterations = 0;
      const V f0(0, 0, 0), f1(s, 0, 0), f2(0, s, 0);
      const auto r = impact::vertex_face_ccd(V(0.25 * s, 0.25 * s, s), f0, f1, f2, V(0.25 * s, 0.25 * s, -s), f0, f1, f2, o);
      ASSERT_TRUE(r.hit);
      EXPECT_LE(r.toi, 0.5);
      const double gap = 2 * s * (0.5 - r.toi);  // |z(toi)|
      EXPECT_LE(gap, 2 * tol * (2 * s) * (1 + 1e-12)) << s << " " << tol;
    }
  }
}
#endif

}  // namespace
