// SPDX-License-Identifier: MIT
/// \file
/// WideBvh: a read-only 4-wide bounding-volume hierarchy over a triangle mesh, made for first-hit
/// ray and segment casts (query/ray_wide_bvh.hpp). It is built by collapsing a binary tree (by
/// default the surface-area-heuristic tree of the mesh): each wide node takes the two children of
/// a binary node and keeps opening its largest-area inner child until it holds four, and every
/// subtree of at most `leaf_size` triangles becomes one leaf. A node is two cache lines: its four
/// children's float boxes (rounded outward) stored plane by plane, so one pass of SIMD arithmetic
/// tests all four (AVX, SSE2 or a scalar loop giving the same answers), and their references. The
/// triangles are copied in leaf order (a leaf reads one contiguous run of coordinates, no index
/// indirection), with their rows of F, as floats when every coordinate is one (exact, half the
/// bytes: meshes read from single-precision files), else in S.
///
/// Contract: every float box contains the triangles below it (lower corner rounded down, upper
/// corner rounded up, from the exact boxes of the source tree), every triangle is in exactly one
/// leaf, and the copied triangles are the mesh's own coordinates, so a cast that is conservative
/// in its node tests decides every crossing by the narrow-phase rule on the mesh's triangles.
///
/// Thread safety: immutable after construction; any number of threads may cast through one
/// WideBvh at once.
#pragma once

#include "impact/bvh/compact_bvh.hpp"
#include "impact/bvh/mesh_bvh.hpp"
#include "impact/core/validate.hpp"
#include "impact/geometry/triangle.hpp"

#include <algorithm>
#include <array>
#include <cfloat>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

namespace impact {

/// Build settings of a WideBvh.
struct WideBvhConfig {
  int leaf_size = 4;  ///< maximum triangles per leaf (>= 1; larger only when the source tree's leaves are)
  int sah_bins = 16;  ///< bins per axis of the binary SAH build (WideBvh(mesh) only), in [2, 256]
};

/// A node of a WideBvh: four children, their float boxes plane by plane.
struct alignas(64) WideBvhNode {
  /// bounds[2 * axis][child] is the lower, bounds[2 * axis + 1][child] the upper plane. Empty
  /// slots hold an inverted box (lower FLT_MAX, upper -FLT_MAX) that no ray enters.
  float bounds[6][4];
  std::int32_t first[4];  ///< inner child: node index; leaf: offset into the leaf-order triangles
  std::int32_t count[4];  ///< 0: inner child; > 0: leaf of that many triangles; -1: empty slot

  WideBvhNode() {
    for (int c = 0; c < 4; ++c) {
      for (int k = 0; k < 3; ++k) bounds[2 * k][c] = FLT_MAX, bounds[2 * k + 1][c] = -FLT_MAX;
      first[c] = 0;
      count[c] = -1;
    }
  }
};
static_assert(sizeof(WideBvhNode) == 128, "WideBvhNode: two cache lines");

template <class S> class WideBvh {
 public:
  static_assert(is_supported_scalar_v<S>, "WideBvh: float or double");

  WideBvh() = default;

  /// Validates the mesh (InvalidInput on bad input, see validate_mesh), builds its binary SAH tree
  /// (leaves of one triangle) and collapses it. Throws InvalidInput for leaf_size < 1 or sah_bins
  /// outside [2, 256]. O(n log n).
  explicit WideBvh(const TriangleMesh<S>& mesh, const WideBvhConfig& cfg = {}) {
    validate_in_range(cfg.sah_bins, 2, 256, "WideBvh", "config.sah_bins");
    validate_in_range(cfg.leaf_size, 1, std::numeric_limits<int>::max(), "WideBvh", "config.leaf_size");
    MeshBvhConfig binary;
    binary.build.split = SplitRule::Sah;
    binary.build.sah_bins = cfg.sah_bins;
    binary.build.leaf_size = 1;
    collapse(MeshBvh<Aabb<S>>(mesh, binary), cfg.leaf_size);
  }

  /// Collapses the tree of an existing MeshBvh (any build; its quality carries over). Throws
  /// InvalidInput for leaf_size < 1. O(nodes).
  explicit WideBvh(const MeshBvh<Aabb<S>>& mesh, const WideBvhConfig& cfg = {}) {
    validate_in_range(cfg.leaf_size, 1, std::numeric_limits<int>::max(), "WideBvh", "config.leaf_size");
    collapse(mesh, cfg.leaf_size);
  }

  bool empty() const { return ids_.empty(); }
  /// Nodes; nodes()[0] is the root (absent for an empty mesh).
  const std::vector<WideBvhNode>& nodes() const { return nodes_; }
  /// Triangle at leaf-order position k (the mesh's coordinates, exactly).
  Triangle<S> triangle(std::int32_t k) const {
    if (!full_.empty()) {
      const S* p = full_.data() + 9 * static_cast<std::size_t>(k);
      return Triangle<S>(Vec3<S>(p[0], p[1], p[2]), Vec3<S>(p[3], p[4], p[5]), Vec3<S>(p[6], p[7], p[8]));
    }
    const float* p = packed_.data() + 9 * static_cast<std::size_t>(k);
    return Triangle<S>(Vec3<S>(S(p[0]), S(p[1]), S(p[2])), Vec3<S>(S(p[3]), S(p[4]), S(p[5])), Vec3<S>(S(p[6]), S(p[7]), S(p[8])));
  }
  /// True when the triangles are kept as floats: every coordinate of the mesh is a float (always
  /// for S = float; for double, e.g. meshes read from files in single precision), so the copy is
  /// exact at half the bytes.
  bool packed() const { return full_.empty() && !packed_.empty(); }
  /// Row of F of the triangle at leaf-order position k.
  std::int32_t triangle_id(std::int32_t k) const { return ids_[static_cast<std::size_t>(k)]; }
  /// True when the triangle at position k repeats the one at k - 1 in the same leaf, vertex order
  /// included (MeshBvh::repeats_previous of the source tree, whose leaves a wide leaf never
  /// splits): a cast that has just tested k - 1 may skip k. False on meshes without copies.
  bool repeats_previous(std::int32_t k) const { return !repeats_.empty() && repeats_[static_cast<std::size_t>(k)]; }
  /// True when some triangle repeats_previous().
  bool has_repeats() const { return !repeats_.empty(); }
  /// The leaf-order float coordinates when packed() (9 a triangle: a, b, c), else null. Readable
  /// kPackedPadding floats past the last triangle (zeros), so a cast may load four triangles'
  /// rows, and one float more, from any position.
  const float* packed_data() const { return packed() ? packed_.data() : nullptr; }
  static constexpr int kPackedPadding = 28;
  std::int32_t num_triangles() const { return static_cast<std::int32_t>(ids_.size()); }
  /// An upper bound of |x|_inf over the vertices (the scale of the casts' rounding).
  S coordinate_bound() const { return coordinate_bound_; }
  /// Heap bytes: nodes, leaf-order triangles and their rows of F.
  std::size_t memory_bytes() const {
    return nodes_.capacity() * sizeof(WideBvhNode) + full_.capacity() * sizeof(S) + packed_.capacity() * sizeof(float) +
           ids_.capacity() * sizeof(std::int32_t) + repeats_.capacity() / 8;
  }

 private:
  void collapse(const MeshBvh<Aabb<S>>& mesh, int leaf_size) {
    const Bvh<Aabb<S>>& tree = mesh.tree();
    const std::int32_t n = mesh.num_triangles();
    ids_.resize(static_cast<std::size_t>(n));
    std::vector<S> full(9 * static_cast<std::size_t>(n));
    bool floats = true;
    coordinate_bound_ = S(0);
    for (std::int32_t k = 0; k < n; ++k) {
      // leaf order: the source tree's permutation (a subtree's triangles are contiguous in it)
      const std::int32_t leaf = tree.primitives[static_cast<std::size_t>(k)];
      ids_[static_cast<std::size_t>(k)] = mesh.triangle_id(leaf);
      if (k > 0 && mesh.repeats_previous(leaf) && tree.primitives[static_cast<std::size_t>(k - 1)] == leaf - 1) {
        if (repeats_.empty()) repeats_.assign(static_cast<std::size_t>(n), false);
        repeats_[static_cast<std::size_t>(k)] = true;
      }
      const Triangle<S> t = mesh.triangle(leaf);
      S* p = full.data() + 9 * static_cast<std::size_t>(k);
      for (int c = 0; c < 3; ++c) p[c] = t.a[c], p[3 + c] = t.b[c], p[6 + c] = t.c[c];
      for (int c = 0; c < 9; ++c) floats = floats && S(static_cast<float>(p[c])) == p[c];
      coordinate_bound_ = std::max({coordinate_bound_, t.a.cwiseAbs().maxCoeff(), t.b.cwiseAbs().maxCoeff(), t.c.cwiseAbs().maxCoeff()});
    }
    if (floats) {
      if (n > 0) {
        packed_.reserve(full.size() + kPackedPadding);
        packed_.assign(full.begin(), full.end());  // exact: every value is a float
        packed_.resize(packed_.size() + kPackedPadding, 0.0f);
      }
    } else {
      full_ = std::move(full);
    }
    if (tree.empty() || n == 0) return;
    const std::size_t m = tree.nodes.size();
    std::vector<std::int32_t> size(m), begin(m);  // triangles of each subtree and its first position
    for (std::size_t j = m; j-- > 0;) {
      const auto& nd = tree.nodes[j];
      if (nd.is_leaf()) {
        size[j] = nd.count;
        begin[j] = nd.first;
      } else {
        size[j] = size[static_cast<std::size_t>(nd.left())] + size[static_cast<std::size_t>(nd.right())];
        begin[j] = begin[static_cast<std::size_t>(nd.left())];
      }
    }
    auto is_leaf = [&](std::int32_t j) { return tree.nodes[static_cast<std::size_t>(j)].is_leaf() || size[static_cast<std::size_t>(j)] <= leaf_size; };
    auto area = [&](std::int32_t j) {
      const Aabb<S>& b = tree.nodes[static_cast<std::size_t>(j)].bv;
      const Vec3<S> e = b.max - b.min;
      return e.x() * e.y() + e.y() * e.z() + e.z() * e.x();
    };
    nodes_.reserve(m / 3 + 1);
    nodes_.emplace_back();
    std::vector<std::pair<std::int32_t, std::int32_t>> work{{0, 0}};  // (binary node, wide node)
    while (!work.empty()) {
      const auto [src, dst] = work.back();
      work.pop_back();
      std::int32_t kids[4];
      int k = 0;
      if (is_leaf(src)) {
        kids[k++] = src;  // a root that is a leaf
      } else {
        kids[k++] = tree.nodes[static_cast<std::size_t>(src)].left();
        kids[k++] = tree.nodes[static_cast<std::size_t>(src)].right();
        while (k < 4) {  // open the largest inner child
          int open = -1;
          for (int c = 0; c < k; ++c)
            if (!is_leaf(kids[c]) && (open < 0 || area(kids[c]) > area(kids[open]))) open = c;
          if (open < 0) break;
          const auto& nd = tree.nodes[static_cast<std::size_t>(kids[open])];
          kids[open] = nd.left();
          kids[k++] = nd.right();
        }
      }
      WideBvhNode node;
      for (int c = 0; c < k; ++c) {
        const Aabb<S>& b = tree.nodes[static_cast<std::size_t>(kids[c])].bv;
        for (int a = 0; a < 3; ++a) {
          node.bounds[2 * a][c] = detail::round_to_float(b.min[a], -1);
          node.bounds[2 * a + 1][c] = detail::round_to_float(b.max[a], 1);
        }
        if (is_leaf(kids[c])) {
          node.first[c] = begin[static_cast<std::size_t>(kids[c])];
          node.count[c] = size[static_cast<std::size_t>(kids[c])];
        } else {
          node.first[c] = static_cast<std::int32_t>(nodes_.size());
          node.count[c] = 0;
          work.push_back({kids[c], node.first[c]});
          nodes_.emplace_back();
        }
      }
      nodes_[static_cast<std::size_t>(dst)] = node;
    }
    nodes_.shrink_to_fit();
  }

  std::vector<WideBvhNode> nodes_;
  std::vector<float> packed_;  // 9 coordinates a triangle, leaf order, when all are floats
  std::vector<S> full_;        // 9 coordinates a triangle, leaf order, otherwise
  std::vector<std::int32_t> ids_;
  std::vector<bool> repeats_;  // repeats_previous() by leaf-order position; empty when none repeats
  S coordinate_bound_ = S(0);
};

}  // namespace impact
