// SPDX-License-Identifier: MIT
/// \file
/// Incremental construction: IncrementalBvh<BV> takes primitives one at a time (insert, remove)
/// and keeps a binary tree over them; build_incremental() builds a Bvh<BV> by inserting every
/// primitive in turn, like the other builders.
///
/// The flat Bvh of bvh.hpp cannot take inserts (its children are adjacent and after their parent,
/// which refit and the traversals' layout rely on), so the incremental tree lives in its own node
/// pool with parent links and a free list, and is turned into a Bvh<BV> by to_bvh() (O(n), the
/// inner BVs merged from the leaves' BVs) or to_fitted_bvh() (every node fitted around its
/// primitives, as the top-down build fits) whenever queries are to run: every query of the
/// library then works unchanged (traverse, traverse_pair, and MeshBvh with
/// BuildMethod::Incremental).
///
/// Choosing the sibling (Bittner, Hapala, Havran 2015, "Incremental BVH construction for ray
/// tracing"; Catto's dynamic AABB trees in Box2D): a new leaf L becomes the sibling of the node X
/// that minimises the surface-area cost of the tree after the insertion, area(X + L) plus the
/// growth of X's ancestors, area(A + L) - area(A) for every ancestor A. SiblingSearch::Greedy (the
/// default) follows one path from the root, into the child whose subtree's lower bound (inherited
/// growth + area(L)) is smaller, and stops when neither child can beat the best node found;
/// SiblingSearch::BranchAndBound finds the exact minimum over a priority queue, entering a subtree
/// only when its lower bound is below the best cost found. Decisions use axis-aligned boxes (every
/// node keeps one; the leaves' BVs are kept apart), whatever the BV type. Ties (equal costs, as
/// for coincident triangles) go to the node with fewer primitives below it, so equal primitives
/// build a balanced tree (depth log2 n), never a chain. After an insertion or a removal each
/// ancestor is refitted and, with rotations on (the default), improved by the tree rotation (Kopta
/// et al. 2012) that most lowers its children's areas: without them, inserting a scanned mesh in
/// its file order gives a tree four times as deep as the top-down build's.
///
/// Measured on igea (268,686 triangles, file order, AABB decisions; docs/hierarchies.md): the
/// greedy search with rotations inserts everything in 7-8x the top-down build of the same tree,
/// with a surface-area cost 1.2x the top-down middle split's; branch and bound about 14x, 1.15x.
///
/// Thread safety: const members (contains, size, to_bvh, to_fitted_bvh, box_of) only read; insert,
/// remove and clear must not overlap any other call on the same object.
#pragma once

#include "impact/bvh/build_config.hpp"
#include "impact/bvh/build_top_down.hpp"
#include "impact/bvh/bvh.hpp"
#include "impact/core/error.hpp"
#include "impact/geometry/triangle.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

namespace impact {

template <class BV> class IncrementalBvh {
 public:
  using Traits = BvTraits<BV>;
  using S = typename Traits::Scalar;
  static constexpr std::int32_t null = -1;

  /// One node of the pool (64 bytes in double: the search reads one cache line per node). Leaves
  /// have child[0] == null and keep their primitive id in child[1]; their BVs are kept apart
  /// (leaf_bv()), since the search never reads them.
  struct alignas(sizeof(S) == 8 ? 64 : 8) Node {
    Aabb<S> box;               ///< the decisions' box (leaves: the primitive's box; inner: merge of the children)
    std::int32_t parent = null;
    std::int32_t child[2] = {null, null};
    std::int32_t count = 0;    ///< primitives below (1 for leaves, 0 for free nodes)
    bool is_leaf() const { return child[0] == null; }
  };

  /// `search`: how the sibling of a new leaf is found; `rotations`: whether the ancestors of an
  /// edit are improved by tree rotations (see the file comment).
  explicit IncrementalBvh(SiblingSearch search = SiblingSearch::Greedy, bool rotations = true)
      : search_(search), rotations_(rotations) {}

  /// Number of primitives in the tree.
  std::size_t size() const { return leaves_; }
  bool empty() const { return leaves_ == 0; }
  /// True when primitive `id` is in the tree.
  /// The BV given for primitive `id` (which must be in the tree).
  const BV& leaf_bv(std::int32_t id) const { return leaf_bv_[static_cast<std::size_t>(id)]; }
  bool contains(std::int32_t id) const {
    return id >= 0 && static_cast<std::size_t>(id) < leaf_of_.size() && leaf_of_[static_cast<std::size_t>(id)] != null;
  }
  /// The node pool and the root (null when empty), for inspection and tests.
  const std::vector<Node>& nodes() const { return nodes_; }
  std::int32_t root() const { return root_; }
  /// Heap bytes held (capacities).
  std::size_t memory_bytes() const { return nodes_.capacity() * sizeof(Node) + (leaf_of_.capacity() + free_.capacity()) * sizeof(std::int32_t) +
                                         leaf_bv_.capacity() * sizeof(BV); }

  /// Inserts primitive `id` (>= 0, not in the tree) with its BV and its axis-aligned box (the
  /// search's cost is the boxes' surface area). Throws InvalidInput for a negative id, an id
  /// already present, or a box that is empty or not finite; the tree is unchanged then.
  void insert(std::int32_t id, const BV& bv, const Aabb<S>& box) {
    require(id >= 0, "IncrementalBvh::insert", "the primitive id must be >= 0");
    require(!contains(id), "IncrementalBvh::insert", "primitive id already in the tree");
    require(box.min.allFinite() && box.max.allFinite() && (box.min.array() <= box.max.array()).all(), "IncrementalBvh::insert",
            "the box must be finite and not empty (min <= max)");
    const std::int32_t leaf = allocate();
    Node& n = nodes_[static_cast<std::size_t>(leaf)];
    n.box = box;
    n.child[0] = null;
    n.child[1] = id;
    n.count = 1;
    if (static_cast<std::size_t>(id) >= leaf_of_.size()) {
      leaf_of_.resize(static_cast<std::size_t>(id) + 1, null);
      leaf_bv_.resize(static_cast<std::size_t>(id) + 1);
    }
    leaf_bv_[static_cast<std::size_t>(id)] = bv;
    leaf_of_[static_cast<std::size_t>(id)] = leaf;
    insert_leaf(leaf);
    ++leaves_;
  }

  /// Inserts a triangle as primitive `id`: its BV is fitted around its vertices (`cfg` chooses
  /// the sphere or box fit). Same checks as insert(id, bv, box), plus finite vertices.
  void insert(std::int32_t id, const Triangle<S>& t, const FitConfig& cfg = {}) {
    require(t.a.allFinite() && t.b.allFinite() && t.c.allFinite(), "IncrementalBvh::insert", "triangle vertex is NaN or infinite");
    const Vec3<S> pts[3] = {t.a, t.b, t.c};
    insert(id, Traits::fit(pts, 3, cfg), Aabb<S>(t.a.cwiseMin(t.b).cwiseMin(t.c), t.a.cwiseMax(t.b).cwiseMax(t.c)));
  }

  /// Removes primitive `id`. Throws InvalidInput when it is not in the tree (nothing changes).
  void remove(std::int32_t id) {
    require(contains(id), "IncrementalBvh::remove", "primitive id not in the tree");
    const std::int32_t leaf = leaf_of_[static_cast<std::size_t>(id)];
    leaf_of_[static_cast<std::size_t>(id)] = null;
    const std::int32_t parent = node(leaf).parent;
    if (parent == null) {
      root_ = null;
    } else {
      const std::int32_t grand = node(parent).parent;
      const std::int32_t sibling = node(parent).child[0] == leaf ? node(parent).child[1] : node(parent).child[0];
      node(sibling).parent = grand;
      if (grand == null) {
        root_ = sibling;
      } else {
        node(grand).child[node(grand).child[0] == parent ? 0 : 1] = sibling;
        refit_up(grand);
      }
      release(parent);
    }
    release(leaf);
    --leaves_;
  }

  /// Removes everything (keeps the pool's memory).
  void clear() {
    nodes_.clear();
    free_.clear();
    leaf_of_.clear();
    leaf_bv_.clear();
    root_ = null;
    leaves_ = 0;
  }

  /// The tree as a flat Bvh<BV> over the primitive ids: depth first, children adjacent and after
  /// their parent (refit.hpp and every traversal work on it), leaves of one primitive, inner BVs
  /// merged from their children (BvTraits::merge: looser than fitting). O(n).
  Bvh<BV> to_bvh() const {
    Bvh<BV> out = layout<BV>(1);
    for (std::size_t k = out.nodes.size(); k-- > 0;) {
      auto& n = out.nodes[k];
      if (n.is_leaf()) {
        n.bv = leaf_bv_[static_cast<std::size_t>(out.primitives[static_cast<std::size_t>(n.first)])];
      } else {
        n.bv = Traits::merge(out.nodes[static_cast<std::size_t>(n.left())].bv, out.nodes[static_cast<std::size_t>(n.right())].bv);
      }
    }
    return out;
  }

  /// The tree as a flat Bvh<OutBV> (any BV type) whose every node is fitted by `fit(const
  /// std::int32_t* ids, std::size_t count) -> OutBV` around its primitives, as the top-down build
  /// fits; subtrees of at most `leaf_size` (>= 1) primitives become one leaf. O(n log n) for
  /// balanced trees.
  template <class OutBV, class Fit> Bvh<OutBV> to_fitted_bvh(Fit&& fit, int leaf_size = 1) const {
    if (leaf_size < 1) throw InvalidInput("IncrementalBvh::to_fitted_bvh: leaf_size must be >= 1");
    Bvh<OutBV> out = layout<OutBV>(leaf_size);
    // ranges of inner nodes from their children (children after parents)
    std::vector<std::pair<std::int32_t, std::int32_t>> range(out.nodes.size());
    for (std::size_t k = out.nodes.size(); k-- > 0;) {
      const auto& n = out.nodes[k];
      range[k] = n.is_leaf() ? std::make_pair(n.first, n.count)
                             : std::make_pair(range[static_cast<std::size_t>(n.left())].first,
                                              range[static_cast<std::size_t>(n.left())].second + range[static_cast<std::size_t>(n.right())].second);
    }
    for (std::size_t k = 0; k < out.nodes.size(); ++k)
      out.nodes[k].bv = fit(out.primitives.data() + range[k].first, static_cast<std::size_t>(range[k].second));
    return out;
  }

  /// Surface-area cost of the tree: the sum of the inner nodes' box half-areas (what the sibling
  /// choice greedily minimises), for benchmarks and tests.
  double sah_cost() const {
    double c = 0;
    for (const Node& n : nodes_)
      if (n.count > 1) c += double(detail::half_area(n.box));
    return c;
  }

 private:
  Node& node(std::int32_t i) { return nodes_[static_cast<std::size_t>(i)]; }
  const Node& node(std::int32_t i) const { return nodes_[static_cast<std::size_t>(i)]; }

  std::int32_t allocate() {
    if (!free_.empty()) {
      const std::int32_t i = free_.back();
      free_.pop_back();
      node(i) = Node{};
      return i;
    }
    nodes_.emplace_back();
    return static_cast<std::int32_t>(nodes_.size()) - 1;
  }
  void release(std::int32_t i) {
    node(i) = Node{};
    node(i).parent = null;
    free_.push_back(i);
  }

  /// Boxes and counts of i and its ancestors, from their children; with rotations on, each
  /// ancestor first gets the rotation that most reduces its children's areas (rotate()).
  void refit_up(std::int32_t i) {
    for (; i != null; i = node(i).parent) {
      if (rotations_) rotate(i);
      Node& n = node(i);
      const Node& l = node(n.child[0]);
      const Node& r = node(n.child[1]);
      n.box = merge(l.box, r.box);
      n.count = l.count + r.count;
    }
  }

  /// Tree rotation at node a (Kopta et al. 2012, as Box2D v3): swap one child of a with one
  /// grandchild under its other child when that lowers the area of the child that changes
  /// (the only area a swap changes); strict decrease only, so equal boxes never rotate. Node a's
  /// box and count are unchanged; the changed child's are recomputed.
  void rotate(std::int32_t a) {
    const Node& n = node(a);
    S best_gain = S(0);
    int best_c = -1, best_g = -1;
    for (int c = 0; c < 2; ++c) {
      const Node& other = node(n.child[1 - c]);  // its children are candidates to swap with child c
      if (other.is_leaf()) continue;
      const Aabb<S>& moving = node(n.child[c]).box;
      const S old_area = detail::half_area(other.box);
      for (int g = 0; g < 2; ++g) {
        const S gain = old_area - detail::half_area(merge(moving, node(other.child[1 - g]).box));
        if (gain > best_gain) best_gain = gain, best_c = c, best_g = g;
      }
    }
    if (best_c < 0) return;
    const std::int32_t moving = n.child[best_c], other = n.child[1 - best_c];
    const std::int32_t grand = node(other).child[best_g];
    node(a).child[best_c] = grand;
    node(grand).parent = a;
    node(other).child[best_g] = moving;
    node(moving).parent = other;
    Node& o = node(other);
    o.box = merge(node(o.child[0]).box, node(o.child[1]).box);
    o.count = node(o.child[0]).count + node(o.child[1]).count;
  }

  /// Branch and bound for the best sibling of a leaf with box `b` (see the file comment).
  std::int32_t best_sibling(const Aabb<S>& b) {
    const S area_b = detail::half_area(b);
    // a min-heap on (inherited growth, primitive count)
    const auto later = [](const QueueItem& x, const QueueItem& y) {
      return x.inherited != y.inherited ? x.inherited > y.inherited : x.count > y.count;
    };
    std::int32_t best = root_;
    S best_cost = std::numeric_limits<S>::infinity();
    std::int32_t best_count = std::numeric_limits<std::int32_t>::max();
    heap_.clear();
    heap_.push_back({S(0), node(root_).count, root_});
    while (!heap_.empty()) {
      std::pop_heap(heap_.begin(), heap_.end(), later);
      const QueueItem it = heap_.back();
      heap_.pop_back();
      const S lower = it.inherited + area_b;
      if (lower > best_cost || (lower == best_cost && it.count >= best_count)) continue;
      const Node& n = node(it.node);
      const S direct = detail::half_area(merge(n.box, b));
      const S cost = direct + it.inherited;
      if (cost < best_cost || (cost == best_cost && n.count < best_count)) {
        best = it.node;
        best_cost = cost;
        best_count = n.count;
      }
      if (n.is_leaf()) continue;
      const S inherited = it.inherited + (direct - detail::half_area(n.box));
      const S child_lower = inherited + area_b;
      for (int c = 0; c < 2; ++c) {
        const Node& k = node(n.child[c]);
        if (child_lower < best_cost || (child_lower == best_cost && k.count < best_count)) {
          heap_.push_back({inherited, k.count, n.child[c]});
          std::push_heap(heap_.begin(), heap_.end(), later);
        }
      }
    }
    return best;
  }

  /// One path from the root (SiblingSearch::Greedy): the costs are those of best_sibling, the
  /// descent goes into the child with the smaller lower bound (ties: fewer primitives).
  std::int32_t greedy_sibling(const Aabb<S>& b) const {
    const S area_b = detail::half_area(b);
    std::int32_t i = root_;
    S inherited = S(0);
    S direct = detail::half_area(merge(node(i).box, b));
    std::int32_t best = i;
    S best_cost = direct;
    std::int32_t best_count = node(i).count;
    while (!node(i).is_leaf()) {
      const Node& n = node(i);
      inherited += direct - detail::half_area(n.box);
      S lower[2], dir[2];
      for (int c = 0; c < 2; ++c) {
        const Node& k = node(n.child[c]);
        dir[c] = detail::half_area(merge(k.box, b));
        const S cost = dir[c] + inherited;
        if (cost < best_cost || (cost == best_cost && k.count < best_count)) best = n.child[c], best_cost = cost, best_count = k.count;
        lower[c] = k.is_leaf() ? std::numeric_limits<S>::infinity() : inherited + (dir[c] - detail::half_area(k.box)) + area_b;
      }
      const auto useful = [&](int c) {
        return lower[c] < best_cost || (lower[c] == best_cost && node(n.child[c]).count - 1 < best_count);
      };
      const bool u0 = useful(0), u1 = useful(1);
      if (!u0 && !u1) break;
      int c = u0 && !u1 ? 0 : !u0 && u1 ? 1 : (lower[0] != lower[1] ? (lower[0] < lower[1] ? 0 : 1) : (node(n.child[0]).count <= node(n.child[1]).count ? 0 : 1));
      i = n.child[c];
      direct = dir[c];
    }
    return best;
  }

  void insert_leaf(std::int32_t leaf) {
    if (root_ == null) {
      root_ = leaf;
      node(leaf).parent = null;
      return;
    }
    const std::int32_t sibling = search_ == SiblingSearch::Greedy ? greedy_sibling(node(leaf).box) : best_sibling(node(leaf).box);
    const std::int32_t old_parent = node(sibling).parent;
    const std::int32_t parent = allocate();
    node(parent).parent = old_parent;
    node(parent).child[0] = sibling;
    node(parent).child[1] = leaf;
    node(sibling).parent = parent;
    node(leaf).parent = parent;
    if (old_parent == null)
      root_ = parent;
    else
      node(old_parent).child[node(old_parent).child[0] == sibling ? 0 : 1] = parent;
    refit_up(parent);
  }

  /// Depth-first flat layout (children adjacent, after their parent); subtrees of at most
  /// leaf_size primitives are one leaf. BVs are left for the caller.
  template <class OutBV> Bvh<OutBV> layout(int leaf_size) const {
    Bvh<OutBV> out;
    if (root_ == null) return out;
    out.primitives.reserve(leaves_);
    out.nodes.reserve(2 * leaves_);
    out.nodes.emplace_back();
    std::vector<std::pair<std::int32_t, std::int32_t>> stack{{root_, 0}};  // (pool node, flat node)
    std::vector<std::int32_t> sub;
    while (!stack.empty()) {
      const auto [p, f] = stack.back();
      stack.pop_back();
      const Node& n = node(p);
      if (n.count <= leaf_size) {
        out.nodes[static_cast<std::size_t>(f)].first = static_cast<std::int32_t>(out.primitives.size());
        out.nodes[static_cast<std::size_t>(f)].count = n.count;
        sub.assign(1, p);
        while (!sub.empty()) {
          const Node& s = node(sub.back());
          sub.pop_back();
          if (s.is_leaf()) {
            out.primitives.push_back(s.child[1]);
          } else {
            sub.push_back(s.child[1]);
            sub.push_back(s.child[0]);
          }
        }
        continue;
      }
      const auto left = static_cast<std::int32_t>(out.nodes.size());
      out.nodes.emplace_back();
      out.nodes.emplace_back();
      out.nodes[static_cast<std::size_t>(f)].first = left;
      out.nodes[static_cast<std::size_t>(f)].count = 0;
      stack.push_back({n.child[1], left + 1});
      stack.push_back({n.child[0], left});
    }
    return out;
  }

  std::vector<Node> nodes_;
  std::vector<std::int32_t> free_;
  std::vector<std::int32_t> leaf_of_;  // primitive id -> leaf node (null when absent)
  std::vector<BV> leaf_bv_;            // primitive id -> its BV
  std::int32_t root_ = null;
  std::size_t leaves_ = 0;
  struct QueueItem {
    S inherited;  // growth of the ancestors' areas
    std::int32_t count, node;
  };
  std::vector<QueueItem> heap_;
  SiblingSearch search_ = SiblingSearch::Greedy;
  bool rotations_ = true;  // scratch of best_sibling, kept to avoid an allocation per insertion
};

/// Builds a tree over centroids.size() primitives by inserting them one at a time, in index
/// order, into an IncrementalBvh over their axis-aligned `boxes` (one per primitive; the search
/// and the rotations are cfg.sibling_search and cfg.rotations); every node
/// of the result is then fitted by `fit(const std::int32_t* ids, std::size_t count) -> BV` around
/// its primitives, as build_top_down fits, and subtrees of at most cfg.leaf_size primitives become
/// leaves. `centroids` only give the count (the boxes decide). Throws InvalidInput on leaf_size <
/// 1, a box count that does not match, or a box that is empty or not finite.
template <class BV, class Fit>
Bvh<BV> build_incremental(const std::vector<Vec3<typename BvTraits<BV>::Scalar>>& centroids,
                          const std::vector<Aabb<typename BvTraits<BV>::Scalar>>& boxes, Fit&& fit, const BuildConfig& cfg = {}) {
  using S = typename BvTraits<BV>::Scalar;
  if (cfg.leaf_size < 1) throw InvalidInput("build_incremental: leaf_size must be >= 1");
  if (boxes.size() != centroids.size()) throw InvalidInput("build_incremental: one box per primitive");
  IncrementalBvh<Aabb<S>> inc(cfg.sibling_search, cfg.rotations);
  for (std::size_t i = 0; i < boxes.size(); ++i) inc.insert(static_cast<std::int32_t>(i), boxes[i], boxes[i]);
  return inc.template to_fitted_bvh<BV>(fit, cfg.leaf_size);
}

}  // namespace impact
