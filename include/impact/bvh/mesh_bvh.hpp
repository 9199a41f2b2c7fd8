// SPDX-License-Identifier: MIT
/// \file
/// MeshBvh<BV>: a triangle mesh together with its hierarchy, the object every mesh query takes.
/// Construction validates the arrays (throws InvalidInput on empty meshes, NaN/Inf coordinates,
/// out-of-range indices), copies them, builds the tree (top-down by default, with the BV's default
/// split: SAH for oriented boxes, the middle split for spheres and AABBs, see DefaultSplitRule;
/// MeshBvhConfig::build chooses another split, or bottom-up or incremental construction) with each node's BV fitted around
/// its triangles' vertices, and keeps only the leaf order of the triangles (their rows of F): a
/// triangle's vertices are read from the copied mesh. In the tree, primitive ids are leaf positions; triangle_id() maps them back to rows of
/// F. For deforming meshes, set_vertices() moves the vertices and refits; the topology is kept.
/// The nodes are stored in page-sized treelets (lay_out_in_treelets, bvh/node_layout.hpp).
///
/// Coincident copies of a triangle: the top-down build gathers the copies of one triangle (the
/// same three points) in one leaf (TriangleCopyOrder), sorted by vertex order, and the tree marks
/// each triangle equal to the one before it in its leaf, vertex order included
/// (repeats_previous()). The nearest-first queries (first hit of a ray or a swept sphere, closest
/// point) and the any-hit cast skip marked triangles: they give exactly the answer of the one
/// before. So a mesh of 200,000 copies of one triangle is one node and one triangle test per
/// query, not 200,000, in every BV. (The bottom-up and incremental builds do not gather copies.)
///
/// Thread safety: every const member and every query taking a `const MeshBvh&` (collides,
/// collide, self_collide, ray casts, closest points, distance grids built on it) only reads, so
/// any number of threads may query one tree at once. set_vertices() (and assignment) edits: it
/// must not overlap any other call on the same tree.
#pragma once

#include "impact/bvh/build_bottom_up.hpp"
#include "impact/bvh/build_incremental.hpp"
#include "impact/bvh/build_top_down.hpp"
#include "impact/bvh/node_layout.hpp"
#include "impact/bvh/refit.hpp"
#include "impact/detail/revision.hpp"
#include "impact/geometry/obb_slabs.hpp"
#include "impact/geometry/triangle_mesh.hpp"

#include <type_traits>

namespace impact {

struct MeshBvhConfig {
  BuildConfig build;  ///< split rule and leaf size
  FitConfig fit;      ///< how node spheres are fitted (ignored by other BVs)
};

template <class BV> class MeshBvh {
 public:
  using Traits = BvTraits<BV>;
  using S = typename Traits::Scalar;

  /// Validates and copies the mesh, then builds the tree. Throws InvalidInput on bad input.
  MeshBvh(const Vertices<S>& V, const Faces& F, const MeshBvhConfig& cfg = {}) : mesh_(V, F), cfg_(cfg), revision_(detail::next_revision()) {
    validate_mesh(mesh_.V, mesh_.F);
    build();
  }
  explicit MeshBvh(const TriangleMesh<S>& m, const MeshBvhConfig& cfg = {}) : MeshBvh(m.V, m.F, cfg) {}

  const Bvh<BV>& tree() const { return tree_; }
  const TriangleMesh<S>& mesh() const { return mesh_; }
  const MeshBvhConfig& config() const { return cfg_; }
  std::int32_t num_triangles() const { return static_cast<std::int32_t>(ids_.size()); }
  /// A stamp of this tree's contents: unique in the process to each construction and each
  /// set_vertices() call (never 0), carried along by copies and assignment (a copy holds the same
  /// contents). Caches of results computed on the mesh (the particles' free balls) compare it to
  /// notice an edit in place; O(1).
  std::uint64_t revision() const { return revision_; }
  /// An upper bound of |x|_inf over the mesh's vertices and the tree's node centres: the scale at
  /// which the mesh queries bound the rounding of moving this mesh by a pose (mesh_collide.hpp).
  S coordinate_bound() const { return coordinate_bound_; }
  /// Heap bytes held by this object beyond sizeof(*this): the copied mesh (V, F), the tree's nodes
  /// and primitive permutation, the triangles' rows of F in leaf order (capacities, not sizes).
  std::size_t memory_bytes() const { return mesh_bytes() + tree_bytes(); }
  /// Oriented-box trees: the mesh's vertices' slabs along the ten diagonal directions of the root
  /// box's axes (fit_obb_slabs), measured at construction and at every set_vertices(), in the
  /// root's frame. The mesh queries try them on the root pair when its 15 axes fail (a 26-sided
  /// polytope around the mesh instead of its box). Invalid (never used) for the other BVs.
  const ObbSlabs<S>& root_slabs() const { return root_slabs_; }
  /// The part of memory_bytes() held by the copied mesh arrays V and F.
  std::size_t mesh_bytes() const {
    return static_cast<std::size_t>(mesh_.V.size()) * sizeof(S) + static_cast<std::size_t>(mesh_.F.size()) * sizeof(int);
  }
  /// The part of memory_bytes() beyond the mesh: nodes, permutation, triangle ids in leaf order
  /// (and the repeat marks, on meshes with coincident copies only).
  std::size_t tree_bytes() const {
    return tree_.nodes.capacity() * sizeof(BvhNode<BV>) + tree_.primitives.capacity() * sizeof(std::int32_t) +
           ids_.capacity() * sizeof(std::int32_t) + repeats_.capacity() / 8;
  }
  /// True when the triangle at leaf position k has exactly the vertices of the one at k - 1, in
  /// the same order, and both lie in the same leaf: every per-triangle test gives the same
  /// result on both, so a query that has just tested k - 1 may skip k. False on meshes without
  /// coincident copies (nothing is stored for them).
  bool repeats_previous(std::int32_t k) const { return !repeats_.empty() && repeats_[static_cast<std::size_t>(k)]; }

  /// Triangle at leaf position k (the primitive ids the traversals hand out), read from the copied
  /// mesh through the triangle's row of F (no per-triangle copy of the coordinates is kept: D14).
  Triangle<S> triangle(std::int32_t k) const {
    const int* f = mesh_.F.data() + 3 * static_cast<std::size_t>(ids_[static_cast<std::size_t>(k)]);  // row-major
    const S* v = mesh_.V.data();  // row-major: vertex i at v + 3 i
    return Triangle<S>(Vec3<S>(v[3 * f[0]], v[3 * f[0] + 1], v[3 * f[0] + 2]), Vec3<S>(v[3 * f[1]], v[3 * f[1] + 1], v[3 * f[1] + 2]),
                       Vec3<S>(v[3 * f[2]], v[3 * f[2] + 1], v[3 * f[2] + 2]));
  }
  /// Row of F of the triangle at leaf position k.
  std::int32_t triangle_id(std::int32_t k) const { return ids_[static_cast<std::size_t>(k)]; }
  /// Vertex indices of the triangle at leaf position k.
  Eigen::Matrix<int, 1, 3> triangle_indices(std::int32_t k) const { return mesh_.F.row(ids_[static_cast<std::size_t>(k)]); }
  /// True when the triangles at leaf positions p and q share a vertex index.
  bool adjacent(std::int32_t p, std::int32_t q) const {
    const auto a = triangle_indices(p), b = triangle_indices(q);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        if (a[i] == b[j]) return true;
    return false;
  }

  /// Moves the vertices (same count, finite) and refits the tree; the topology stays.
  /// Throws InvalidInput when V has another size or a non-finite coordinate.
  void set_vertices(const Vertices<S>& V, RefitMode mode = RefitMode::Merge) {
    if (V.rows() != mesh_.V.rows()) throw InvalidInput("MeshBvh::set_vertices: vertex count changed");
    validate_mesh(V, mesh_.F);
    mesh_.V = V;
    refit(tree_, fitter([this](std::int32_t k) { return triangle(k); }), mode);
    update_coordinate_bound();
    update_root_slabs();
    mark_repeats();
    revision_ = detail::next_revision();
  }

 private:
  /// Fits a BV around the vertices of the triangles at leaf positions ids[0..n), gathering them in
  /// a scratch buffer of its own (not kept with the tree; each copy of the fitter has its own, so
  /// the parallel build's copies run concurrently).
  template <class Get> auto fitter(Get get) {
    return [this, buf = std::vector<Vec3<S>>(), get](const std::int32_t* ids, std::size_t n) mutable {
      buf.resize(3 * n);
      for (std::size_t i = 0; i < n; ++i) {
        const Triangle<S> t = get(ids[i]);
        buf[3 * i] = t.a;
        buf[3 * i + 1] = t.b;
        buf[3 * i + 2] = t.c;
      }
      return Traits::fit(buf.data(), buf.size(), cfg_.fit);
    };
  }
  void build() {
    const auto m = static_cast<std::size_t>(mesh_.F.rows());
    std::vector<Vec3<S>> centroids(m);
    std::vector<Triangle<S>> tris(m);  // mesh order, for the build only
    for (std::size_t t = 0; t < m; ++t) {
      tris[t] = mesh_.triangle(static_cast<int>(t));
      centroids[t] = tris[t].centroid();
    }
    // Build over mesh order, then renumber primitives to leaf positions.
    std::vector<Aabb<S>> boxes;  // the surface-area heuristic and the clustering weigh the triangles' boxes
    if (resolve_split_rule<BV>(cfg_.build.split) == SplitRule::Sah || cfg_.build.method != BuildMethod::TopDown) {
      boxes.resize(m);
      for (std::size_t t = 0; t < m; ++t) boxes[t] = Aabb<S>(tris[t].a.cwiseMin(tris[t].b).cwiseMin(tris[t].c), tris[t].a.cwiseMax(tris[t].b).cwiseMax(tris[t].c));
    }
    auto get = [&tris](std::int32_t t) { return tris[static_cast<std::size_t>(t)]; };
    switch (cfg_.build.method) {
      case BuildMethod::BottomUp: tree_ = build_bottom_up<BV>(centroids, boxes, fitter(get), cfg_.build); break;
      case BuildMethod::Incremental: tree_ = build_incremental<BV>(centroids, boxes, fitter(get), cfg_.build); break;
      default: tree_ = build_top_down<BV>(centroids, fitter(get), cfg_.build, boxes, TriangleCopyOrder<S>{&tris});
    }
    ids_ = tree_.primitives;
    for (std::size_t k = 0; k < m; ++k) tree_.primitives[k] = static_cast<std::int32_t>(k);
    lay_out_in_treelets(tree_);  // a page-sized block per few levels (node_layout.hpp); the same tree
    tree_.nodes.shrink_to_fit();
    update_coordinate_bound();
    update_root_slabs();
    mark_repeats();
  }
  /// root_slabs() of the current vertices and root box (every vertex row: a superset of the
  /// triangles' corners, so the slabs hold every triangle).
  void update_root_slabs() {
    root_slabs_ = ObbSlabs<S>();
    if constexpr (std::is_same_v<BV, Obb<S>>) {
      if (!tree_.nodes.empty()) root_slabs_ = fit_obb_slabs(tree_.nodes.front().bv, mesh_.V.data(), static_cast<std::size_t>(mesh_.V.rows()));
    }
  }
  /// repeats_previous() of every leaf position: stored only when some triangle repeats the one
  /// before it in its leaf (after set_vertices, copies that moved apart are no longer marked).
  void mark_repeats() {
    repeats_.clear();
    const auto same = [this](std::int32_t p, std::int32_t q) {
      const int *a = mesh_.F.data() + 3 * static_cast<std::size_t>(ids_[static_cast<std::size_t>(p)]),
                *b = mesh_.F.data() + 3 * static_cast<std::size_t>(ids_[static_cast<std::size_t>(q)]);
      for (int j = 0; j < 3; ++j)
        if (a[j] != b[j] && mesh_.V.row(a[j]) != mesh_.V.row(b[j])) return false;
      return true;
    };
    for (const auto& node : tree_.nodes) {
      if (node.count < 2) continue;
      for (std::int32_t k = node.first + 1; k < node.first + node.count; ++k) {
        if (!same(k - 1, k)) continue;
        if (repeats_.empty()) repeats_.assign(ids_.size(), false);
        repeats_[static_cast<std::size_t>(k)] = true;
      }
    }
  }
  void update_coordinate_bound() {
    S bound = mesh_.V.size() > 0 ? mesh_.V.cwiseAbs().maxCoeff() : S(0);
    for (const auto& node : tree_.nodes) bound = std::max(bound, Traits::center(node.bv).cwiseAbs().maxCoeff());
    coordinate_bound_ = bound;
  }

  TriangleMesh<S> mesh_;
  MeshBvhConfig cfg_;
  Bvh<BV> tree_;
  std::vector<std::int32_t> ids_;  // leaf position -> row of F
  std::vector<bool> repeats_;      // repeats_previous() by leaf position; empty when none repeats
  S coordinate_bound_ = 0;
  ObbSlabs<S> root_slabs_;  // root_slabs(): valid for oriented-box trees only
  std::uint64_t revision_ = 0;  // revision()
};

}  // namespace impact
