// SPDX-License-Identifier: MIT
// Ground truth: every query file under $IMPACT_DATA_DIR/ccd-queries. Zero false negatives is
// asserted; false positives are reported (RecordProperty and stdout). Also checks the exact
// conversion of the rational coordinates.
#include "impact/ccd/edge_edge.hpp"
#include "impact/ccd/vertex_face.hpp"
#include "support/ccd_queries.hpp"
#include "support/data.hpp"

#include <gtest/gtest.h>

#include <cstdio>

namespace {

TEST(CcdQueryReader, ExactConversion) {
  double v = 0;
  EXPECT_TRUE(impact::test::exact_ratio_to_double("3", "4", v));
  EXPECT_EQ(v, 0.75);
  EXPECT_TRUE(impact::test::exact_ratio_to_double("-5", "1", v));
  EXPECT_EQ(v, -5.0);
  EXPECT_TRUE(impact::test::exact_ratio_to_double("0", "8", v));
  EXPECT_EQ(v, 0.0);
  EXPECT_FALSE(impact::test::exact_ratio_to_double("1", "3", v));                 // not a binary fraction
  EXPECT_FALSE(impact::test::exact_ratio_to_double("1", "0", v));                 // division by zero
  EXPECT_FALSE(impact::test::exact_ratio_to_double("9007199254740993", "1", v));  // 2^53 + 1: 54 bits
  EXPECT_TRUE(impact::test::exact_ratio_to_double("9007199254740992", "1", v));   // 2^53
  EXPECT_EQ(v, 9007199254740992.0);
  // A 34-digit denominator (2^111) as in the data: 5348868689029467 / 2^111.
  EXPECT_TRUE(impact::test::exact_ratio_to_double("-5348868689029467", "2596148429267413814265248164610048", v));
  EXPECT_EQ(v, -std::ldexp(5348868689029467.0, -111));
  EXPECT_FALSE(impact::test::exact_ratio_to_double("1x", "2", v));
}

struct KindStats {
  std::size_t queries = 0, positives = 0, fp = 0, fn = 0;
};

KindStats run_kind(const std::string& root, const std::string& kind) {
  KindStats s;
  const auto files = impact::test::find_ccd_query_files(root, kind);
  EXPECT_FALSE(files.empty()) << "no " << kind << " files under " << root;
  for (const auto& f : files) {
    const auto queries = impact::test::read_ccd_queries(f);
    std::size_t i = 0;
    for (const auto& q : queries) {
      const auto& p = q.points;
      const auto r = kind == "vertex-face" ? impact::vertex_face_ccd(p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7])
                                           : impact::edge_edge_ccd(p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7]);
      ++s.queries;
      s.positives += q.truth;
      if (q.truth && !r.hit) {
        ++s.fn;
        ADD_FAILURE() << "false negative: " << f << " query " << i;
      }
      if (!q.truth && r.hit) ++s.fp;
      ++i;
    }
  }
  std::printf("[ccd-queries] %-12s queries %zu positives %zu false positives %zu false negatives %zu\n", kind.c_str(), s.queries,
              s.positives, s.fp, s.fn);
  return s;
}

TEST(CcdGroundTruth, VertexFaceNoFalseNegatives) {
  IMPACT_REQUIRE_DATA(root, "ccd-queries/README.md");
  const std::string dir = root.substr(0, root.size() - std::string("/README.md").size());
  const auto s = run_kind(dir, "vertex-face");
  EXPECT_EQ(s.fn, 0u);
  RecordProperty("queries", int(s.queries));
  RecordProperty("false_positives", int(s.fp));
}

TEST(CcdGroundTruth, EdgeEdgeNoFalseNegatives) {
  IMPACT_REQUIRE_DATA(root, "ccd-queries/README.md");
  const std::string dir = root.substr(0, root.size() - std::string("/README.md").size());
  const auto s = run_kind(dir, "edge-edge");
  EXPECT_EQ(s.fn, 0u);
  RecordProperty("queries", int(s.queries));
  RecordProperty("false_positives", int(s.fp));
}

}  // namespace
