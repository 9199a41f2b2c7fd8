// SPDX-License-Identifier: MIT
/// \file
/// DynamicTree: an incremental AABB tree over objects (the dynamic tree of the static/dynamic
/// split, both trees of the hierarchical broad phase).
///
/// The tree lives in one flat node pool with a free list (the build-once `Bvh` of bvh/ cannot grow).
/// Leaves hold *fattened* boxes: the object's tight box grown by a margin, so an object that moves a
/// little stays inside its leaf box and costs nothing in the tree. An object that leaves its fat box
/// is removed and inserted again: the new sibling is chosen by the surface-area cost of the
/// enlargement (greedy descent, as in the incremental trees of Goldsmith & Salmon 1987 and of Box2D),
/// and its ancestors are refitted and improved by surface-area tree rotations (Kopta et al. 2012) up to the
/// first one the edit leaves unchanged. The
/// surface-area cost of the whole tree is watched; when it degrades past a ratio of its value after the last
/// rebuild, the tree is rebuilt top-down (median split on the longest axis of the leaf centres).
/// Leaf node ids are stable across rotations and rebuilds, so callers keep them as handles.
///
/// Each node also records whether its subtree holds an *active* leaf (dynamic and awake): the
/// self pair traversal (self_pairs) skips node pairs with no active leaf on either side, so
/// static–static and sleeping pairs are never reached; it descends the larger node first (FCL's
/// collisionRecurse rule, written iteratively). A cache of pairs (dynamic_pairs.hpp) needs only
/// the pairs whose fat boxes changed: leaves marked *fresh* (mark_fresh) after an insertion or a
/// reinsertion give theirs by fresh_pairs, each fresh leaf querying the subtrees beside its path
/// to the root.
///
/// Thread safety: the const members of DynamicTree (query, self_pairs) only read: any number of
/// threads may call them at once while no thread edits the tree (insert, remove, update,
/// set_active, mark_fresh, fresh_pairs, rebuild, maybe_rebuild).
#pragma once

#include "impact/broad/broad_phase.hpp"
#include "impact/bvh/traversal_stack.hpp"
#include "impact/core/parallel.hpp"

#include <algorithm>
#include <cmath>
#include <utility>
#include <cstdint>
#include <vector>

namespace impact {

/// Knobs of the incremental tree, with their defaults.
struct DynamicTreeOptions {
  /// A leaf box is the tight box grown on every side by fat_fraction times the object's largest
  /// extent plus fat_margin (absolute, scene units). Larger values mean fewer reinsertions and
  /// more candidate node pairs.
  double fat_fraction = 0.1;
  double fat_margin = 0.0;
  /// Rebuild when the tree's surface-area cost exceeds this multiple of its value after the last
  /// rebuild (checked after every leaves/8 reinsertions).
  double rebuild_ratio = 1.4;
  /// On reinsertion, a leaf box is stretched by this multiple of the displacement since the last
  /// insertion (capped at the object's size plus fat_margin).
  double predict = 2.0;
};

template <class S>
class DynamicTree {
 public:
  static constexpr std::int32_t null = -1;

  /// One cache line for double (64 bytes): box, links, height and flags.
  struct alignas(sizeof(S) == 8 ? 64 : 8) Node {
    Aabb<S> box;
    std::int32_t parent = null;
    std::int32_t child[2] = {null, null};  ///< child[0] == null for leaves; a leaf keeps its object in child[1]
    std::int16_t height = 0;               ///< 0 for leaves, -1 for free nodes
    std::uint8_t active = 0;               ///< the subtree holds an active leaf
    std::uint8_t exact : 1;                ///< leaf stored with its tight box (objects that never move)
    std::uint8_t fresh : 1;                ///< a fresh leaf (mark_fresh)
    Node() : exact(0), fresh(0) {}
    bool is_leaf() const { return child[0] == null; }
    std::int32_t object() const { return child[1]; }  ///< the caller's payload (leaves)
  };

  explicit DynamicTree(const DynamicTreeOptions& opt = {}) : opt_(opt) {}

  /// Inserts a leaf for `object` with tight box `tight`, stored fattened unless `exact` (for
  /// objects that are not expected to move). Returns the leaf id.
  std::int32_t insert(std::int32_t object, const Aabb<S>& tight, bool active, bool exact = false) {
    const std::int32_t leaf = allocate();
    Node& n = nodes_[static_cast<std::size_t>(leaf)];
    n.exact = exact;
    n.box = exact ? tight : fatten(tight);
    n.child[1] = object;
    n.height = 0;
    n.active = active;
    insert_leaf(leaf);
    ++leaves_;
    ++changes_;
    return leaf;
  }

  /// Removes a leaf returned by insert().
  void remove(std::int32_t leaf) {
    remove_leaf(leaf);
    release(leaf);
    --leaves_;
    ++changes_;
  }

  /// The object's tight box changed. Returns true when it left its fat box and the leaf was
  /// reinserted; false when the tree did not change. The new fat box is also stretched along the
  /// displacement since the last insertion (at most by the object's size plus the margin), so an
  /// object moving steadily is reinserted every few steps rather than every step.
  bool update(std::int32_t leaf, const Aabb<S>& tight) {
    Node& n = nodes_[static_cast<std::size_t>(leaf)];
    if (n.exact ? (n.box.min == tight.min && n.box.max == tight.max) : contains(n.box, tight)) return false;
    remove_leaf(leaf);
    if (n.exact) {
      n.box = tight;
    } else {
      const Vec3<S> d = tight.center() - n.box.center();
      Aabb<S> fat = fatten(tight);
      const S cap = (tight.max - tight.min).maxCoeff() + S(opt_.fat_margin);
      for (int k = 0; k < 3; ++k) {
        const S e = std::min(std::abs(d[k]) * S(opt_.predict), cap);
        if (d[k] > S(0))
          fat.max[k] += e;
        else
          fat.min[k] -= e;
      }
      n.box = fat;
    }
    insert_leaf(leaf);
    ++changes_;
    return true;
  }

  /// Marks a leaf active (dynamic and awake) or not, and updates its ancestors' flags.
  void set_active(std::int32_t leaf, bool active) {
    nodes_[static_cast<std::size_t>(leaf)].active = active;
    for (std::int32_t i = nodes_[static_cast<std::size_t>(leaf)].parent; i != null; i = node(i).parent) {
      const std::uint8_t a = node(node(i).child[0]).active | node(node(i).child[1]).active;
      if (a == node(i).active) break;
      node(i).active = a;
    }
  }

  /// Rebuilds when the surface-area cost has degraded (see DynamicTreeOptions::rebuild_ratio).
  /// Returns true when it rebuilt.
  bool maybe_rebuild() {
    if (leaves_ < 4 || changes_ < std::max<std::size_t>(leaves_ / 8, 16)) return false;
    changes_ = 0;
    const double cost = sah_cost();
    if (built_cost_ > 0 && cost <= opt_.rebuild_ratio * built_cost_) return false;
    rebuild();
    return true;
  }

  /// Top-down rebuild over the current leaves (ids unchanged). O(n log n).
  void rebuild() {
    std::vector<std::int32_t> leaves;
    leaves.reserve(leaves_);
    for (std::size_t i = 0; i < nodes_.size(); ++i) {
      Node& n = nodes_[i];
      if (n.height < 0) continue;
      if (n.is_leaf())
        leaves.push_back(static_cast<std::int32_t>(i));
      else
        n.height = -1;
    }
    // Free list in ascending order, so that the pre-order build below lays parents before
    // children and left subtrees next to their parents.
    free_ = null;
    for (std::size_t i = nodes_.size(); i-- > 0;)
      if (nodes_[i].height < 0) release(static_cast<std::int32_t>(i));
    root_ = leaves.empty() ? null : build_range(leaves.data(), leaves.data() + leaves.size());
    if (root_ != null) node(root_).parent = null;
    changes_ = 0;
    built_cost_ = sah_cost();
  }

  /// Calls visit(object) for every leaf whose fat box overlaps `box`; stops when visit returns false.
  template <class Visit>
  bool query(const Aabb<S>& box, Visit&& visit, BroadPhaseStats& st) const {
    if (root_ == null) return true;
    detail::TraversalStack<std::int32_t> stack;
    stack.push(root_);
    while (!stack.empty()) {
      const Node& n = node(stack.pop());
      ++st.bv_tests;
      if (!overlap(n.box, box)) continue;
      if (n.is_leaf()) {
        if (!visit(n.object())) return false;
      } else {
        stack.push(n.child[1]);
        stack.push(n.child[0]);
      }
    }
    return true;
  }

  /// Calls visit(object_a, object_b) once for every unordered pair of leaves whose fat boxes
  /// overlap and of which at least one is active. Larger node first; stops when visit returns false.
  template <class Visit>
  bool self_pairs(Visit&& visit, BroadPhaseStats& st) const {
    if (root_ == null) return true;
    detail::TraversalStack<std::pair<std::int32_t, std::int32_t>> stack;
    stack.push({root_, root_});
    while (!stack.empty()) {
      const auto [i, j] = stack.pop();
      const Node& ni = node(i);
      if (i == j) {
        if (ni.is_leaf() || !ni.active) continue;
        stack.push({ni.child[0], ni.child[1]});
        stack.push({ni.child[1], ni.child[1]});
        stack.push({ni.child[0], ni.child[0]});
        continue;
      }
      const Node& nj = node(j);
      if (!(ni.active | nj.active)) continue;
      ++st.bv_tests;
      if (!overlap(ni.box, nj.box)) continue;
      if (!descend(i, j, stack))
        if (!visit(ni.object(), nj.object())) return false;
    }
    return true;
  }

  /// Marks a leaf *fresh*: its fat box is new (inserted or reinserted), so its pairs are to be
  /// found again by fresh_pairs().
  void mark_fresh(std::int32_t leaf) {
    if (node(leaf).fresh) return;
    node(leaf).fresh = 1;
    fresh_.push_back(leaf);
  }
  /// Calls visit(object_a, object_b) once for every unordered pair of leaves whose fat boxes
  /// overlap and of which at least one is fresh, active or not; then unmarks the fresh leaves.
  /// Each fresh leaf walks up to the root and queries, at every ancestor, the subtree on the
  /// other side with its box: about one node test per level where a query from the root takes
  /// two, and the pairs of two fresh leaves come from the one with the smaller id. The queries
  /// only read the tree, so on `threads` threads ranges of fresh leaves collect their pairs apart
  /// and visit then gets them all in the serial order: the same calls for every thread count.
  template <class Visit>
  void fresh_pairs(Visit&& visit, BroadPhaseStats& st, int threads = 1) {
    std::sort(fresh_.begin(), fresh_.end());  // a removed fresh leaf's node may have been reused
    fresh_.erase(std::unique(fresh_.begin(), fresh_.end()), fresh_.end());
    constexpr std::size_t grain = 32;
    const std::size_t n = fresh_.size();
    if (threads == 1 || n < 2 * grain) {
      detail::TraversalStack<std::int32_t> stack;
      for (const std::int32_t leaf : fresh_) fresh_leaf_pairs(leaf, stack, visit, st);
    } else {
      struct Part {
        std::vector<std::pair<std::int32_t, std::int32_t>> pairs;
        BroadPhaseStats stats;
      };
      std::vector<Part> parts((n + grain - 1) / grain);
      parallel_for_ranges(n, grain, threads, [&](std::size_t b, std::size_t e) {
        Part& part = parts[b / grain];
        detail::TraversalStack<std::int32_t> stack;
        auto collect = [&part](std::int32_t x, std::int32_t y) {
          part.pairs.emplace_back(x, y);
          return true;
        };
        for (std::size_t k = b; k < e; ++k) fresh_leaf_pairs(fresh_[k], stack, collect, part.stats);
      });
      for (const Part& part : parts) {
        st += part.stats;
        for (const auto& pr : part.pairs) visit(pr.first, pr.second);
      }
    }
    for (const std::int32_t leaf : fresh_) node(leaf).fresh = 0;
    fresh_.clear();
  }

  const Node& node(std::int32_t i) const { return nodes_[static_cast<std::size_t>(i)]; }
  /// The (fattened) box stored for leaf or node i.
  const Aabb<S>& box(std::int32_t i) const { return nodes_[static_cast<std::size_t>(i)].box; }
  std::int32_t root() const { return root_; }
  std::size_t num_leaves() const { return leaves_; }
  /// Height of the root (0 for a single leaf, -1 when empty).
  std::int32_t height() const { return root_ == null ? -1 : node(root_).height; }
  /// Sum of the surface areas of the inner nodes over the root's: the expected number of inner
  /// nodes a random ray or box visits; lower is better.
  double sah_cost() const {
    if (root_ == null) return 0;
    double sum = 0;
    for (const Node& n : nodes_)
      if (n.height > 0) sum += area(n.box);
    const double r = area(node(root_).box);
    return r > 0 ? sum / r : 0;
  }
  /// Checks parent links, heights, boxes and activity flags (for tests). O(n).
  bool valid() const {
    if (root_ == null) return leaves_ == 0;
    std::size_t count = 0;
    std::vector<std::int32_t> stack{root_};
    if (node(root_).parent != null) return false;
    while (!stack.empty()) {
      const std::int32_t i = stack.back();
      stack.pop_back();
      const Node& n = node(i);
      if (n.height < 0) return false;
      if (n.is_leaf()) {
        ++count;
        if (n.height != 0) return false;
        continue;
      }
      const Node& a = node(n.child[0]);
      const Node& b = node(n.child[1]);
      if (a.parent != i || b.parent != i) return false;
      if (n.height != 1 + std::max(a.height, b.height)) return false;
      if (!contains(n.box, a.box) || !contains(n.box, b.box)) return false;
      if (n.active != (a.active | b.active)) return false;
      stack.push_back(n.child[0]);
      stack.push_back(n.child[1]);
    }
    return count == leaves_;
  }

 private:
  Node& node(std::int32_t i) { return nodes_[static_cast<std::size_t>(i)]; }

  static bool contains(const Aabb<S>& outer, const Aabb<S>& inner) {
    return (outer.min.array() <= inner.min.array()).all() && (inner.max.array() <= outer.max.array()).all();
  }
  static double area(const Aabb<S>& b) {
    const Vec3<S> e = b.max - b.min;
    return double(e.x()) * double(e.y()) + double(e.y()) * double(e.z()) + double(e.z()) * double(e.x());
  }
  static S size(const Aabb<S>& b) { return (b.max - b.min).sum(); }
  Aabb<S> fatten(const Aabb<S>& tight) const {
    const S m = S(opt_.fat_fraction) * (tight.max - tight.min).maxCoeff() + S(opt_.fat_margin);
    return {tight.min.array() - m, tight.max.array() + m};
  }

  /// Pushes the children of the larger of nodes i and j, or of the inner one when the other is a
  /// leaf (FCL's collisionRecurse rule); false when both are leaves.
  template <class Stack>
  bool descend(std::int32_t i, std::int32_t j, Stack& stack) const {
    const Node& ni = node(i);
    const Node& nj = node(j);
    const bool li = ni.is_leaf(), lj = nj.is_leaf();
    if (li && lj) return false;
    if (lj || (!li && size(ni.box) >= size(nj.box))) {
      stack.push({ni.child[1], j});
      stack.push({ni.child[0], j});
    } else {
      stack.push({i, nj.child[1]});
      stack.push({i, nj.child[0]});
    }
    return true;
  }

  std::int32_t allocate() {
    if (free_ != null) {
      const std::int32_t i = free_;
      free_ = node(i).parent;
      node(i) = Node{};
      return i;
    }
    nodes_.push_back(Node{});
    return static_cast<std::int32_t>(nodes_.size() - 1);
  }
  void release(std::int32_t i) {
    Node& n = node(i);
    n.height = -1;
    n.child[0] = n.child[1] = null;
    n.parent = free_;
    free_ = i;
  }

  /// Box, height and activity of inner node i from its children.
  void recompute(std::int32_t i) {
    Node& n = node(i);
    const Node& a = node(n.child[0]);
    const Node& b = node(n.child[1]);
    n.box = merge(a.box, b.box);
    n.height = static_cast<std::int16_t>(1 + std::max(a.height, b.height));
    n.active = a.active | b.active;
  }

  /// The pairs of one fresh leaf for fresh_pairs (reads only).
  template <class Visit>
  void fresh_leaf_pairs(std::int32_t leaf, detail::TraversalStack<std::int32_t>& stack, Visit& visit, BroadPhaseStats& st) const {
    const Node& nl = node(leaf);
    if (nl.height != 0 || !nl.fresh) return;  // removed since it was marked
    for (std::int32_t c = leaf, p = nl.parent; p != null; c = p, p = node(p).parent) {
      const Node& np = node(p);
      stack.push(np.child[np.child[0] == c ? 1 : 0]);
      while (!stack.empty()) {
        const std::int32_t i = stack.pop();
        const Node& n = node(i);
        ++st.bv_tests;
        if (!overlap(n.box, nl.box)) continue;
        if (!n.is_leaf()) {
          stack.push(n.child[1]);
          stack.push(n.child[0]);
        } else if (!n.fresh || leaf < i) {
          visit(nl.object(), n.object());
        }
      }
    }
  }

  void insert_leaf(std::int32_t leaf) {
    if (root_ == null) {
      root_ = leaf;
      node(leaf).parent = null;
      return;
    }
    // Greedy descent: the sibling whose enlargement costs least in surface area.
    const Aabb<S> box = node(leaf).box;
    std::int32_t i = root_;
    while (!node(i).is_leaf()) {
      const Node& n = node(i);
      const double a = area(n.box);
      const double combined = area(merge(n.box, box));
      const double here = 2 * combined;           // new parent of (n, leaf)
      const double inherit = 2 * (combined - a);  // growth every node below pays
      double cost[2];
      for (int k = 0; k < 2; ++k) {
        const Node& c = node(n.child[k]);
        const double grown = area(merge(c.box, box));
        cost[k] = (c.is_leaf() ? grown : grown - area(c.box)) + inherit;
      }
      if (here < cost[0] && here < cost[1]) break;
      i = cost[0] <= cost[1] ? n.child[0] : n.child[1];
    }
    const std::int32_t sibling = i;
    const std::int32_t old_parent = node(sibling).parent;
    const std::int32_t p = allocate();
    node(p).parent = old_parent;
    node(p).child[0] = sibling;
    node(p).child[1] = leaf;
    node(sibling).parent = p;
    node(leaf).parent = p;
    if (old_parent == null) {
      root_ = p;
    } else {
      Node& op = node(old_parent);
      op.child[op.child[0] == sibling ? 0 : 1] = p;
    }
    fix_upwards(p);
  }

  void remove_leaf(std::int32_t leaf) {
    if (leaf == root_) {
      root_ = null;
      return;
    }
    const std::int32_t p = node(leaf).parent;
    const std::int32_t g = node(p).parent;
    const std::int32_t sibling = node(p).child[node(p).child[0] == leaf ? 1 : 0];
    if (g == null) {
      root_ = sibling;
      node(sibling).parent = null;
      release(p);
    } else {
      Node& gn = node(g);
      gn.child[gn.child[0] == p ? 0 : 1] = sibling;
      node(sibling).parent = g;
      release(p);
      fix_upwards(g);
    }
    node(leaf).parent = null;
  }

  /// Rotates and refits the ancestors of an edit, from node i up. Stops at the first node that
  /// neither rotated nor changed its box, height or activity: every node above it is then
  /// unchanged too (a reinsertion deep in a large tree usually stops a few levels up instead of
  /// walking and rotating to the root).
  void fix_upwards(std::int32_t i) {
    while (i != null) {
      const Node before = node(i);
      const bool rotated = rotate(i);
      recompute(i);
      const Node& n = node(i);
      if (!rotated && n.height == before.height && n.active == before.active && n.box.min == before.box.min &&
          n.box.max == before.box.max)
        break;
      i = n.parent;
    }
  }

  /// Surface-area tree rotation at inner node a (Kopta et al., "Fast, effective BVH updates for
  /// animated scenes", I3D 2012): swap one child of a with a grandchild under the other child
  /// when that shrinks the other child's surface area, most shrinking swap first. Unlike
  /// height-balancing (AVL) rotations this never groups distant nodes; a rebuild bounds the depth.
  /// Returns whether it swapped.
  bool rotate(std::int32_t a) {
    if (node(a).is_leaf()) return false;
    const std::int32_t b = node(a).child[0], c = node(a).child[1];
    double best = 0;
    int kind = -1;  // 0/1: b <-> c.child[k]; 2/3: c <-> b.child[k - 2]
    for (int side = 0; side < 2; ++side) {
      const std::int32_t keep = side == 0 ? b : c;   // stays a child of a, moves down
      const std::int32_t under = side == 0 ? c : b;  // the child whose children are candidates
      const Node& nu = node(under);
      if (nu.is_leaf()) continue;
      const double current = area(nu.box);
      for (int k = 0; k < 2; ++k) {
        const double cost = area(merge(node(keep).box, node(nu.child[1 - k]).box)) - current;
        if (cost < best) {
          best = cost;
          kind = 2 * side + k;
        }
      }
    }
    if (kind < 0) return false;
    const int k = kind & 1;
    const std::int32_t keep = kind < 2 ? b : c, under = kind < 2 ? c : b;
    const std::int32_t g = node(under).child[k];
    node(under).child[k] = keep;
    node(keep).parent = under;
    node(a).child[kind < 2 ? 0 : 1] = g;
    node(g).parent = a;
    recompute(under);
    return true;
  }

  /// Builds inner nodes over the leaves in [first, last) by median split; returns the subtree root.
  std::int32_t build_range(std::int32_t* first, std::int32_t* last) {
    const std::ptrdiff_t n = last - first;
    if (n == 1) return *first;
    const std::int32_t p = allocate();  // before the children: pre-order layout
    Aabb<S> cbox;
    for (std::int32_t* q = first; q != last; ++q) cbox.extend(node(*q).box.center());
    const int axis = cbox.longest_axis();
    std::int32_t* mid = first + n / 2;
    std::nth_element(first, mid, last, [&](std::int32_t x, std::int32_t y) {
      return node(x).box.min[axis] + node(x).box.max[axis] < node(y).box.min[axis] + node(y).box.max[axis];
    });
    const std::int32_t l = build_range(first, mid);
    const std::int32_t r = build_range(mid, last);
    node(p).child[0] = l;
    node(p).child[1] = r;
    node(l).parent = p;
    node(r).parent = p;
    recompute(p);
    return p;
  }

  DynamicTreeOptions opt_;
  std::vector<Node> nodes_;
  std::int32_t root_ = null;
  std::int32_t free_ = null;
  std::size_t leaves_ = 0;
  std::size_t changes_ = 0;
  double built_cost_ = 0;
  std::vector<std::int32_t> fresh_;  // leaves marked fresh since the last fresh_pairs
};

}  // namespace impact
