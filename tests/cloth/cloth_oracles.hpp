// SPDX-License-Identifier: MIT
// Oracles for the cloth collision step, independent of the step's own CCD and broad phase:
//  - sampled_min_distance: every non-adjacent vertex-face and edge-edge pair of the combined
//    arrays (all pairs, no tree, each pair once), at K + 1 evenly spaced times of the linear
//    motion, by closest points in double; a lower bound check between samples comes from the CCD
//    oracle below;
//  - all_pairs_ccd_hits: every such pair through vertex_face_ccd / edge_edge_ccd (no tree, no
//    candidate filtering): checks that the step's broad phase missed nothing;
//  Both skip the pairs of triangles whose boxes over the whole motion are farther apart, along
//  one coordinate, than a reach of a few thicknesses: such pairs stay that far apart at every time
//  of the linear motion (every position lies in its vertex's box), so they can neither come within
//  the thickness nor be a CCD hit. Compared one by one, not through a tree.
//  - Scene: cloth + kinematic obstacles, combined the way the step numbers them.
#pragma once

#include "impact/ccd/edge_edge.hpp"
#include "impact/ccd/vertex_face.hpp"
#include "impact/cloth/collision_step.hpp"
#include "impact/narrow/closest_point.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

namespace cloth_test {

using impact::Faces;
using impact::Vec3;
using impact::Vertices;

template <class S>
struct Combined {
  Vertices<S> X0, X1;
  Faces F;
  std::vector<char> obstacle_tri;
};

template <class S>
Combined<S> combine(const Faces& F, const Vertices<S>& x0, const Vertices<S>& x1, const impact::ClothObstacles<S>& obs) {
  Combined<S> c;
  Eigen::Index nv = x0.rows(), nf = F.rows();
  for (const auto& k : obs.kinematic) nv += k.x0->rows(), nf += k.faces->rows();
  c.X0.resize(nv, 3), c.X1.resize(nv, 3), c.F.resize(nf, 3);
  c.obstacle_tri.assign(static_cast<std::size_t>(nf), 1);
  c.X0.topRows(x0.rows()) = x0, c.X1.topRows(x0.rows()) = x1, c.F.topRows(F.rows()) = F;
  for (Eigen::Index i = 0; i < F.rows(); ++i) c.obstacle_tri[static_cast<std::size_t>(i)] = 0;
  Eigen::Index vo = x0.rows(), fo = F.rows();
  for (const auto& k : obs.kinematic) {
    c.X0.middleRows(vo, k.x0->rows()) = *k.x0;
    c.X1.middleRows(vo, k.x0->rows()) = *k.x1;
    c.F.middleRows(fo, k.faces->rows()) = k.faces->array() + int(vo);
    vo += k.x0->rows(), fo += k.faces->rows();
  }
  return c;
}

/// One vertex-face (v0 against the triangle v1 v2 v3) or edge-edge (v0 v1 against v2 v3) pair.
struct PrimitivePair {
  bool edge_edge = false;
  int v[4] = {0, 0, 0, 0};
};

/// Every non-adjacent primitive pair of distinct triangles, not both obstacle ones, each once: a
/// vertex-face pair comes from every triangle holding the vertex and an edge-edge pair from the
/// two triangles of each edge, so the walk over triangle pairs meets most pairs several times;
/// each is kept at its first meeting, as met. Triangles whose boxes over the motion (both ends)
/// are more than `reach` apart along a coordinate are skipped (infinity: none).
template <class S>
std::vector<PrimitivePair> unique_pairs(const Combined<S>& c, double reach = std::numeric_limits<double>::infinity()) {
  struct Keyed {
    std::array<int, 5> key;
    PrimitivePair pair;
  };
  std::vector<Keyed> all;
  const auto nf = c.F.rows();
  // each triangle's box over both ends of the motion, in double (exact conversions)
  std::vector<std::array<double, 6>> box(static_cast<std::size_t>(nf));
  for (Eigen::Index f = 0; f < nf; ++f) {
    auto& b = box[std::size_t(f)];
    for (int k = 0; k < 3; ++k) b[std::size_t(k)] = std::numeric_limits<double>::infinity(), b[std::size_t(k + 3)] = -b[std::size_t(k)];
    for (int j = 0; j < 3; ++j)
      for (const Vertices<S>* X : {&c.X0, &c.X1})
        for (int k = 0; k < 3; ++k) {
          const double x = double((*X)(c.F(f, j), k));
          b[std::size_t(k)] = std::min(b[std::size_t(k)], x), b[std::size_t(k + 3)] = std::max(b[std::size_t(k + 3)], x);
        }
  }
  auto apart = [&](Eigen::Index a, Eigen::Index b) {
    const auto &ba = box[std::size_t(a)], &bb = box[std::size_t(b)];
    for (std::size_t k = 0; k < 3; ++k)
      if (ba[k] - bb[k + 3] > reach || bb[k] - ba[k + 3] > reach) return true;
    return false;
  };
  for (Eigen::Index a = 0; a < nf; ++a)
    for (Eigen::Index b = a + 1; b < nf; ++b) {
      if (c.obstacle_tri[std::size_t(a)] && c.obstacle_tri[std::size_t(b)]) continue;
      if (apart(a, b)) continue;
      const int ia[3] = {c.F(a, 0), c.F(a, 1), c.F(a, 2)}, ib[3] = {c.F(b, 0), c.F(b, 1), c.F(b, 2)};
      auto in = [](const int* t, int v) { return t[0] == v || t[1] == v || t[2] == v; };
      // a vertex against a triangle: keyed by the vertex and the triangle's index
      for (int k = 0; k < 3; ++k) {
        if (!in(ib, ia[k])) all.push_back({{0, ia[k], int(b), 0, 0}, {false, {ia[k], ib[0], ib[1], ib[2]}}});
        if (!in(ia, ib[k])) all.push_back({{0, ib[k], int(a), 0, 0}, {false, {ib[k], ia[0], ia[1], ia[2]}}});
      }
      // two edges: keyed by their sorted end points, the lower edge first
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
          const int a0 = ia[i], a1 = ia[(i + 1) % 3], b0 = ib[j], b1 = ib[(j + 1) % 3];
          if (a0 == b0 || a0 == b1 || a1 == b0 || a1 == b1) continue;
          std::array<int, 2> e = {std::min(a0, a1), std::max(a0, a1)}, g = {std::min(b0, b1), std::max(b0, b1)};
          if (g < e) std::swap(e, g);
          all.push_back({{1, e[0], e[1], g[0], g[1]}, {true, {a0, a1, b0, b1}}});
        }
    }
  std::stable_sort(all.begin(), all.end(), [](const Keyed& x, const Keyed& y) { return x.key < y.key; });
  std::vector<PrimitivePair> out;
  for (std::size_t i = 0; i < all.size(); ++i)
    if (i == 0 || all[i].key != all[i - 1].key) out.push_back(all[i].pair);
  return out;
}

/// The smallest distance of any pair at the K + 1 sample times; pairs farther apart than `reach`
/// (see unique_pairs) are left out, so the answer is exact when at most `reach` and otherwise
/// above `reach`: `sampled_min_distance(c, K, 2 * h) >= h` holds exactly when every pair stays at
/// least h apart at the samples.
template <class S>
double sampled_min_distance(const Combined<S>& c, int K = 32, double reach = std::numeric_limits<double>::infinity()) {
  double best = std::numeric_limits<double>::infinity();
  const std::vector<PrimitivePair> pairs = unique_pairs(c, reach);
  const Vertices<double> X0 = c.X0.template cast<double>(), X1 = c.X1.template cast<double>();
  for (int s = 0; s <= K; ++s) {
    const double t = double(s) / K;
    const Vertices<double> Xt = (1 - t) * X0 + t * X1;
    auto X = [&](int v) { return Vec3<double>(Xt.row(v).transpose()); };
    for (const PrimitivePair& p : pairs) {
      double d2;
      if (p.edge_edge)
        d2 = impact::closest_points_segment_segment(impact::Segment<double>(X(p.v[0]), X(p.v[1])), impact::Segment<double>(X(p.v[2]), X(p.v[3]))).squared_distance;
      else
        d2 = impact::closest_point_on_triangle(X(p.v[0]), impact::Triangle<double>(X(p.v[1]), X(p.v[2]), X(p.v[3]))).squared_distance;
      best = std::min(best, std::sqrt(d2));
    }
  }
  return best;
}

/// The number of distinct primitive pairs whose CCD reports a hit.
template <class S>
int all_pairs_ccd_hits(const Combined<S>& c, double min_separation) {
  impact::CcdOptions o;
  o.min_separation = min_separation;
  int hits = 0;
  auto P0 = [&](int v) { return Vec3<S>(c.X0.row(v).transpose()); };
  auto P1 = [&](int v) { return Vec3<S>(c.X1.row(v).transpose()); };
  // A CCD hit comes within min_separation (up to the CCD's small relative tolerance): pairs more
  // than four times that apart cannot be one. Touching pairs (min_separation 0) are never apart.
  for (const PrimitivePair& p : unique_pairs(c, 4 * min_separation)) {
    const int* v = p.v;
    const auto r = p.edge_edge ? impact::edge_edge_ccd(P0(v[0]), P0(v[1]), P0(v[2]), P0(v[3]), P1(v[0]), P1(v[1]), P1(v[2]), P1(v[3]), o)
                               : impact::vertex_face_ccd(P0(v[0]), P0(v[1]), P0(v[2]), P0(v[3]), P1(v[0]), P1(v[1]), P1(v[2]), P1(v[3]), o);
    hits += r.hit ? 1 : 0;
  }
  return hits;
}

}  // namespace cloth_test
