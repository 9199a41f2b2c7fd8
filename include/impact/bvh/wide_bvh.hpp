// SPDX-License-Identifier: MIT
/// \file
/// WideBvh: a read-only 4-wide (or 8-wide: WideBvh<S, 8>) bounding-volume hierarchy over a
/// triangle mesh, made for first-hit ray and segment casts (query/ray_wide_bvh.hpp). It is built by
/// collapsing a binary tree (by default the surface-area-heuristic tree of the mesh) into the
/// wide tree of least surface-area cost (WideBvhConfig::node_cost, block_cost): which binary nodes
/// become wide nodes, which are opened into their parent, and which subtrees of at most
/// `leaf_size` triangles become leaves, chosen by dynamic programming over the binary tree (Ylitie,
/// Karras and Laine 2017), not by a fixed rule. A 4-wide node is two cache lines: its four
/// children's float boxes (rounded outward) stored plane by plane, so one pass of SIMD arithmetic
/// tests all four (SSE2 or a scalar loop giving the same answers), and their references; an 8-wide node is four (its test: AVX when the
/// CPU has it, checked at run time, else SSE2 on two halves; no compiler flag needed). The
/// triangles are copied in leaf order into blocks of four, coordinate by coordinate (a block holds
/// a[x][4], a[y][4], ..., c[z][4]: one aligned load per coordinate of four triangles, no
/// transposes; each leaf starts a block, a leaf of more than four triangles takes consecutive
/// blocks, unused lanes are zero), as floats when every coordinate is one (exact, half the bytes:
/// meshes read from single-precision files), else in S.
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
#include <cstdlib>
#include <cstring>
#include <limits>
#include <new>
#include <type_traits>
#include <utility>
#include <vector>

#if defined(__linux__)
#include <sys/mman.h>
#include <unistd.h>
#endif

namespace impact {

namespace detail {
/// The allocator of a WideBvh's nodes and triangle blocks. An array of at least
/// kHugePageMinBytes (2 MiB) starts on a 2 MiB boundary and, on Linux, is marked for transparent
/// huge pages (madvise MADV_HUGEPAGE) before its first write: the kernel then maps each whole 2 MiB
/// of it with one page when it has them, in the default `madvise` mode as in `always`; the tail
/// beyond the last whole 2 MiB keeps 4 KiB pages, so no byte is added. On Linux such an array is
/// a mapping of its own (mmap), never memory the heap has handed out and written before: advice
/// given to pages already mapped small changes nothing until khugepaged merges them, which it
/// does slowly, so a tree built after other large allocations were freed (a bench's or an
/// application's earlier structures) stayed on 4 KiB pages when it came from operator new. A
/// cast reads a few lines of a node or block here and there: with 4 KiB pages most of those
/// reads on a mesh of 100,000 triangles or more also miss the TLB (igea's 19 MB span 4,700
/// pages), with 2 MiB pages about ten pages hold nearly everything. (Embree maps and advises its
/// own arrays the same way.) Smaller arrays come from operator new as usual. No effect on any
/// value.
template <class T> struct WideBvhAllocator {
  using value_type = T;
  static constexpr std::size_t kHugePage = std::size_t(1) << 21;
  static constexpr std::size_t kHugePageMinBytes = kHugePage;
  WideBvhAllocator() = default;
  template <class U> WideBvhAllocator(const WideBvhAllocator<U>&) {}
  /// The alignment of an array of n elements.
  static std::size_t alignment(std::size_t n) {
    return n >= kHugePageMinBytes / sizeof(T) ? std::max(kHugePage, alignof(T)) : alignof(T);
  }
  T* allocate(std::size_t n) {
    if (n > std::numeric_limits<std::size_t>::max() / sizeof(T) - kHugePage) throw std::bad_alloc();
    const std::size_t b = n * sizeof(T);
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    if (b >= kHugePageMinBytes && alignof(T) <= kHugePage) {
      // a mapping 2 MiB longer, cut to the first 2 MiB boundary; the pages before it and after
      // the array's last page are returned at once
      const std::size_t len = mapped_bytes(b);
      void* m = ::mmap(nullptr, len + kHugePage, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
      if (m == MAP_FAILED) throw std::bad_alloc();
      const std::uintptr_t a = reinterpret_cast<std::uintptr_t>(m), start = (a + kHugePage - 1) & ~(kHugePage - 1);
      if (start > a) (void)::munmap(m, start - a);
      if (start + len < a + len + kHugePage) (void)::munmap(reinterpret_cast<void*>(start + len), a + len + kHugePage - start - len);
      (void)::madvise(reinterpret_cast<void*>(start), len, MADV_HUGEPAGE);  // a hint: nothing changes where it is refused
      return reinterpret_cast<T*>(start);
    }
#endif
    return static_cast<T*>(::operator new(b, std::align_val_t(alignment(n))));
  }
  void deallocate(T* p, std::size_t n) noexcept {
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    if (n * sizeof(T) >= kHugePageMinBytes && alignof(T) <= kHugePage) {
      (void)::munmap(p, mapped_bytes(n * sizeof(T)));
      return;
    }
#endif
    ::operator delete(p, std::align_val_t(alignment(n)));
  }
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  /// Bytes of the mapping of an array of b bytes: whole pages.
  static std::size_t mapped_bytes(std::size_t b) {
    static const std::size_t page = static_cast<std::size_t>(::sysconf(_SC_PAGESIZE));
    return (b + page - 1) / page * page;
  }
#endif
  template <class U> bool operator==(const WideBvhAllocator<U>&) const { return true; }
  template <class U> bool operator!=(const WideBvhAllocator<U>&) const { return false; }
};

/// True when the double x is exactly a float (finite or infinite; false for NaN), decided on its
/// bits alone: a round trip double(float(x)) == x gives the same answer in IEEE arithmetic, but
/// a compiler that keeps the float in a wider register (x87 excess precision, which g++ 12 does
/// not strip from casts in C++) or folds the round trip away (-ffast-math) would answer true for
/// every x, and a WideBvh would then store rounded triangles. O(1), integer operations only.
inline bool is_float_exact(double x) {
  std::uint64_t b;
  std::memcpy(&b, &x, sizeof b);
  const int biased = static_cast<int>((b >> 52) & 0x7ff);
  const std::uint64_t fraction = b & ((std::uint64_t(1) << 52) - 1);
  if (biased == 0x7ff) return fraction == 0;  // infinities are floats, NaNs are not
  if (biased == 0) return fraction == 0;      // zeros; a double subnormal is far below float's range
  const int e = biased - 1023;                // x = 1.fraction * 2^e
  if (e > 127 || e < -149) return false;
  // a float keeps 23 fraction bits (e >= -126), fewer below: the multiples of 2^-149
  const int kept = e >= -126 ? 23 : e + 149;
  return (fraction & ((std::uint64_t(1) << (52 - kept)) - 1)) == 0;
}
inline bool is_float_exact(float) { return true; }
}  // namespace detail

/// Build settings of a WideBvh.
struct WideBvhConfig {
  int leaf_size = 4;  ///< maximum triangles per leaf (>= 1; larger only when the source tree's leaves are)
  int sah_bins = 16;  ///< bins per axis of the binary SAH build (WideBvh(mesh) only), in [2, 256]
  /// The collapse's surface-area costs (> 0, finite; only their ratio matters): of testing one
  /// node's children, and of testing one block of up to four triangles of a leaf.
  double node_cost = 1.0;
  double block_cost = 1.0;
};

/// A node of a WideBvh of width W (4 or 8): W children, their float boxes plane by plane.
template <int W> struct alignas(64) WideBvhNodeN {
  static_assert(W == 4 || W == 8, "WideBvhNodeN: 4 or 8 children");
  static constexpr int kWidth = W;
  /// bounds[2 * axis][child] is the lower, bounds[2 * axis + 1][child] the upper plane. Empty
  /// slots hold an inverted box (lower FLT_MAX, upper -FLT_MAX) that no ray enters.
  float bounds[6][W];
  std::int32_t first[W];  ///< inner child: node index; leaf: its first triangle block (WideBvh::block_first)
  std::int32_t count[W];  ///< 0: inner child; > 0: leaf of that many triangles; -1: empty slot

  WideBvhNodeN() {
    for (int c = 0; c < W; ++c) {
      for (int k = 0; k < 3; ++k) bounds[2 * k][c] = FLT_MAX, bounds[2 * k + 1][c] = -FLT_MAX;
      first[c] = 0;
      count[c] = -1;
    }
  }
};
/// The 4-wide node: two cache lines.
using WideBvhNode = WideBvhNodeN<4>;
/// The 8-wide node: four cache lines (the six planes of eight boxes in three, the references in one).
using WideBvhNode8 = WideBvhNodeN<8>;
static_assert(sizeof(WideBvhNode) == 128, "WideBvhNode: two cache lines");
static_assert(sizeof(WideBvhNode8) == 256, "WideBvhNode8: four cache lines");

/// Four triangles of a WideBvh leaf, coordinate by coordinate: v[3 * vertex + axis][lane] (vertex
/// 0, 1, 2 = the triangle's a, b, c), and their rows of F (`id`). Unused lanes hold zeros and id -1.
/// The rows sit behind the coordinates, on the cache line of the last ones (a float block is 160
/// bytes from a multiple of 32), so a hit's row costs no load of its own beyond the block the leaf
/// test has read (a separate array of rows missed the cache on most hits of a large mesh).
template <class T> struct alignas(4 * sizeof(T)) WideTriangleBlock {
  T v[9][4];
  std::int32_t id[4];
};

/// W: children a node, 4 (WideBvhNode, the default) or 8 (WideBvhNode8: half the levels, its node
/// test eight boxes at once with AVX when the CPU has it).
template <class S, int W = 4> class WideBvh {
 public:
  static_assert(is_supported_scalar_v<S>, "WideBvh: float or double");
  static_assert(W == 4 || W == 8, "WideBvh: 4 or 8 children a node");
  using Node = WideBvhNodeN<W>;
  static constexpr int kWidth = W;

  WideBvh() = default;

  /// Validates the mesh (InvalidInput on bad input, see validate_mesh), builds its binary SAH tree
  /// (leaves of one triangle) and collapses it. Throws InvalidInput for leaf_size < 1, sah_bins
  /// outside [2, 256], or costs that are not finite and positive. O(n log n).
  explicit WideBvh(const TriangleMesh<S>& mesh, const WideBvhConfig& cfg = {}) {
    validate_in_range(cfg.sah_bins, 2, 256, "WideBvh", "config.sah_bins");
    validate_in_range(cfg.leaf_size, 1, std::numeric_limits<int>::max(), "WideBvh", "config.leaf_size");
    validate_positive(cfg.node_cost, "WideBvh", "config.node_cost");
    validate_positive(cfg.block_cost, "WideBvh", "config.block_cost");
    MeshBvhConfig binary;
    binary.build.split = SplitRule::Sah;
    binary.build.sah_bins = cfg.sah_bins;
    binary.build.leaf_size = 1;
    collapse(MeshBvh<Aabb<S>>(mesh, binary), cfg);
  }

  /// Collapses the tree of an existing MeshBvh (any build; its quality carries over). Throws
  /// InvalidInput for leaf_size < 1 or costs that are not finite and positive. O(W^2 nodes).
  explicit WideBvh(const MeshBvh<Aabb<S>>& mesh, const WideBvhConfig& cfg = {}) {
    validate_in_range(cfg.leaf_size, 1, std::numeric_limits<int>::max(), "WideBvh", "config.leaf_size");
    validate_positive(cfg.node_cost, "WideBvh", "config.node_cost");
    validate_positive(cfg.block_cost, "WideBvh", "config.block_cost");
    collapse(mesh, cfg);
  }

  bool empty() const { return ids_.empty(); }
  /// Nodes; nodes()[0] is the root (absent for an empty mesh).
  const std::vector<Node, detail::WideBvhAllocator<Node>>& nodes() const { return nodes_; }
  /// Triangle at leaf-order position k (the mesh's coordinates, exactly). O(log leaves).
  Triangle<S> triangle(std::int32_t k) const {
    const auto it = std::upper_bound(block_first_.begin(), block_first_.end(), k);
    const std::int32_t b = static_cast<std::int32_t>(it - block_first_.begin()) - 1;
    return block_triangle(b, k - block_first_[static_cast<std::size_t>(b)]);
  }
  /// Triangle in lane `lane` of block b (the leaf-order position block_first(b) + lane).
  Triangle<S> block_triangle(std::int32_t b, int lane) const {
    auto get = [&](const auto& blocks) {
      const auto& v = blocks[static_cast<std::size_t>(b)].v;
      auto at = [&](int vertex) { return Vec3<S>(S(v[3 * vertex][lane]), S(v[3 * vertex + 1][lane]), S(v[3 * vertex + 2][lane])); };
      return Triangle<S>(at(0), at(1), at(2));
    };
    return packed() ? get(packed_) : get(full_);
  }
  /// True when the triangles are kept as floats: every coordinate of the mesh is a float (always
  /// for S = float; for double, e.g. meshes read from files in single precision), so the copy is
  /// exact at half the bytes.
  bool packed() const { return !packed_.empty(); }
  /// The triangle blocks when packed(), else empty.
  const std::vector<WideTriangleBlock<float>, detail::WideBvhAllocator<WideTriangleBlock<float>>>& packed_blocks() const { return packed_; }
  /// The triangle blocks in S when not packed(), else empty.
  const std::vector<WideTriangleBlock<S>, detail::WideBvhAllocator<WideTriangleBlock<S>>>& full_blocks() const { return full_; }
  /// Leaf-order position of lane 0 of block b (the positions of a block's lanes are consecutive,
  /// and so are those of a leaf's blocks: a leaf of n triangles from block b holds positions
  /// block_first(b) .. block_first(b) + n - 1).
  std::int32_t block_first(std::int32_t b) const { return block_first_[static_cast<std::size_t>(b)]; }
  std::int32_t num_blocks() const { return static_cast<std::int32_t>(block_first_.size()); }
  /// Row of F of the triangle at leaf-order position k.
  std::int32_t triangle_id(std::int32_t k) const { return ids_[static_cast<std::size_t>(k)]; }
  /// Row of F of the triangle in lane `lane` of block b (triangle_id(block_first(b) + lane), read
  /// from the block itself).
  std::int32_t block_triangle_id(std::int32_t b, int lane) const {
    return packed() ? packed_[static_cast<std::size_t>(b)].id[lane] : full_[static_cast<std::size_t>(b)].id[lane];
  }
  /// True when the triangle at position k repeats the one at k - 1 in the same leaf, vertex order
  /// included (MeshBvh::repeats_previous of the source tree, whose leaves a wide leaf never
  /// splits): a cast that has just tested k - 1 may skip k. False on meshes without copies.
  bool repeats_previous(std::int32_t k) const { return !repeats_.empty() && repeats_[static_cast<std::size_t>(k)]; }
  /// True when some triangle repeats_previous().
  bool has_repeats() const { return !repeats_.empty(); }
  /// packed() && !has_repeats(), kept as one flag (a cast's leaf path reads it at each leaf).
  bool packed_without_repeats() const { return packed_without_repeats_; }
  std::int32_t num_triangles() const { return static_cast<std::int32_t>(ids_.size()); }
  /// Levels of inner nodes on the longest path from the root (0 for an empty tree): a
  /// nearest-first walk keeps at most (W - 1) depth() children pending.
  int depth() const { return depth_; }
  /// An upper bound of |x|_inf over the vertices (the scale of the casts' rounding).
  S coordinate_bound() const { return coordinate_bound_; }
  /// The union of every node's child boxes (floats, kept in double): box()[0..2] its lower
  /// corner, box()[4..6] its upper one, box()[3] = box()[7] = 0 (the layout the AVX cast's set-up
  /// loads). No child box pokes out of it, so a ray's exit from it bounds the entry of every box
  /// the cast can enter (query/wide_fused_slab.hpp). All zeros for an empty tree.
  const std::array<double, 8>& box() const { return box_; }
  /// Heap bytes: nodes, leaf-order triangles and their rows of F.
  std::size_t memory_bytes() const {
    return nodes_.capacity() * sizeof(Node) + full_.capacity() * sizeof(WideTriangleBlock<S>) +
           packed_.capacity() * sizeof(WideTriangleBlock<float>) + (ids_.capacity() + block_first_.capacity()) * sizeof(std::int32_t) +
           repeats_.capacity() / 8;
  }

 private:
  void collapse(const MeshBvh<Aabb<S>>& mesh, const WideBvhConfig& cfg) {
    const int leaf_size = cfg.leaf_size;
    const double node_cost = cfg.node_cost, block_cost = cfg.block_cost;
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
      for (int c = 0; c < 9; ++c) floats = floats && detail::is_float_exact(p[c]);
      coordinate_bound_ = std::max({coordinate_bound_, t.a.cwiseAbs().maxCoeff(), t.b.cwiseAbs().maxCoeff(), t.c.cwiseAbs().maxCoeff()});
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
    // The collapse minimising the wide tree's SAH cost (Ylitie, Karras and Laine 2017, "Efficient
    // incoherent ray traversal on GPUs through compressed wide BVHs", section 3, without their
    // triangle splitting): cost[W j + i - 1] is the least cost of covering binary subtree j by a
    // forest of at most i subtrees (i in 1..W), each of them a wide leaf (area * block_cost per
    // block of four triangles; only subtrees of at most leaf_size triangles, or a leaf of the
    // source tree) or a wide node (area * node_cost plus the cost of its children, a forest of at
    // most W from its two binary children). Areas are half surface areas; the probability that a
    // ray through the root's box enters a box is proportional to it, so the cost is the expected
    // work of a ray that is not stopped by a hit. O(W^2 nodes) time, O(W nodes) memory.
    const auto area = [&](std::int32_t j) {
      const Aabb<S>& b = tree.nodes[static_cast<std::size_t>(j)].bv;
      const Vec3<S> e = b.max - b.min;
      return double(e.x()) * double(e.y()) + double(e.y()) * double(e.z()) + double(e.z()) * double(e.x());
    };
    const double inf = std::numeric_limits<double>::infinity();
    std::vector<double> cost(static_cast<std::size_t>(W) * m, inf);
    // choice[W j + i - 1]: for i = 1, 0 a leaf, 1 a node; for i > 1, the number k of trees the
    // best forest of exactly i (split at j) takes from the left child (i - k from the right);
    // fewer[W j + i - 1]: a forest of at most i - 1 is as cheap (always at a leaf of the source)
    std::vector<std::int8_t> choice(static_cast<std::size_t>(W) * m, 0), fewer(static_cast<std::size_t>(W) * m, 1);
    auto at = [&](std::int32_t j, int i) { return static_cast<std::size_t>(W) * static_cast<std::size_t>(j) + static_cast<std::size_t>(i - 1); };
    std::vector<double> split(W + 1, inf);  // split[i]: the best forest of exactly i split at j
    for (std::size_t jj = m; jj-- > 0;) {
      const std::int32_t j = static_cast<std::int32_t>(jj);
      const auto& nd = tree.nodes[jj];
      const double a = area(j);
      const double leaf = nd.is_leaf() || size[jj] <= leaf_size ? a * block_cost * double((size[jj] + 3) / 4) : inf;
      if (nd.is_leaf()) {
        for (int i = 1; i <= W; ++i) cost[at(j, i)] = leaf;  // choice 0: a leaf; fewer
        continue;
      }
      for (int i = 2; i <= W; ++i) {
        split[i] = inf;
        for (int k = 1; k < i; ++k) {
          const double c = cost[at(nd.left(), k)] + cost[at(nd.right(), i - k)];
          if (c < split[i]) split[i] = c, choice[at(j, i)] = static_cast<std::int8_t>(k);
        }
      }
      const double inner = a * node_cost + split[W];
      cost[at(j, 1)] = leaf <= inner ? leaf : inner;
      choice[at(j, 1)] = leaf <= inner ? 0 : 1;
      for (int i = 2; i <= W; ++i) {
        const bool f = cost[at(j, i - 1)] <= split[i];
        cost[at(j, i)] = f ? cost[at(j, i - 1)] : split[i];
        fewer[at(j, i)] = f ? 1 : 0;
      }
    }
    auto is_leaf = [&](std::int32_t j) { return choice[at(j, 1)] == 0; };
    // the forest of at most W trees that covers the children of inner binary node j
    std::vector<std::pair<std::int32_t, int>> pending;
    auto forest = [&](std::int32_t j, std::int32_t (&kids)[W]) {
      int k = 0;
      const auto& nd = tree.nodes[static_cast<std::size_t>(j)];
      const int kl = choice[at(j, W)];
      pending.assign({{nd.right(), W - kl}, {nd.left(), kl}});
      while (!pending.empty()) {
        auto [x, i] = pending.back();
        pending.pop_back();
        while (i > 1 && fewer[at(x, i)]) --i;  // a forest of fewer trees is as cheap
        if (i == 1) {
          kids[k++] = x;
          continue;
        }
        const auto& nx = tree.nodes[static_cast<std::size_t>(x)];
        const int kx = choice[at(x, i)];
        pending.push_back({nx.right(), i - kx});
        pending.push_back({nx.left(), kx});
      }
      return k;
    };
    nodes_.reserve(m / (W - 1) + 1);
    nodes_.emplace_back();
    std::vector<int> level{1};  // of each wide node: the root is on level 1
    depth_ = 1;
    std::vector<std::pair<std::int32_t, std::int32_t>> work{{0, 0}};  // (binary node, wide node)
    while (!work.empty()) {
      const auto [src, dst] = work.back();
      work.pop_back();
      std::int32_t kids[W];
      int k = 0;
      if (is_leaf(src)) {
        kids[k++] = src;  // a root that is one leaf (at most leaf_size triangles, cheaper so)
      } else {
        k = forest(src, kids);
      }
      Node node;
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
          level.push_back(level[static_cast<std::size_t>(dst)] + 1);
          depth_ = std::max(depth_, level.back());
        }
      }
      nodes_[static_cast<std::size_t>(dst)] = node;
    }
    nodes_.shrink_to_fit();
    box_ = {FLT_MAX, FLT_MAX, FLT_MAX, 0.0, -FLT_MAX, -FLT_MAX, -FLT_MAX, 0.0};
    for (const Node& nd : nodes_)
      for (int c = 0; c < W; ++c)
        if (nd.count[c] >= 0)
          for (std::size_t a = 0; a < 3; ++a) {
            box_[a] = std::min(box_[a], double(nd.bounds[2 * a][c]));
            box_[4 + a] = std::max(box_[4 + a], double(nd.bounds[2 * a + 1][c]));
          }
    // the blocks: each leaf from a new block, in leaf order; the leaves' references become blocks
    struct LeafRef {
      std::int32_t pos, count;
      std::size_t node;
      int slot;
      bool operator<(const LeafRef& r) const { return pos < r.pos; }
    };
    std::vector<LeafRef> leaves;
    for (std::size_t j = 0; j < nodes_.size(); ++j)
      for (int c = 0; c < W; ++c)
        if (nodes_[j].count[c] > 0) leaves.push_back({nodes_[j].first[c], nodes_[j].count[c], j, c});
    std::sort(leaves.begin(), leaves.end());
    for (const LeafRef& l : leaves) {
      nodes_[l.node].first[l.slot] = static_cast<std::int32_t>(block_first_.size());
      for (std::int32_t q = 0; q < l.count; q += 4) block_first_.push_back(l.pos + q);
    }
    auto fill = [&](auto& blocks) {
      using T = std::remove_reference_t<decltype(blocks[0].v[0][0])>;
      blocks.resize(block_first_.size());  // zeros in the unused lanes
      for (auto& blk : blocks)
        for (int c = 0; c < 4; ++c) blk.id[c] = -1;
      for (const LeafRef& l : leaves) {
        const std::size_t b = static_cast<std::size_t>(nodes_[l.node].first[l.slot]);
        for (std::int32_t q = 0; q < l.count; ++q) {
          const S* p = full.data() + 9 * static_cast<std::size_t>(l.pos + q);
          auto& blk = blocks[b + static_cast<std::size_t>(q / 4)];
          for (int c = 0; c < 9; ++c) blk.v[c][q % 4] = static_cast<T>(p[c]);  // exact when packed
          blk.id[q % 4] = ids_[static_cast<std::size_t>(l.pos + q)];
        }
      }
    };
    if (floats) fill(packed_);
    else fill(full_);
    packed_without_repeats_ = floats && repeats_.empty();
  }

  template <class T> using Array = std::vector<T, detail::WideBvhAllocator<T>>;
  Array<Node> nodes_;
  Array<WideTriangleBlock<float>> packed_;  // the triangle blocks when every coordinate is a float
  Array<WideTriangleBlock<S>> full_;        // otherwise
  std::vector<std::int32_t> block_first_;         // leaf-order position of each block's lane 0
  std::vector<std::int32_t> ids_;
  std::vector<bool> repeats_;  // repeats_previous() by leaf-order position; empty when none repeats
  S coordinate_bound_ = S(0);
  std::array<double, 8> box_{};  // box(): the union of the child boxes
  int depth_ = 0;
  bool packed_without_repeats_ = false;
};

}  // namespace impact
