// SPDX-License-Identifier: MIT
// Cone against convex hull (convex/cone_hull_pair.hpp and the cone–hull path of convex/query.hpp):
// the certified candidates, the side vertex's climb with a cone's lean, and the whole penetration,
// against an oracle: the least overlap f(n) = max(h n_z, r |P_z n| - h n_z) + max_v (-n . v) over
// unit directions (the hull's support by a scan of all its vertices, in long double), minimised by
// test::least_overlap (support/convex_oracle.hpp) with the kink circle of the cone's side normals,
// then again with the circles of the hull's edges whose ends both lie near the first minimiser's
// supporting plane (an edge against the rim: a valley along its arc). Its minimum is an upper bound
// of the true depth and every certified lower bound lies below the true depth, so a certificate of
// a wrong (too large) depth shows as depth - depth_gap above the oracle.
#include "impact/convex/cone_hull_pair.hpp"
#include "impact/convex/query.hpp"
#include "hull_pair_cases.hpp"
#include "support/convex_oracle.hpp"
#include "support/random.hpp"
#include "support/sanitizer.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

// a named namespace: the convex tests build as one unity file
namespace cone_hull_pair_test {

using namespace impact;
using namespace hull_pair_cases;

// The oracle of the file comment; `extra` (the normal under test) starts both passes.
test::LeastOverlap depth_oracle(const Cone<double>& a, const ConvexHull<double>& b, const Eigen::Matrix3d& R, const Eigen::Vector3d& t,
                                const Eigen::Vector3d& extra) {
  return solid_hull_depth_oracle(a, b, R, t, extra, a.radius / std::sqrt(4 * a.half_length * a.half_length + a.radius * a.radius));
}

using Case = SolidHullCase<Cone<double>>;

// Cones of varied proportions (every fourth the zoo's) against the hulls in turn, b about a,
// `scale` times the size and `offset` from the origin.
std::vector<Case> cases(int n, std::uint64_t seed, double scale = 1, double offset = 0) {
  return solid_hull_cases(Cone<double>(0.5, 0.6), n, seed, scale, offset);
}

// Each certified candidate: its lower bound below the oracle's depth (an upper bound of the true
// one), its depth within 1e-9 of the size of it and of the overlap along its normal; every kind
// certified (a hull face against the apex or the base rim, the base against a vertex, the side
// against an edge, the side against a vertex). Checked to fail: the edge's crossing taken with the
// other sign (not between the faces' normals); the side vertex's climb without the cone's lean
// (a cylinder's); the face ball's radius taken as the distance to the contact face alone.
TEST(ConeHullPair, CertifiedDepthsAgainstTheOracle) {
  int face = 0, base = 0, side_edges = 0, side_vertices = 0;
  for (const Case& c : cases(IMPACT_TEST_SANITIZED ? 120 : 200, 651)) {
    const ConvexHull<double>& h = hulls()[static_cast<std::size_t>(c.hull)];
    const double size = std::max(shape_size(c.solid), shape_size(h)), tol = 1e-10 * size;
    const detail::PairFrame<double> f(c.pa, c.pb);
    ConvexContact<double> k;
    const auto verdict = detail::cone_hull_candidates(c.solid, h, f.R, f.t, 1e-15, tol, k);
    if (verdict != detail::CylinderHullVerdict::Certified) continue;
    const test::LeastOverlap o = depth_oracle(c.solid, h, f.R, f.t, k.normal);
    const double oracle = double(o.depth);
    EXPECT_GT(oracle, 0) << "certified a pair the oracle finds apart";
    EXPECT_LE(k.depth - k.depth_gap, oracle + 1e-12 * size) << "lower bound above the depth";
    EXPECT_NEAR(k.depth, oracle, 1e-9 * size);
    EXPECT_NEAR(double(overlap_ld(c.solid, placed(h, f.R, f.t), k.normal.cast<LD>())), k.depth, 1e-12 * size);
    const double side_z = c.solid.radius / detail::cone_slant(c.solid);
    if (k.normal.z() < -1 + 1e-12) {
      ++base;
    } else if (std::abs(k.normal.z() - side_z) < 1e-12) {
      (support_count(placed(h, f.R, f.t), k.normal, size) == 1 ? side_vertices : side_edges) += 1;
    } else {
      ++face;
    }
  }
  EXPECT_GT(face, IMPACT_TEST_SANITIZED ? 0 : 2);
  EXPECT_GT(base, IMPACT_TEST_SANITIZED ? 0 : 2);
  EXPECT_GT(side_edges, IMPACT_TEST_SANITIZED ? 0 : 2);
  EXPECT_GT(side_vertices, IMPACT_TEST_SANITIZED ? 0 : 2);
}

// side_vertex with a cone's lean r / (2h) from every start vertex, axes passing 0.4 to 0.9 from the
// hull's centre: what it returns is the hull's support (a scan of all vertices, long double) along
// minus the cone's side normal at its azimuth (its offset from the axis, unit, plus the lean along
// the axis), and the climb moves (from a start that is not) for some starts. Checked to fail: the
// lean left out (the cylinder's radial direction).
TEST(ConeHullPair, SideVertexIsTheSupportAlongTheSideNormal) {
  test::Rng rng(652);
  int found = 0, moved = 0;
  for (const ConvexHull<double>& h : hulls()) {
    for (int j = 0; j < 10; ++j) {
      const Eigen::Vector3d ax = rng.vec(-1, 1).normalized(), away = ax.cross(rng.vec(-1, 1)).normalized();
      const Eigen::Vector3d c = h.centroid + rng.uniform(0.4, 0.9) * away + rng.uniform(-1, 1) * ax;
      const double lean = rng.uniform(0.1, 2.0);
      for (int start = 0; start < static_cast<int>(h.vertices.rows()); ++start) {
        const int v = detail::side_vertex(h, ax, c, start, lean);
        if (v < 0) continue;
        ++found;
        moved += v != start;
        const V3L y = (h.vertices.row(v).transpose() - c).cast<LD>(), a = ax.cast<LD>();
        const V3L q = y - y.dot(a) * a;
        const V3L w = q / q.norm() + LD(lean) * a;
        const LD top = -w.dot(h.vertices.row(v).transpose().cast<LD>());
        for (Eigen::Index i = 0; i < h.vertices.rows(); ++i)
          EXPECT_LE(-w.dot(h.vertices.row(i).transpose().cast<LD>()), top + LD(1e-12)) << "vertex " << v << " from " << start;
      }
    }
  }
  EXPECT_GT(found, 40);
  EXPECT_GT(moved, 20);
}

// The whole penetration, both argument orders, in S: the same boolean as the oracle away from
// touching, depth within `close` of the size of the oracle's, never a lower bound above it, and the
// overlap along the returned normal (the oracle's closed form) within `close` of the depth: the
// normal is a minimiser of the overlap.
template <class S>
void check_against_oracle(int count, double scale, double offset, std::uint64_t seed, double close) {
  int hits = 0, apart = 0;
  for (const Case& c : cases(IMPACT_TEST_SANITIZED ? std::max(16, count / 2) : count, seed, scale, offset)) {
    const ConvexHull<double> hd = scale == 1 ? hulls()[static_cast<std::size_t>(c.hull)] : scaled(hulls()[static_cast<std::size_t>(c.hull)], scale);
    const ConvexHull<S> hs = convex_hull(Vertices<S>(hd.vertices.cast<S>()));
    const Cone<S> cone(S(c.solid.radius), S(c.solid.half_length));
    const RigidTransform<S> pa{c.pa.R.cast<S>(), c.pa.t.cast<S>()}, pb{c.pb.R.cast<S>(), c.pb.t.cast<S>()};
    // the oracle on the shapes and poses as S holds them
    const RigidTransform<double> qa{pa.R.template cast<double>(), pa.t.template cast<double>()},
        qb{pb.R.template cast<double>(), pb.t.template cast<double>()};
    const ConvexHull<double> hq = convex_hull(Vertices<double>(hs.vertices.template cast<double>()));
    const Cone<double> cd(double(cone.radius), double(cone.half_length));
    const detail::PairFrame<double> f(qa, qb);
    const double size = std::max(shape_size(cd), shape_size(hq));
    const auto p = convex_penetration(cone, pa, hs, pb);
    const auto q = convex_penetration(hs, pb, cone, pa);
    const Eigen::Vector3d extra = p.intersecting ? Eigen::Vector3d(qa.R.transpose() * p.normal.template cast<double>()) : Eigen::Vector3d::UnitZ();
    const double oracle = double(depth_oracle(cd, hq, f.R, f.t, extra).depth);
    if (std::abs(oracle) < std::max(1e-5, 10 * close) * size) continue;  // touching: either answer
    EXPECT_EQ(p.intersecting, oracle > 0);
    EXPECT_EQ(q.intersecting, oracle > 0);
    if (oracle < 0) ++apart;
    if (oracle < 0 || !p.intersecting || !q.intersecting) continue;
    ++hits;
    const std::vector<V3L> v = placed(hq, f.R, f.t);
    for (const auto& r : {p, q}) {
      EXPECT_LE(double(r.depth - r.depth_gap), oracle + close * size) << "lower bound above the depth";
      EXPECT_NEAR(double(r.depth), oracle, close * size);
      EXPECT_FALSE(r.limit_reached);
    }
    // p's normal from the cone towards the hull, q's from the hull towards the cone (a's frame)
    const Eigen::Vector3d np = qa.R.transpose() * p.normal.template cast<double>(), nq = -(qa.R.transpose() * q.normal.template cast<double>());
    EXPECT_NEAR(double(overlap_ld(cd, v, np.normalized().cast<LD>())), oracle, close * size);
    EXPECT_NEAR(double(overlap_ld(cd, v, nq.normalized().cast<LD>())), oracle, close * size);
  }
  EXPECT_GT(hits, IMPACT_TEST_SANITIZED ? 1 : count / 5);
  EXPECT_GT(apart, IMPACT_TEST_SANITIZED ? -1 : count / 20);
}

TEST(ConeHullPair, PenetrationAgainstTheOracle) {
  check_against_oracle<double>(80, 1, 0, 653, 1e-9);
  check_against_oracle<float>(24, 1, 0, 654, 2e-4);
}

TEST(ConeHullPair, ScaledAndTranslated) {
  check_against_oracle<double>(20, 1e-3, 0, 655, 1e-9);
  check_against_oracle<double>(20, 1e3, 0, 656, 1e-9);
  check_against_oracle<double>(20, 1, 1e3, 657, 1e-9);
}

}  // namespace cone_hull_pair_test
