// SPDX-License-Identifier: MIT
/// \file
/// MeshBvh<BV>: a triangle mesh together with its hierarchy, the object every mesh query takes.
/// Construction validates the arrays (throws InvalidInput on empty meshes, NaN/Inf coordinates,
/// out-of-range indices), copies them, builds the tree top-down with each node's BV fitted around
/// its triangles' vertices, and keeps the triangles in leaf order so leaf tests read memory in
/// sequence. In the tree, primitive ids are leaf positions; triangle_id() maps them back to rows of
/// F. For deforming meshes, set_vertices() moves the vertices and refits; the topology is kept.
///
/// Thread safety: every const member and every query taking a `const MeshBvh&` (collides,
/// collide, self_collide, ray casts, closest points, distance grids built on it) only reads, so
/// any number of threads may query one tree at once. set_vertices() (and assignment) edits: it
/// must not overlap any other call on the same tree.
#pragma once

#include "impact/bvh/build_bottom_up.hpp"
#include "impact/bvh/build_top_down.hpp"
#include "impact/bvh/refit.hpp"
#include "impact/geometry/triangle_mesh.hpp"

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
  MeshBvh(const Vertices<S>& V, const Faces& F, const MeshBvhConfig& cfg = {}) : mesh_(V, F), cfg_(cfg) {
    validate_mesh(mesh_.V, mesh_.F);
    build();
  }
  explicit MeshBvh(const TriangleMesh<S>& m, const MeshBvhConfig& cfg = {}) : MeshBvh(m.V, m.F, cfg) {}

  const Bvh<BV>& tree() const { return tree_; }
  const TriangleMesh<S>& mesh() const { return mesh_; }
  const MeshBvhConfig& config() const { return cfg_; }
  std::int32_t num_triangles() const { return static_cast<std::int32_t>(tris_.size()); }
  /// An upper bound of |x|_inf over the mesh's vertices and the tree's node centres: the scale at
  /// which the mesh queries bound the rounding of moving this mesh by a pose (mesh_collide.hpp).
  S coordinate_bound() const { return coordinate_bound_; }
  /// Heap bytes held by this object beyond sizeof(*this): the copied mesh (V, F), the tree's nodes
  /// and primitive permutation, the leaf-ordered triangles and their ids (capacities, not sizes).
  std::size_t memory_bytes() const { return mesh_bytes() + tree_bytes(); }
  /// The part of memory_bytes() held by the copied mesh arrays V and F.
  std::size_t mesh_bytes() const {
    return static_cast<std::size_t>(mesh_.V.size()) * sizeof(S) + static_cast<std::size_t>(mesh_.F.size()) * sizeof(int);
  }
  /// The part of memory_bytes() beyond the mesh: nodes, permutation, leaf-ordered triangles, ids.
  std::size_t tree_bytes() const {
    return tree_.nodes.capacity() * sizeof(BvhNode<BV>) + tree_.primitives.capacity() * sizeof(std::int32_t) +
           tris_.capacity() * sizeof(Triangle<S>) + ids_.capacity() * sizeof(std::int32_t);
  }

  /// Triangle at leaf position k (the primitive ids the traversals hand out).
  const Triangle<S>& triangle(std::int32_t k) const { return tris_[static_cast<std::size_t>(k)]; }
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
    gather_triangles();
    std::vector<Vec3<S>> scratch;
    refit(tree_, fitter(scratch), mode);
    update_coordinate_bound();
  }

 private:
  void gather_triangles() {
    for (std::size_t k = 0; k < ids_.size(); ++k) tris_[k] = mesh_.triangle(ids_[k]);
  }
  /// Fits a BV around the vertices of the triangles at leaf positions ids[0..n), gathering them in
  /// the caller's scratch buffer (a local of build/set_vertices: it is not kept with the tree).
  auto fitter(std::vector<Vec3<S>>& buf) {
    return [this, &buf](const std::int32_t* ids, std::size_t n) {
      buf.resize(3 * n);
      for (std::size_t i = 0; i < n; ++i) {
        const Triangle<S>& t = tris_[static_cast<std::size_t>(ids[i])];
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
    tris_.resize(m);
    for (std::size_t t = 0; t < m; ++t) {
      tris_[t] = mesh_.triangle(static_cast<int>(t));
      centroids[t] = tris_[t].centroid();
    }
    // Build over mesh order, then renumber primitives to leaf positions.
    std::vector<Aabb<S>> boxes;  // the surface-area heuristic and the clustering weigh the triangles' boxes
    if (cfg_.build.split == SplitRule::Sah || cfg_.build.method == BuildMethod::BottomUp) {
      boxes.resize(m);
      for (std::size_t t = 0; t < m; ++t) boxes[t] = Aabb<S>(tris_[t].a.cwiseMin(tris_[t].b).cwiseMin(tris_[t].c), tris_[t].a.cwiseMax(tris_[t].b).cwiseMax(tris_[t].c));
    }
    std::vector<Vec3<S>> scratch;
    tree_ = cfg_.build.method == BuildMethod::BottomUp ? build_bottom_up<BV>(centroids, boxes, fitter(scratch), cfg_.build)
                                                        : build_top_down<BV>(centroids, fitter(scratch), cfg_.build, boxes);
    ids_ = tree_.primitives;
    std::vector<Triangle<S>> ordered(m);
    for (std::size_t k = 0; k < m; ++k) ordered[k] = tris_[static_cast<std::size_t>(ids_[k])];
    tris_ = std::move(ordered);
    for (std::size_t k = 0; k < m; ++k) tree_.primitives[k] = static_cast<std::int32_t>(k);
    update_coordinate_bound();
  }
  void update_coordinate_bound() {
    S bound = mesh_.V.size() > 0 ? mesh_.V.cwiseAbs().maxCoeff() : S(0);
    for (const auto& node : tree_.nodes) bound = std::max(bound, Traits::center(node.bv).cwiseAbs().maxCoeff());
    coordinate_bound_ = bound;
  }

  TriangleMesh<S> mesh_;
  MeshBvhConfig cfg_;
  Bvh<BV> tree_;
  std::vector<Triangle<S>> tris_;  // leaf order
  std::vector<std::int32_t> ids_;  // leaf position -> row of F
  S coordinate_bound_ = 0;
};

}  // namespace impact
