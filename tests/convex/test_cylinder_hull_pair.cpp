// SPDX-License-Identifier: MIT
// Cylinder against convex hull (convex/cylinder_hull_pair.hpp and the cylinder–hull path of
// convex/query.hpp): the certified candidates, the local certificate's terms (also a cone's
// against a hull, convex/cone_hull_terms.hpp) and the whole
// penetration, against an oracle: the least overlap f(n) = h |n_z| + r |P_z n| + max_v (-n . v)
// over unit directions (the hull's support by a scan of all its vertices, in long double),
// minimised by test::least_overlap (support/convex_oracle.hpp) with the kink circle of the
// cylinder's side, then again with the circles of the hull's edges whose ends both lie near the
// first minimiser's supporting plane (an edge against the rim: a valley along its arc). Its
// minimum is an upper bound of the true depth and every certified lower bound lies below the
// true depth, so a certificate of a wrong (too large) depth shows as depth - depth_gap above the
// oracle.
#include "impact/convex/cone_hull_terms.hpp"
#include "impact/convex/cylinder_hull_pair.hpp"
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
namespace cylinder_hull_pair_test {

using namespace impact;
using namespace hull_pair_cases;

// The oracle of the file comment; `extra` (the normal under test) starts both passes.
test::LeastOverlap depth_oracle(const Cylinder<double>& a, const ConvexHull<double>& b, const Eigen::Matrix3d& R, const Eigen::Vector3d& t,
                                const Eigen::Vector3d& extra) {
  return solid_hull_depth_oracle(a, b, R, t, extra, 0);
}

using Case = SolidHullCase<Cylinder<double>>;

using test::overlap_terms_value;

// Cylinders of varied proportions (every fourth the zoo's) against the hulls in turn, b about a,
// `scale` times the size and `offset` from the origin.
std::vector<Case> cases(int n, std::uint64_t seed, double scale = 1, double offset = 0) {
  return solid_hull_cases(Cylinder<double>(0.4, 0.5), n, seed, scale, offset);
}

// Each certified candidate: its lower bound below the oracle's depth (an upper bound of the true
// one), its depth within 1e-9 of the size of it and the overlap along its normal; every kind
// certified (a hull face, a cap, the side against an edge, the side against a vertex). Checked to
// fail: the face ball's radius taken as the distance to the contact face alone (not the least over
// the faces); the side vertex taken where the climb starts (no climb); its ball's radius taken as
// its distance to the side alone (not the caps').
TEST(CylinderHullPair, CertifiedDepthsAgainstTheOracle) {
  int face = 0, cap = 0, side = 0, side_vertices = 0;
  for (const Case& c : cases(IMPACT_TEST_SANITIZED ? 30 : 150, 641)) {
    const ConvexHull<double>& h = hulls()[static_cast<std::size_t>(c.hull)];
    const double size = std::max(shape_size(c.solid), shape_size(h)), tol = 1e-10 * size;
    const detail::PairFrame<double> f(c.pa, c.pb);
    ConvexContact<double> k;
    const auto verdict = detail::cylinder_hull_candidates(c.solid, h, f.R, f.t, 1e-15, tol, k);
    if (verdict != detail::CylinderHullVerdict::Certified) continue;
    const test::LeastOverlap o = depth_oracle(c.solid, h, f.R, f.t, k.normal);
    const double oracle = double(o.depth);
    EXPECT_GT(oracle, 0) << "certified a pair the oracle finds apart";
    EXPECT_LE(k.depth - k.depth_gap, oracle + 1e-12 * size) << "lower bound above the depth";
    EXPECT_NEAR(k.depth, oracle, 1e-9 * size);
    EXPECT_NEAR(double(overlap_ld(c.solid, placed(h, f.R, f.t), k.normal.cast<LD>())), k.depth, 1e-12 * size);
    if (std::abs(k.normal.z()) > 1 - 1e-12) {
      ++cap;
    } else if (std::abs(k.normal.z()) < 1e-12) {
      ++side;
      side_vertices += support_count(placed(h, f.R, f.t), k.normal, size) == 1;
    } else {
      ++face;
    }
  }
  EXPECT_GT(face, IMPACT_TEST_SANITIZED ? 0 : 2);
  EXPECT_GT(cap, IMPACT_TEST_SANITIZED ? 0 : 2);
  EXPECT_GT(side, IMPACT_TEST_SANITIZED ? 0 : 2);
  EXPECT_GT(side_vertices, IMPACT_TEST_SANITIZED ? 0 : 2);
}

// side_vertex from every start vertex, axes passing 0.4 to 0.9 from the hull's centre (an axis
// through the hull has no vertex against its side): what it returns is the hull's support (a scan
// of all vertices, long double) along minus its offset from the axis, and the climb moves (from a
// start that is not) for some starts. Checked to fail: the start returned without the climb.
TEST(CylinderHullPair, SideVertexIsTheSupportAlongItsOffset) {
  test::Rng rng(649);
  int found = 0, moved = 0;
  for (const ConvexHull<double>& h : hulls()) {
    for (int j = 0; j < 10; ++j) {
      const Eigen::Vector3d ax = rng.vec(-1, 1).normalized(), away = ax.cross(rng.vec(-1, 1)).normalized();
      const Eigen::Vector3d c = h.centroid + rng.uniform(0.4, 0.9) * away + rng.uniform(-1, 1) * ax;
      for (int start = 0; start < static_cast<int>(h.vertices.rows()); ++start) {
        const int v = detail::side_vertex(h, ax, c, start);
        if (v < 0) continue;
        ++found;
        moved += v != start;
        const V3L y = (h.vertices.row(v).transpose() - c).cast<LD>(), a = ax.cast<LD>();
        const V3L q = y - y.dot(a) * a;
        const LD top = -q.dot(h.vertices.row(v).transpose().cast<LD>());
        for (Eigen::Index i = 0; i < h.vertices.rows(); ++i)
          EXPECT_LE(-q.dot(h.vertices.row(i).transpose().cast<LD>()), top + LD(1e-12)) << "vertex " << v << " from " << start;
      }
    }
  }
  EXPECT_GT(found, 40);  // 91 and 85 when written
  EXPECT_GT(moved, 20);
}

// The local certificate's terms, of cylinder_hull_terms and of convex/cone_hull_terms.hpp (a cone
// of the cylinder's radius and half length; its branch, and the body along a side ruling): at most
// the overlap everywhere, equal to it along the direction they were built at; the side body's own
// part equal to the cone's support where that is the ruling's base rim point. Checked to fail: the
// edge's abs term with twice its coefficient; the cone's rim branch with its linear term's sign
// turned; the inactive branch; the side body's support not mirrored; the side body on the opposite
// ruling.
TEST(CylinderHullPair, TermsBoundTheOverlap) {
  test::Rng rng(642);
  test::Rng rim_rng(644);  // its own, so the other directions stay those drawn before
  int cone_terms = 0, side_terms = 0;
  for (const Case& c : cases(30, 643)) {
    const ConvexHull<double>& h = hulls()[static_cast<std::size_t>(c.hull)];
    const Cone<double> cone(c.solid.radius, c.solid.half_length);
    const detail::PairFrame<double> f(c.pa, c.pb);
    const std::vector<V3L> v = placed(h, f.R, f.t);
    for (int j = 0; j < 6; ++j) {
      const Eigen::Vector3d n = rng.vec(-1, 1).normalized();
      const detail::OverlapTerms<double> terms = detail::cylinder_hull_terms(c.solid, h, f.R, f.t, n);
      detail::OverlapTerms<double> ct;
      const bool has_cone = detail::cone_hull_terms(cone, h, f.R, f.t, n, detail::cone_branch(cone, n), ct);
      cone_terms += has_cone;
      EXPECT_NEAR(overlap_terms_value(terms, n), double(overlap_ld(c.solid, v, n.cast<LD>())), 1e-12);
      if (has_cone) {
        EXPECT_NEAR(overlap_terms_value(ct, n), double(overlap_ld(cone, v, n.cast<LD>())), 1e-12);
      }
      // the body inside the cone along the ruling the hull's feature along -n touches, at that
      // ruling's side normal s, over a random span
      Eigen::Vector3d e, s = Eigen::Vector3d::Zero();
      detail::OverlapTerms<double> st;
      bool has_side = false;
      if (detail::cone_hull_side_azimuth(cone, h, f.R, f.t, n, e)) {
        s = Eigen::Vector3d(2 * cone.half_length * e.x(), 2 * cone.half_length * e.y(), cone.radius).normalized();
        has_side = detail::cone_side_hull_terms(cone, h, f.R, f.t, s, e, rng.uniform(0.1, 0.95), st);
      }
      side_terms += has_side;
      if (has_side) {
        EXPECT_NEAR(overlap_terms_value(st, s), double(overlap_ld(cone, v, s.cast<LD>())), 1e-12);
        // the body holds that ruling's base rim point, so its own part (the terms less the hull's)
        // is the cone's support along the directions whose support is that point: between s and
        // -z in the plane of e and z (a body on another ruling is not, though it still bounds)
        detail::OverlapTerms<double> hull_part;
        detail::add_hull_feature_terms(h, f.R, f.t, s, hull_part);
        for (int i = 0; i < 3; ++i) {
          const Eigen::Vector3d w = (s - rim_rng.uniform(0.05, 2.0) * Eigen::Vector3d::UnitZ()).normalized();
          const double rim = cone.radius * std::hypot(w.x(), w.y()) - cone.half_length * w.z();
          EXPECT_NEAR(overlap_terms_value(st, w) - overlap_terms_value(hull_part, w), std::max(cone.half_length * w.z(), rim), 1e-12);
        }
      }
      for (int i = 0; i < 10; ++i) {
        const Eigen::Vector3d m = rng.vec(-1, 1).normalized();
        EXPECT_LE(overlap_terms_value(terms, m), double(overlap_ld(c.solid, v, m.cast<LD>())) + 1e-12);
        if (has_cone) {
          EXPECT_LE(overlap_terms_value(ct, m), double(overlap_ld(cone, v, m.cast<LD>())) + 1e-12);
        }
        if (has_side) {
          EXPECT_LE(overlap_terms_value(st, m), double(overlap_ld(cone, v, m.cast<LD>())) + 1e-12);
        }
      }
    }
  }
  EXPECT_GT(cone_terms, 150);  // of 180 directions
  EXPECT_GT(side_terms, 100);
}

// The terms of a square inside a hull face (add_hull_face_square_terms) with the cylinder's, at
// minus each face's normal of each case (x a point above the face's centre, so that its projection
// lies inside): never above the overlap along random directions (the square lies inside the hull),
// equal to it at the face's normal, and built for most faces (the slab's merged polygons too); not
// built for a point beyond the face's edges. Checked to fail: the square's half-side delta instead
// of delta / sqrt(2) (its corners outside the triangle); the triangle's inward normal reversed (no
// face built).
TEST(CylinderHullPair, FaceSquareTermsBoundTheOverlap) {
  test::Rng rng(649);
  int built = 0, merged = 0, faces = 0;
  for (const Case& c : cases(12, 650)) {
    const ConvexHull<double>& h = hulls()[static_cast<std::size_t>(c.hull)];
    const detail::PairFrame<double> f(c.pa, c.pb);
    const std::vector<V3L> v = placed(h, f.R, f.t);
    const double size = std::max(shape_size(c.solid), shape_size(h));
    for (std::size_t k = 0; k < h.faces.size(); ++k) {
      const Eigen::Vector3d n = -(f.R * h.faces[k].normal);
      detail::OverlapTerms<double> terms;
      terms.add(Eigen::Vector3d::UnitZ(), c.solid.radius, true);
      terms.add(Eigen::Vector3d::UnitZ(), c.solid.half_length, false);
      Eigen::Vector3d centre = Eigen::Vector3d::Zero();
      for (int i : h.faces[k].vertices) centre += h.vertices.row(i).transpose();
      centre /= double(h.faces[k].vertices.size());
      const Eigen::Vector3d above = centre + 0.3 * h.faces[k].normal;
      ++faces;
      // beyond the face's edges (twice the largest distance from its centre): no square
      double reach = 0;
      for (int i : h.faces[k].vertices) reach = std::max(reach, (Eigen::Vector3d(h.vertices.row(i).transpose()) - centre).norm());
      const Eigen::Vector3d e = detail::any_orthogonal(h.faces[k].normal);
      detail::OverlapTerms<double> outside = terms;
      EXPECT_FALSE(detail::add_hull_face_square_terms(h, f.R, f.t, k, Eigen::Vector3d(f.R * (above + 2 * reach * e) + f.t), outside));
      EXPECT_EQ(outside.n, 2);
      if (!detail::add_hull_face_square_terms(h, f.R, f.t, k, Eigen::Vector3d(f.R * above + f.t), terms)) continue;
      ++built;
      merged += h.faces[k].vertices.size() > 3;
      EXPECT_NEAR(overlap_terms_value(terms, n), double(overlap_ld(c.solid, v, n.cast<LD>())), 1e-12 * size);
      for (int i = 0; i < 20; ++i) {
        // directions near n (the square's corners decide there) and anywhere
        const Eigen::Vector3d m = i < 10 ? Eigen::Vector3d((n + 0.3 * rng.vec(-1, 1)).normalized()) : Eigen::Vector3d(rng.vec(-1, 1).normalized());
        EXPECT_LE(overlap_terms_value(terms, m), double(overlap_ld(c.solid, v, m.cast<LD>())) + 1e-12 * size);
      }
    }
  }
  EXPECT_GT(built, faces * 9 / 10);
  EXPECT_GT(merged, 2);
}

// The whole penetration, both argument orders, in S: the same boolean as the oracle away from
// touching, depth within `close` of the size of the oracle's, never a lower bound above it.
template <class S>
void check_against_oracle(int count, double scale, double offset, std::uint64_t seed, double close) {
  int hits = 0, apart = 0;
  for (const Case& c : cases(IMPACT_TEST_SANITIZED ? 8 : count, seed, scale, offset)) {
    const ConvexHull<double> hd = scale == 1 ? hulls()[static_cast<std::size_t>(c.hull)] : scaled(hulls()[static_cast<std::size_t>(c.hull)], scale);
    const ConvexHull<S> hs = convex_hull(Vertices<S>(hd.vertices.cast<S>()));
    const Cylinder<S> cyl(S(c.solid.radius), S(c.solid.half_length));
    const RigidTransform<S> pa{c.pa.R.cast<S>(), c.pa.t.cast<S>()}, pb{c.pb.R.cast<S>(), c.pb.t.cast<S>()};
    // the oracle on the shapes and poses as S holds them
    const RigidTransform<double> qa{pa.R.template cast<double>(), pa.t.template cast<double>()},
        qb{pb.R.template cast<double>(), pb.t.template cast<double>()};
    const ConvexHull<double> hq = convex_hull(Vertices<double>(hs.vertices.template cast<double>()));
    const Cylinder<double> cd(double(cyl.radius), double(cyl.half_length));
    const detail::PairFrame<double> f(qa, qb);
    const double size = std::max(shape_size(cd), shape_size(hq));
    const auto p = convex_penetration(cyl, pa, hs, pb);
    const auto q = convex_penetration(hs, pb, cyl, pa);
    const Eigen::Vector3d extra = p.intersecting ? Eigen::Vector3d(qa.R.transpose() * p.normal.template cast<double>()) : Eigen::Vector3d::UnitZ();
    const double oracle = double(depth_oracle(cd, hq, f.R, f.t, extra).depth);
    if (std::abs(oracle) < std::max(1e-5, 10 * close) * size) continue;  // touching: either answer
    EXPECT_EQ(p.intersecting, oracle > 0);
    EXPECT_EQ(q.intersecting, oracle > 0);
    if (oracle < 0) ++apart;
    if (oracle < 0 || !p.intersecting || !q.intersecting) continue;
    ++hits;
    for (const auto& r : {p, q}) {
      EXPECT_LE(double(r.depth - r.depth_gap), oracle + close * size) << "lower bound above the depth";
      EXPECT_NEAR(double(r.depth), oracle, close * size);
      EXPECT_FALSE(r.limit_reached);
    }
  }
  EXPECT_GT(hits, IMPACT_TEST_SANITIZED ? 1 : count / 5);
  EXPECT_GT(apart, IMPACT_TEST_SANITIZED ? -1 : count / 20);
}

TEST(CylinderHullPair, PenetrationAgainstTheOracle) {
  check_against_oracle<double>(60, 1, 0, 644, 1e-9);
  check_against_oracle<float>(24, 1, 0, 645, 2e-4);
}

TEST(CylinderHullPair, ScaledAndTranslated) {
  check_against_oracle<double>(15, 1e-3, 0, 646, 1e-9);
  check_against_oracle<double>(15, 1e3, 0, 647, 1e-9);
  check_against_oracle<double>(15, 1, 1e3, 648, 1e-9);
}

}  // namespace cylinder_hull_pair_test
