// SPDX-License-Identifier: MIT
/// \file
/// Mesh-level continuous collision detection for deforming triangle meshes whose vertices move
/// linearly over a time step: a BVH over the triangles' swept AABBs (start and end positions,
/// grown by half the minimum separation so that two primitives that come within d have
/// overlapping boxes), refitted between steps instead of rebuilt; a pair traversal (two meshes)
/// or self traversal (one mesh) over it; and, for each pair of overlapping triangles, the
/// vertex-face and edge-edge tests (vertex_face_ccd, edge_edge_ccd) on the distinct primitive
/// pairs they give. Self CCD skips adjacent primitives: a vertex against a face it belongs to and
/// two edges sharing a vertex. Conservative like the primitive tests: no contact is missed.
///
/// Threads: mesh_ccd and mesh_self_ccd gather their candidates (the pair traversal) and run their
/// primitive tests on a `threads` count (the answer does not depend on it); they only read the motions and trees, so concurrent calls on
/// shared trees are safe. SweptMeshBvh::refit and build edit: not concurrently with queries on
/// the same tree.
#pragma once

#include "impact/bvh/build_top_down.hpp"
#include "impact/bvh/refit.hpp"
#include "impact/bvh/traverse_pair.hpp"
#include "impact/ccd/edge_edge.hpp"
#include "impact/ccd/swept_volume.hpp"
#include "impact/ccd/vertex_face.hpp"
#include "impact/core/next_float.hpp"
#include "impact/core/parallel.hpp"
#include "impact/core/sorted_union.hpp"
#include "impact/geometry/triangle_mesh.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <tuple>
#include <vector>

namespace impact {

/// One step of a deforming mesh: positions at t = 0 and t = 1 and the (fixed) triangles.
/// Non-owning; the arrays must outlive the view.
template <class S>
struct MeshMotion {
  const Vertices<S>* start = nullptr;
  const Vertices<S>* end = nullptr;
  const Faces* faces = nullptr;

  Vec3<S> p0(int v) const { return start->row(v).transpose(); }
  Vec3<S> p1(int v) const { return end->row(v).transpose(); }
};

/// Validates a step (same vertex count at both ends, finite coordinates below 1e100 in magnitude,
/// so that the swept boxes grown by a minimum separation stay finite, indices in range) and
/// returns its view. Throws InvalidInput.
template <class S>
MeshMotion<S> make_mesh_motion(const Vertices<S>& start, const Vertices<S>& end, const Faces& faces) {
  validate_mesh(start, faces, "mesh motion (start)");
  validate_mesh(end, faces, "mesh motion (end)");
  if (start.rows() != end.rows()) throw InvalidInput("mesh motion: start and end have different vertex counts");
  for (const Vertices<S>* V : {&start, &end})
    for (Eigen::Index i = 0; i < V->rows(); ++i)
      for (int k = 0; k < 3; ++k)
        if (!(std::abs(static_cast<double>((*V)(i, k))) < detail::kCcdMaxCoordinate))
          throw InvalidInput(std::string("mesh motion (") + (V == &start ? "start" : "end") + "): vertex " + std::to_string(i) +
                             " has coordinate " + detail::ccd_number(static_cast<double>((*V)(i, k))) +
                             ", outside the range |x| < 1e100 of the mesh CCD");
  return {&start, &end, &faces};
}

namespace detail {
/// Which vertices and edges each triangle owns, for the mesh CCD's candidates (MeshPrimitives):
/// each vertex and each edge is owned by the first (triangle, corner) slot that holds it; bit k
/// of a triangle's byte: the vertex of corner k; bit 3 + k: the edge from corner k to corner k + 1.
inline std::vector<std::uint8_t> primitive_owners(const Faces& F, Eigen::Index vertices) {
  const auto nf = static_cast<std::size_t>(F.rows());
  std::vector<std::uint8_t> owns(nf, 0);
  std::vector<char> seen(static_cast<std::size_t>(vertices), 0);
  std::vector<std::array<std::int32_t, 3>> edges;  // (smaller vertex, larger vertex, slot 3 f + k)
  edges.reserve(3 * nf);
  for (std::size_t f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) {
      const auto i = static_cast<Eigen::Index>(f);
      const std::int32_t v = F(i, k), w = F(i, (k + 1) % 3);
      if (!seen[static_cast<std::size_t>(v)]) seen[static_cast<std::size_t>(v)] = 1, owns[f] |= std::uint8_t(1u << k);
      edges.push_back({std::min(v, w), std::max(v, w), static_cast<std::int32_t>(3 * f) + k});
    }
  std::sort(edges.begin(), edges.end());
  for (std::size_t e = 0; e < edges.size(); ++e)
    if (e == 0 || edges[e][0] != edges[e - 1][0] || edges[e][1] != edges[e - 1][1])
      owns[static_cast<std::size_t>(edges[e][2] / 3)] |= std::uint8_t(8u << (edges[e][2] % 3));
  return owns;
}
}  // namespace detail

/// The BVH over a mesh's triangles with swept AABBs for one step, grown by half the minimum
/// separation (rounded up in S). Build once; call refit() for each new step (same triangles).
template <class S>
struct SweptMeshBvh {
  Bvh<Aabb<S>> tree;
  S inflate = S(0);  ///< >= min_separation / 2 exactly
  /// Per triangle, the vertices and edges it owns (detail::primitive_owners; the topology is
  /// fixed, so refit keeps it): mesh_ccd gathers each primitive pair once, from its owners.
  std::vector<std::uint8_t> owners;

  /// Builds the tree top-down over the triangles' swept-box centres, for queries with a minimum
  /// separation up to `min_separation` (finite, >= 0 and <= 1e100; InvalidInput otherwise).
  static SweptMeshBvh build(const MeshMotion<S>& m, double min_separation = 0.0, const BuildConfig& cfg = {}) {
    if (!(min_separation >= 0.0 && min_separation <= detail::kCcdMaxCoordinate))
      throw InvalidInput("SweptMeshBvh::build: min_separation must be finite, >= 0 and <= 1e100, is " +
                         detail::ccd_number(min_separation));
    if (m.start == nullptr || m.end == nullptr || m.faces == nullptr)
      throw InvalidInput("SweptMeshBvh::build: empty mesh motion (use make_mesh_motion)");
    SweptMeshBvh b;
    b.inflate = half_separation(min_separation);
    const auto nf = static_cast<std::size_t>(m.faces->rows());
    std::vector<Vec3<S>> centroids(nf);
    for (std::size_t f = 0; f < nf; ++f) centroids[f] = triangle_box(m, static_cast<int>(f), b.inflate).center();
    b.tree = build_top_down<Aabb<S>>(centroids, fitter(m, b.inflate), cfg);
    b.owners = detail::primitive_owners(*m.faces, m.start->rows());
    return b;
  }
  /// Updates the boxes for a new step of the same mesh (same faces); the topology is kept.
  void refit(const MeshMotion<S>& m) { impact::refit(tree, fitter(m, inflate), RefitMode::Merge); }

  /// min_separation / 2 rounded up in S (>= it exactly): the growth of every swept box.
  static S half_separation(double min_separation) {
    S h = static_cast<S>(min_separation / 2);
    if (static_cast<double>(h) * 2 < min_separation) h = next_up(h);
    return h;
  }
  /// Swept box of triangle f over the step.
  static Aabb<S> triangle_box(const MeshMotion<S>& m, int f, S inflate_by) {
    const Vec3<S> a[3] = {m.p0((*m.faces)(f, 0)), m.p0((*m.faces)(f, 1)), m.p0((*m.faces)(f, 2))};
    const Vec3<S> b[3] = {m.p1((*m.faces)(f, 0)), m.p1((*m.faces)(f, 1)), m.p1((*m.faces)(f, 2))};
    return swept_aabb(a, b, inflate_by);
  }

 private:
  static auto fitter(const MeshMotion<S>& m, S inflate_by) {
    return [m, inflate_by](const std::int32_t* ids, std::size_t n) {
      Aabb<S> box;
      for (std::size_t k = 0; k < n; ++k) box.extend(triangle_box(m, ids[k], inflate_by));
      return box;
    };
  }
};

enum class MeshCcdKind { VertexFace, EdgeEdge };

/// One colliding primitive pair. Vertex-face: `vertex` of mesh `vertex_mesh` (0 = first, 1 =
/// second; 0 for self CCD) against `face` of the other mesh. Edge-edge: edge (a0, a1) of the
/// first mesh against edge (b0, b1) of the second (vertex ids, a0 < a1, b0 < b1).
template <class S>
struct MeshCcdContact {
  MeshCcdKind kind = MeshCcdKind::VertexFace;
  int vertex_mesh = 0;
  std::int32_t vertex = -1, face = -1;
  std::int32_t a0 = -1, a1 = -1, b0 = -1, b1 = -1;
  CcdResult<S> result;
};

template <class S>
struct MeshCcdResult {
  std::vector<MeshCcdContact<S>> contacts;  ///< every primitive pair that hit (all of them, not just the first)
  bool hit = false;
  S toi = S(1);                     ///< the earliest toi over the contacts (t_max without a hit)
  std::size_t triangle_pairs = 0;   ///< overlapping swept-box pairs visited
  std::size_t primitive_tests = 0;  ///< vertex-face and edge-edge tests run
};

namespace detail {

// Checks a mesh CCD query before any work (InvalidInput): the options, and each tree built for
// this mesh (one box per triangle) with an inflation that covers the query's minimum separation.
template <class S>
void validate_mesh_ccd(const char* where, const CcdOptions& opt, const MeshMotion<S>& m, const SweptMeshBvh<S>& t,
                       const char* which) {
  ccd_validate_options(opt, where);
  if (m.start == nullptr || m.end == nullptr || m.faces == nullptr)
    throw InvalidInput(std::string(where) + ": empty mesh motion (use make_mesh_motion)");
  if (t.tree.num_primitives() != static_cast<std::size_t>(m.faces->rows()))
    throw InvalidInput(std::string(where) + ": the tree " + which + " has " + std::to_string(t.tree.num_primitives()) +
                       " triangles, the mesh " + std::to_string(m.faces->rows()) + " (built for another mesh?)");
  if (t.owners.size() != static_cast<std::size_t>(m.faces->rows()))
    throw InvalidInput(std::string(where) + ": the tree " + which + " was not built by SweptMeshBvh::build for this mesh");
  if (!(static_cast<double>(t.inflate) * 2 >= opt.min_separation))
    throw InvalidInput(std::string(where) + ": the tree " + which + " was built for a minimum separation up to " +
                       ccd_number(static_cast<double>(t.inflate) * 2) + ", the query asks for " + ccd_number(opt.min_separation) +
                       " (its boxes could miss contacts: build it with SweptMeshBvh::build(motion, d))");
}

// What the candidate gathering needs of one mesh for one query: its triangles, its vertices'
// swept boxes over the step, grown by `inflate` as the tree's triangle boxes are (swept_aabb: the
// hull of a triangle's three vertex boxes is its box in the tree, bit for bit, since the growth and
// its outward rounding are monotone), and which vertices and edges each triangle owns. Each vertex
// and each edge is owned by the first (triangle, corner) slot that holds it (bit k: the vertex of
// corner k; bit 3 + k: the edge from corner k to corner k + 1), so that a primitive pair is
// gathered from the pair of its owners' triangles only: once, with no duplicates to sort away.
// An owner's box holds its primitive's box, so when the primitives' boxes overlap the tree walk
// visits the owners' pair (self CCD: two primitives of one triangle are adjacent and skipped).
template <class S>
struct MeshPrimitives {
  const Faces* faces = nullptr;
  const std::vector<std::uint8_t>& owns;  // SweptMeshBvh::owners
  std::vector<Aabb<S>> boxes;

  MeshPrimitives(const MeshMotion<S>& m, const std::vector<std::uint8_t>& owners, S inflate) : faces(m.faces), owns(owners) {
    boxes.resize(static_cast<std::size_t>(m.start->rows()));
    for (std::size_t v = 0; v < boxes.size(); ++v)
      boxes[v] = swept_aabb(m.p0(static_cast<int>(v)), m.p1(static_cast<int>(v)), inflate);
  }
  std::int32_t vertex(std::int32_t f, int k) const { return (*faces)(f, k); }
  const Aabb<S>& box(std::int32_t v) const { return boxes[static_cast<std::size_t>(v)]; }
  Aabb<S> triangle_box(std::int32_t f) const {
    Aabb<S> b = box(vertex(f, 0));
    b.extend(box(vertex(f, 1)));
    b.extend(box(vertex(f, 2)));
    return b;
  }
  Aabb<S> edge_box(std::int32_t f, int k) const {
    Aabb<S> b = box(vertex(f, k));
    b.extend(box(vertex(f, (k + 1) % 3)));
    return b;
  }
  bool has(std::int32_t f, std::int32_t v) const { return vertex(f, 0) == v || vertex(f, 1) == v || vertex(f, 2) == v; }
};

// Distinct primitive pairs gathered from overlapping triangle pairs: (vertex_mesh, vertex, face)
// and (a0, a1, b0, b1), then sorted before testing (an order that does not depend on the threads).
// A triangle pair gives the pairs of the primitives its triangles own (MeshPrimitives), and only
// those whose swept boxes overlap: the primitives stay within those boxes over the step, so a
// pair whose boxes are disjoint never comes within the separation (the primitive test would
// exclude it at its first box; this skips the call and the candidate's sorting).
template <class S>
struct MeshCcdCandidates {
  std::vector<std::array<std::int32_t, 3>> vf;
  std::vector<std::array<std::int32_t, 4>> ee;

  void add_triangle_pair(const MeshPrimitives<S>& a, std::int32_t ta, const MeshPrimitives<S>& b, std::int32_t tb, bool self) {
    const unsigned oa = a.owns[static_cast<std::size_t>(ta)], ob = b.owns[static_cast<std::size_t>(tb)];
    if (!(oa | ob)) return;
    const Aabb<S> tri_a = a.triangle_box(ta), tri_b = b.triangle_box(tb);
    for (int k = 0; k < 3; ++k) {
      if (oa & (1u << k)) {
        const std::int32_t v = a.vertex(ta, k);
        if (!(self && b.has(tb, v)) && overlap(a.box(v), tri_b)) vf.push_back({0, v, tb});
      }
      if (ob & (1u << k)) {
        const std::int32_t v = b.vertex(tb, k);
        if (!(self && a.has(ta, v)) && overlap(b.box(v), tri_a)) vf.push_back({self ? 0 : 1, v, ta});
      }
    }
    if (!(oa & 0x38u) || !(ob & 0x38u)) return;
    for (int i = 0; i < 3; ++i) {
      if (!(oa & (8u << i))) continue;
      const Aabb<S> edge_a = a.edge_box(ta, i);
      if (!overlap(edge_a, tri_b)) continue;
      for (int j = 0; j < 3; ++j) {
        if (!(ob & (8u << j)) || !overlap(edge_a, b.edge_box(tb, j))) continue;
        std::int32_t a0 = a.vertex(ta, i), a1 = a.vertex(ta, (i + 1) % 3), b0 = b.vertex(tb, j), b1 = b.vertex(tb, (j + 1) % 3);
        if (a0 > a1) std::swap(a0, a1);
        if (b0 > b1) std::swap(b0, b1);
        if (self) {
          if (a0 == b0 || a0 == b1 || a1 == b0 || a1 == b1) continue;  // adjacent (or the same edge)
          if (std::make_pair(a0, a1) > std::make_pair(b0, b1)) {
            std::swap(a0, b0);
            std::swap(a1, b1);
          }
        }
        ee.push_back({a0, a1, b0, b1});
      }
    }
  }
  void finish() {
    std::sort(vf.begin(), vf.end());
    vf.erase(std::unique(vf.begin(), vf.end()), vf.end());
    std::sort(ee.begin(), ee.end());
    ee.erase(std::unique(ee.begin(), ee.end()), ee.end());
  }
};

/// The candidates of every overlapping triangle pair of ta and tb (self: of ta against itself,
/// adjacent primitives skipped) on `threads` threads; returns the number of triangle pairs. On one
/// thread, one traversal. On more, the node pairs near the roots are split breadth first, as the
/// traversal splits them, until there are 16 per thread (or nothing is left to split); each is
/// then walked into its own candidate lists (no pair twice: MeshPrimitives), and the lists are
/// joined sorted on the threads too (sorted_union; on one thread, finish()): the candidates,
/// hence every answer, are the same for every thread count.
template <bool Self, class S>
std::size_t gather_candidates(const Bvh<Aabb<S>>& ta, const Bvh<Aabb<S>>& tb, const MeshPrimitives<S>& pa,
                              const MeshPrimitives<S>& pb, MeshCcdCandidates<S>& c, int threads) {
  const auto overlap_boxes = [](const Aabb<S>& x, const Aabb<S>& y) { return overlap(x, y); };
  const auto walk = [&](std::int32_t i, std::int32_t j, MeshCcdCandidates<S>& out) {
    std::size_t pairs = 0;
    const auto visit = [&](std::int32_t p, std::int32_t q) {
      ++pairs;
      out.add_triangle_pair(pa, p, pb, q, Self);
      return true;
    };
    if constexpr (Self)
      traverse_self(ta, overlap_boxes, visit, i, j);
    else
      traverse_pair(ta, tb, overlap_boxes, visit, i, j);
    return pairs;
  };
  const int t = resolve_threads(threads);
  if (t <= 1 || ta.empty() || tb.empty()) {
    const std::size_t pairs = walk(0, 0, c);
    c.finish();
    return pairs;
  }
  std::vector<std::pair<std::int32_t, std::int32_t>> tasks{{0, 0}}, next;
  const std::size_t want = 16 * static_cast<std::size_t>(t);
  for (bool split = true; split && tasks.size() < want;) {
    split = false;
    next.clear();
    for (const auto& [i, j] : tasks) {
      const auto& ni = ta.nodes[static_cast<std::size_t>(i)];
      const auto& nj = tb.nodes[static_cast<std::size_t>(j)];
      if (Self && i == j) {
        if (ni.is_leaf()) {
          next.push_back({i, j});
        } else {
          next.push_back({ni.left(), ni.left()});
          next.push_back({ni.right(), ni.right()});
          next.push_back({ni.left(), ni.right()});
          split = true;
        }
        continue;
      }
      if (!overlap(ni.bv, nj.bv)) continue;
      if (ni.is_leaf() && nj.is_leaf()) {
        next.push_back({i, j});
      } else if (nj.is_leaf() || (!ni.is_leaf() && BvTraits<Aabb<S>>::size(ni.bv) >= BvTraits<Aabb<S>>::size(nj.bv))) {
        next.push_back({ni.left(), j});
        next.push_back({ni.right(), j});
        split = true;
      } else {
        next.push_back({i, nj.left()});
        next.push_back({i, nj.right()});
        split = true;
      }
    }
    tasks.swap(next);
  }
  std::vector<MeshCcdCandidates<S>> parts(tasks.size());
  std::vector<std::size_t> pairs(tasks.size(), 0);
  parallel_for(tasks.size(), t, [&](std::size_t k) { pairs[k] = walk(tasks[k].first, tasks[k].second, parts[k]); });
  std::size_t total = 0;
  std::vector<std::vector<std::array<std::int32_t, 3>>> vf(parts.size());
  std::vector<std::vector<std::array<std::int32_t, 4>>> ee(parts.size());
  for (std::size_t k = 0; k < parts.size(); ++k) {
    total += pairs[k];
    vf[k].swap(parts[k].vf);
    ee[k].swap(parts[k].ee);
  }
  c.vf = sorted_union(vf, t);
  c.ee = sorted_union(ee, t);
  return total;
}

/// The primitive tests of the deduplicated candidates: vertex-face pairs in order, then edge-edge
/// pairs, on `threads` threads (chunks of candidates, each with its own contact list, joined in
/// candidate order): the contacts, their order and the counters do not depend on the thread count.
template <class S>
MeshCcdResult<S> run_mesh_ccd(MeshCcdCandidates<S>& c, const MeshMotion<S>& a, const MeshMotion<S>& b, const CcdOptions& opt,
                              int threads) {
  const std::size_t nvf = c.vf.size(), n = nvf + c.ee.size();
  // test k (vertex-face k for k < nvf, else edge-edge k - nvf); appends a hit to out
  const auto test = [&](std::size_t k, std::vector<MeshCcdContact<S>>& out) {
    if (k < nvf) {
      const auto& [mesh, v, f] = c.vf[k];
      const MeshMotion<S>& mv = mesh == 0 ? a : b;
      const MeshMotion<S>& mf = mesh == 0 ? b : a;
      const Faces& F = *mf.faces;
      const auto res = vertex_face_ccd(mv.p0(v), mf.p0(F(f, 0)), mf.p0(F(f, 1)), mf.p0(F(f, 2)), mv.p1(v), mf.p1(F(f, 0)),
                                       mf.p1(F(f, 1)), mf.p1(F(f, 2)), opt);
      if (!res.hit) return;
      MeshCcdContact<S> h;
      h.kind = MeshCcdKind::VertexFace;
      h.vertex_mesh = mesh;
      h.vertex = v;
      h.face = f;
      h.result = res;
      out.push_back(h);
    } else {
      const auto& [a0, a1, b0, b1] = c.ee[k - nvf];
      const auto res = edge_edge_ccd(a.p0(a0), a.p0(a1), b.p0(b0), b.p0(b1), a.p1(a0), a.p1(a1), b.p1(b0), b.p1(b1), opt);
      if (!res.hit) return;
      MeshCcdContact<S> h;
      h.kind = MeshCcdKind::EdgeEdge;
      h.a0 = a0, h.a1 = a1, h.b0 = b0, h.b1 = b1;
      h.result = res;
      out.push_back(h);
    }
  };
  MeshCcdResult<S> r;
  r.primitive_tests = n;
  constexpr std::size_t grain = 512;
  const int t = resolve_threads(threads);
  if (t <= 1 || n < 2 * grain) {
    for (std::size_t k = 0; k < n; ++k) test(k, r.contacts);
  } else {
    std::vector<std::vector<MeshCcdContact<S>>> parts((n + grain - 1) / grain);
    parallel_for_ranges(n, grain, t, [&](std::size_t begin, std::size_t end) {
      auto& out = parts[begin / grain];
      for (std::size_t k = begin; k < end; ++k) test(k, out);
    });
    for (const auto& p : parts) r.contacts.insert(r.contacts.end(), p.begin(), p.end());
  }
  r.toi = static_cast<S>(opt.t_max);
  for (const auto& h : r.contacts) r.toi = std::min(r.toi, h.result.toi);
  r.hit = !r.contacts.empty();
  return r;
}

}  // namespace detail

/// CCD between two deforming meshes over one step. `ta`, `tb`: their swept trees for this step
/// (built for a minimum separation >= opt.min_separation, then refitted). Returns every vertex-face pair (in
/// both directions) and edge-edge pair that comes within opt.min_separation, with the earliest
/// toi. No false negatives (see CcdResult); hits may include near misses within the tolerance.
///
/// `threads`: threads of the traversal and of the primitive tests (<= 0 the hardware concurrency,
/// 1 serial; fewer than 1,024 candidate pairs are tested serially). The contacts, their order, toi and the counters are the
/// same for every thread count.
/// Throws InvalidInput (before any work) on bad options (see CcdOptions), a tree built for another
/// mesh, or a tree built for a smaller minimum separation than opt.min_separation.
template <class S>
MeshCcdResult<S> mesh_ccd(const MeshMotion<S>& a, const SweptMeshBvh<S>& ta, const MeshMotion<S>& b, const SweptMeshBvh<S>& tb,
                          const CcdOptions& opt = {}, int threads = 0) {
  detail::validate_mesh_ccd("mesh_ccd", opt, a, ta, "of mesh a");
  detail::validate_mesh_ccd("mesh_ccd", opt, b, tb, "of mesh b");
  const S grow = SweptMeshBvh<S>::half_separation(opt.min_separation);
  detail::MeshCcdCandidates<S> c;
  const detail::MeshPrimitives<S> pa(a, ta.owners, grow), pb(b, tb.owners, grow);
  const std::size_t pairs = detail::gather_candidates<false>(ta.tree, tb.tree, pa, pb, c, threads);
  auto r = detail::run_mesh_ccd(c, a, b, opt, threads);
  r.triangle_pairs = pairs;
  return r;
}

/// Self CCD of one deforming mesh over one step, skipping adjacent primitives (a vertex against a
/// face containing it, edges sharing a vertex). Vertex-face contacts have vertex_mesh 0; edge
/// pairs are reported once with (a0, a1) < (b0, b1). Throws InvalidInput like mesh_ccd.
/// `threads` as for mesh_ccd.
template <class S>
MeshCcdResult<S> mesh_self_ccd(const MeshMotion<S>& m, const SweptMeshBvh<S>& t, const CcdOptions& opt = {}, int threads = 0) {
  detail::validate_mesh_ccd("mesh_self_ccd", opt, m, t, "of the mesh");
  const detail::MeshPrimitives<S> prims(m, t.owners, SweptMeshBvh<S>::half_separation(opt.min_separation));
  detail::MeshCcdCandidates<S> c;
  const std::size_t pairs = detail::gather_candidates<true>(t.tree, t.tree, prims, prims, c, threads);
  auto r = detail::run_mesh_ccd(c, m, m, opt, threads);
  r.triangle_pairs = pairs;
  return r;
}

}  // namespace impact
