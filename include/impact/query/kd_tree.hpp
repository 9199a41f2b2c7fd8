// SPDX-License-Identifier: MIT
/// \file
/// KdTree<S>: a kd-tree over a triangle mesh (an axis-aligned binary space partition), with ray and
/// segment casts (first hit) and closest point.
///
/// Construction (Wald and Havran 2006, "On building fast kd-trees for ray tracing", binned): a
/// cell is split by the axis-aligned plane of least surface-area cost among KdTreeConfig::bins
/// candidate planes per axis, cost = traversal + intersection * (area(left) / area(cell) *
/// n_left + area(right) / area(cell) * n_right); a cell becomes a leaf when no plane is cheaper
/// than testing its triangles. A triangle is referenced from every cell its bounding box (clipped
/// to the cell) overlaps, closed: a triangle touching a plane is in both cells. Depth and memory
/// are bounded on any input: depth at most max_depth (default 8 + 1.3 log2 n, as PBRT), triangle
/// references at most max_references_per_triangle * n (beyond that cells become leaves), and a
/// split must leave fewer triangles on each side than in the cell, so coincident triangles make
/// one leaf instead of a deep chain. In a leaf of more than leaf_size triangles the references are
/// sorted by their triangles' vertices, and a triangle equal to the one before it (the same three
/// points in the same order: coincident copies) is marked and skipped by both queries, which it
/// would give exactly the same answer (as MeshBvh::repeats_previous).
///
/// Numerical contract. Rays: the first hit is the smallest t among the triangles hit by the
/// library's triangle rule (detail::ray_mesh_triangle_hit of query/ray_mesh.hpp: the watertight
/// test, t raised to the triangle's box entry, the tie rule at t = 0), the same t the BVH casts
/// return; each cell's parameter interval is widened by a bound of its rounding, so a hit on a
/// splitting plane is never lost. It lives in query/ beside the casts whose rule it shares (as
/// DistanceGrid does). Closest point: the nearest triangle's point by the narrow phase's
/// closest_point_on_triangle, its squared distance by the BVH queries' rule (raised to the
/// distance to the triangle's box when rounding put it below); cells are skipped only when their
/// (rounded) squared distance exceeds the best by more than a bound of that rounding, so the
/// result is the minimum over all triangles, as a brute force computes it, and the BVH's.
///
/// Thread safety: construction writes; every const member (first_hit, closest_point, stats) only
/// reads: any number of threads may query one tree at once.
#pragma once

#include "impact/core/error.hpp"
#include "impact/core/validate.hpp"
#include "impact/geometry/aabb.hpp"
#include "impact/geometry/ray.hpp"
#include "impact/geometry/triangle_mesh.hpp"
#include "impact/narrow/closest_point.hpp"
#include "impact/narrow/ray_triangle.hpp"
#include "impact/query/closest_point_mesh.hpp"
#include "impact/query/ray_mesh.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <deque>
#include <limits>
#include <optional>
#include <vector>

namespace impact {

/// Knobs of the kd-tree build, with their defaults.
struct KdTreeConfig {
  int bins = 32;                       ///< candidate planes per axis and cell, in [2, 256]
  double traversal_cost = 1.0;         ///< cost of stepping through an inner node (> 0)
  double intersection_cost = 1.5;      ///< cost of one ray-triangle test (> 0)
  int max_depth = 0;                   ///< 0: 8 + 1.3 log2 n; else in [1, 64]
  double max_references_per_triangle = 8.0;  ///< memory bound, >= 1
  int leaf_size = 1;                   ///< cells of at most this many triangles are leaves (>= 1)
};

/// Counters of one query, for benchmarks: cells visited, and triangles tested (for the closest
/// point, those whose box was near enough to need the narrow phase's closest point).
struct KdTreeStats {
  std::size_t node_visits = 0, triangle_tests = 0;
};

template <class S> struct KdRayHit {
  S t = S(0);                              ///< the hit point is origin + t * direction
  std::int32_t triangle = -1;              ///< row of F
  Vec3<S> point = Vec3<S>::Zero();
  Vec3<S> barycentric = Vec3<S>::Zero();   ///< weights of the triangle's a, b, c
  bool front_face = true;                  ///< the ray came from the side the wound normal points to
};

template <class S> struct KdClosestPoint {
  Vec3<S> point = Vec3<S>::Zero();
  std::int32_t triangle = -1;
  S distance = S(0);
};

template <class S> class KdTree {
 public:
  /// One node: inner nodes split `axis` at `split`, their children at `child` (below) and
  /// child + 1 (above); leaves (axis == 3) hold refs[first, first + count).
  struct Node {
    S split = S(0);
    std::int32_t child_or_first = 0;
    std::int32_t count = 0;
    std::int8_t axis = 3;
    bool is_leaf() const { return axis == 3; }
  };

  /// Validates and copies the mesh, then builds. Throws InvalidInput on a bad mesh (empty,
  /// NaN/Inf, indices out of range) or a config outside its documented ranges.
  explicit KdTree(const TriangleMesh<S>& mesh, const KdTreeConfig& cfg = {}) : mesh_(mesh), cfg_(cfg) {
    validate_mesh(mesh_);
    const char* where = "KdTree";
    require(cfg.bins >= 2 && cfg.bins <= 256, where, "config.bins must be in [2, 256]");
    require(cfg.traversal_cost > 0 && cfg.intersection_cost > 0 && std::isfinite(cfg.traversal_cost) && std::isfinite(cfg.intersection_cost),
            where, "config costs must be finite and > 0");
    require(cfg.max_depth >= 0 && cfg.max_depth <= 64, where, "config.max_depth must be in [0, 64]");
    require(cfg.max_references_per_triangle >= 1 && cfg.max_references_per_triangle <= 1e6, where,
            "config.max_references_per_triangle must be in [1, 1e6]");
    require(cfg.leaf_size >= 1, where, "config.leaf_size must be >= 1");
    build();
  }

  const std::vector<Node>& nodes() const { return nodes_; }
  const std::vector<std::int32_t>& references() const { return refs_; }
  const Aabb<S>& bounds() const { return root_box_; }
  const TriangleMesh<S>& mesh() const { return mesh_; }
  /// Heap bytes beyond the copied mesh: nodes and triangle references (capacities), and the marks
  /// of repeated triangles (only when some leaf holds copies).
  std::size_t memory_bytes() const {
    return nodes_.capacity() * sizeof(Node) + refs_.capacity() * sizeof(std::int32_t) + repeats_.capacity() / 8;
  }
  /// True when reference k's triangle has exactly the vertices of reference k - 1's, in the same
  /// order, within one leaf (a query that has just tested k - 1 may skip k).
  bool repeats_previous(std::int32_t k) const { return !repeats_.empty() && repeats_[static_cast<std::size_t>(k)]; }
  /// Depth of the deepest leaf (the root has depth 0).
  int depth() const { return depth_; }

  /// First hit of origin + t * direction, t in [0, ray.t_max] (a segment p -> q is the ray (p,
  /// q - p, 1)); nothing on a miss. Throws InvalidInput for an invalid ray (validate_ray).
  std::optional<KdRayHit<S>> first_hit(const Ray<S>& ray, KdTreeStats* stats = nullptr) const {
    validate_ray(ray, "KdTree::first_hit");
    const Vec3<S>& o = ray.origin;
    const Vec3<S>& d = ray.direction;
    PreparedRay<S> pr(ray);
    pr.bound_band(root_box_.min, root_box_.max);  // every triangle lies in the root box: the per-ray band bound
    const S scale = (o.cwiseAbs().maxCoeff() + root_box_.min.cwiseAbs().cwiseMax(root_box_.max.cwiseAbs()).maxCoeff()) /
                    d.cwiseAbs().maxCoeff();
    // the root box: entry and exit, widened
    S t0 = S(0), t1 = ray.t_max;
    Vec3<S> inv;
    for (int k = 0; k < 3; ++k) {
      inv[k] = S(1) / d[k];
      if (d[k] == S(0)) {
        if (o[k] < root_box_.min[k] || o[k] > root_box_.max[k]) return std::nullopt;
        continue;
      }
      S a = (root_box_.min[k] - o[k]) * inv[k], b = (root_box_.max[k] - o[k]) * inv[k];
      if (a > b) std::swap(a, b);
      a -= pad(a, scale), b += pad(b, scale);
      t0 = std::max(t0, a);
      t1 = std::min(t1, b);
    }
    if (!(t0 <= t1)) return std::nullopt;
    const Vec3<S> inv_safe = detail::safe_inverse(d);
    S best = ray.t_max;
    std::int32_t best_tri = -1;
    RayTriangleHit<S> best_hit;
    struct Item {
      std::int32_t node;
      S t0, t1;
    };
    Item stack[130];
    int top = 0;
    stack[top++] = {0, t0, t1};
    while (top > 0) {
      Item it = stack[--top];
      if (best_tri >= 0 && it.t0 > best + pad(best, scale)) continue;  // the cell starts after the best hit
      while (!nodes_[static_cast<std::size_t>(it.node)].is_leaf()) {
        const Node& n = nodes_[static_cast<std::size_t>(it.node)];
        if (stats) ++stats->node_visits;
        const int a = n.axis;
        const std::int32_t below = n.child_or_first, above = below + 1;
        if (d[a] == S(0)) {  // parallel to the plane: the side(s) holding the origin
          if (o[a] < n.split) it.node = below;
          else if (o[a] > n.split) it.node = above;
          else {
            stack[top++] = {above, it.t0, it.t1};
            it.node = below;
          }
          continue;
        }
        const S ts = (n.split - o[a]) * inv[a];
        const S lo = ts - pad(ts, scale), hi = ts + pad(ts, scale);
        // near side: the one the ray is in before it crosses the plane at ts (a ray starting on
        // the plane crosses it at ts = 0, coming from the side opposite its direction)
        const bool below_first = o[a] < n.split || (o[a] == n.split && d[a] > S(0));
        const std::int32_t near = below_first ? below : above, far = below_first ? above : below;
        if (lo > it.t1 || hi < S(0)) {
          it.node = near;  // the plane is crossed after the cell (or behind the origin)
        } else if (hi < it.t0) {
          it.node = far;  // crossed before the cell
        } else {
          stack[top++] = {far, std::max(it.t0, lo), it.t1};
          it.node = near;
          it.t1 = std::min(it.t1, hi);
        }
      }
      const Node& leaf = nodes_[static_cast<std::size_t>(it.node)];
      if (stats) ++stats->node_visits;
      for (std::int32_t k = leaf.child_or_first; k < leaf.child_or_first + leaf.count; ++k) {
        if (repeats_previous(k)) continue;  // the triangle just tested, again
        const std::int32_t t = refs_[static_cast<std::size_t>(k)];
        if (stats) ++stats->triangle_tests;
        pr.ray.t_max = best;
        const auto h = detail::ray_mesh_triangle_hit(pr, inv_safe, mesh_.triangle(t));
        if (h && (best_tri < 0 || h->t < best)) {
          best = h->t;
          best_tri = t;
          best_hit = *h;
        }
      }
      // hits beyond this cell may still be beaten by a later cell: the pop test prunes them
    }
    if (best_tri < 0) return std::nullopt;
    KdRayHit<S> r;
    r.t = best;
    r.triangle = best_tri;
    r.point = o + best * d;
    r.barycentric = Vec3<S>(best_hit.u, best_hit.v, best_hit.w);
    r.front_face = best_hit.front;
    return r;
  }

  /// Closest point of the mesh to p (nothing only when max_distance is exceeded). Throws
  /// InvalidInput for a point that is not finite or beyond CoordinateRange.
  ///
  /// A triangle's squared distance is the BVH queries' (detail::triangle_squared_distance of
  /// query/closest_point_mesh.hpp: the narrow phase's, raised to the distance to the triangle's
  /// box when rounding put it below), so the answer equals closest_point_on_mesh's distance. Each
  /// referenced triangle is first culled by the distance to its box (exact: its value is never
  /// below that), and a triangle met again in another cell is skipped (a 32-entry cache of the ids
  /// tested by this query); the traversal stack lives on the call stack (no allocation).
  std::optional<KdClosestPoint<S>> closest_point(const Vec3<S>& p, KdTreeStats* stats = nullptr,
                                                 S max_distance = std::numeric_limits<S>::infinity()) const {
    validate_coordinates(p, "KdTree::closest_point", "p");
    validate_nonnegative_or_inf(max_distance, "KdTree::closest_point", "max_distance");
    S best = max_distance < std::numeric_limits<S>::infinity() ? max_distance * max_distance : std::numeric_limits<S>::infinity();
    std::int32_t best_tri = -1;
    Vec3<S> best_point = Vec3<S>::Zero();
    struct Item {
      std::int32_t node;
      S d2;
      Aabb<S> box;
    };
    Item stack[2 * 64 + 4];  // depth <= 64: at most one pending sibling per level
    int top = 0;
    stack[top++] = {0, box_distance2(p, root_box_), root_box_};
    std::int32_t seen[32];
    std::fill(std::begin(seen), std::end(seen), -1);
    const S slack = S(1) + S(64) * std::numeric_limits<S>::epsilon();
    while (top > 0) {
      const Item it = stack[--top];
      if (it.d2 > best * slack) continue;
      const Node& n = nodes_[static_cast<std::size_t>(it.node)];
      if (stats) ++stats->node_visits;
      if (n.is_leaf()) {
        for (std::int32_t k = n.child_or_first; k < n.child_or_first + n.count; ++k) {
          if (repeats_previous(k)) continue;  // the same distance as the triangle just tested
          const std::int32_t t = refs_[static_cast<std::size_t>(k)];
          std::int32_t& slot = seen[static_cast<std::uint32_t>(t) & 31u];
          if (slot == t) continue;
          slot = t;
          const Triangle<S> tri = mesh_.triangle(t);
          const S box = detail::squared_distance_to_bv(p, Aabb<S>(tri.a.cwiseMin(tri.b).cwiseMin(tri.c), tri.a.cwiseMax(tri.b).cwiseMax(tri.c)));
          if (box > best || (best_tri >= 0 && box == best)) continue;  // its value is >= box: it cannot win
          if (stats) ++stats->triangle_tests;
          const TrianglePoint<S> tp = detail::closest_on_triangle(p, tri);
          const S d2 = detail::triangle_squared_distance(p, tri, tp);
          if (d2 < best || (best_tri < 0 && d2 <= best)) best = d2, best_tri = t, best_point = tp.point;
        }
        continue;
      }
      Aabb<S> lo = it.box, hi = it.box;
      lo.max[n.axis] = n.split;
      hi.min[n.axis] = n.split;
      Item a{n.child_or_first, box_distance2(p, lo), lo}, b{n.child_or_first + 1, box_distance2(p, hi), hi};
      if (a.d2 < b.d2) std::swap(a, b);  // nearer on top
      if (a.d2 <= best * slack) stack[top++] = a;
      if (b.d2 <= best * slack) stack[top++] = b;
    }
    if (best_tri < 0) return std::nullopt;
    return KdClosestPoint<S>{best_point, best_tri, std::sqrt(best)};
  }

 private:
  /// A bound of the rounding of a cell parameter t and of a triangle's hit parameter: 64 ulps of
  /// |t| plus the ray's scale (the coordinates involved over the direction's size).
  static S pad(S t, S scale) { return S(64) * std::numeric_limits<S>::epsilon() * (std::abs(t) + scale); }

  static S box_distance2(const Vec3<S>& p, const Aabb<S>& b) { return (p - p.cwiseMax(b.min).cwiseMin(b.max)).squaredNorm(); }

  void build() {
    const auto n = static_cast<std::int32_t>(mesh_.F.rows());
    std::vector<Aabb<S>> tri_box(static_cast<std::size_t>(n));
    for (std::int32_t t = 0; t < n; ++t) {
      const Triangle<S> tri = mesh_.triangle(t);
      tri_box[static_cast<std::size_t>(t)] = Aabb<S>(tri.a.cwiseMin(tri.b).cwiseMin(tri.c), tri.a.cwiseMax(tri.b).cwiseMax(tri.c));
      root_box_.extend(tri_box[static_cast<std::size_t>(t)]);
    }
    const int max_depth = cfg_.max_depth > 0 ? cfg_.max_depth : static_cast<int>(8 + 1.3 * std::log2(double(std::max(n, 1))));
    const double max_refs = cfg_.max_references_per_triangle * double(n) + 64;
    nodes_.clear();
    refs_.clear();
    nodes_.push_back({});
    struct Job {
      std::int32_t node;
      Aabb<S> box;
      std::vector<std::int32_t> tris;
      int depth;
    };
    std::deque<Job> jobs;  // breadth first: when the reference budget runs out, it runs out level by level
    {
      Job root{0, root_box_, std::vector<std::int32_t>(static_cast<std::size_t>(n)), 0};
      for (std::int32_t t = 0; t < n; ++t) root.tris[static_cast<std::size_t>(t)] = t;
      jobs.push_back(std::move(root));
    }
    double refs_total = n;
    depth_ = 0;
    const int bins = cfg_.bins;
    std::vector<std::int32_t> starts(static_cast<std::size_t>(bins)), ends(static_cast<std::size_t>(bins));
    while (!jobs.empty()) {
      Job job = std::move(jobs.front());
      jobs.pop_front();
      depth_ = std::max(depth_, job.depth);
      const auto count = static_cast<std::int32_t>(job.tris.size());
      const auto make_leaf = [&]() {
        Node& leaf = nodes_[static_cast<std::size_t>(job.node)];
        leaf.axis = 3;
        leaf.child_or_first = static_cast<std::int32_t>(refs_.size());
        leaf.count = count;
        if (count > cfg_.leaf_size) mark_copies(job.tris, refs_.size());
        refs_.insert(refs_.end(), job.tris.begin(), job.tris.end());
      };
      if (count <= cfg_.leaf_size || job.depth >= max_depth || refs_total >= max_refs) {
        make_leaf();
        continue;
      }
      // binned SAH over the clipped boxes
      const S area = half_area(job.box);
      double best_cost = cfg_.intersection_cost * double(count);
      int best_axis = -1;
      S best_split = S(0);
      for (int axis = 0; axis < 3; ++axis) {
        const S lo = job.box.min[axis], ext = job.box.max[axis] - lo;
        if (!(ext > S(0))) continue;
        std::fill(starts.begin(), starts.end(), 0);
        std::fill(ends.begin(), ends.end(), 0);
        const S scale = S(bins) / ext;
        auto bin_of = [&](S x) { return std::clamp(static_cast<int>((x - lo) * scale), 0, bins - 1); };
        for (std::int32_t t : job.tris) {
          const Aabb<S>& b = tri_box[static_cast<std::size_t>(t)];
          ++starts[static_cast<std::size_t>(bin_of(std::max(b.min[axis], lo)))];
          ++ends[static_cast<std::size_t>(bin_of(std::min(b.max[axis], job.box.max[axis])))];
        }
        // plane between bin i - 1 and bin i: left holds the boxes starting in bins < i, right
        // those ending in bins >= i (approximate counts: the partition below is exact)
        std::int32_t left = 0, right = count;
        for (int i = 1; i < bins; ++i) {
          left += starts[static_cast<std::size_t>(i - 1)];
          right -= ends[static_cast<std::size_t>(i - 1)];
          if (left == count && right == count) continue;
          const S split = lo + ext * S(i) / S(bins);
          Aabb<S> bl = job.box, br = job.box;
          bl.max[axis] = split;
          br.min[axis] = split;
          const double cost = cfg_.traversal_cost + cfg_.intersection_cost * (double(half_area(bl)) * left + double(half_area(br)) * right) /
                                                        double(area > S(0) ? area : S(1));
          if (cost < best_cost) best_cost = cost, best_axis = axis, best_split = split;
        }
      }
      if (best_axis < 0) {
        make_leaf();
        continue;
      }
      Job below{0, job.box, {}, job.depth + 1}, above{0, job.box, {}, job.depth + 1};
      below.box.max[best_axis] = best_split;
      above.box.min[best_axis] = best_split;
      for (std::int32_t t : job.tris) {  // closed: a box touching the plane goes to both sides
        const Aabb<S>& b = tri_box[static_cast<std::size_t>(t)];
        if (b.min[best_axis] <= best_split) below.tris.push_back(t);
        if (b.max[best_axis] >= best_split) above.tris.push_back(t);
      }
      if (static_cast<std::int32_t>(below.tris.size()) == count || static_cast<std::int32_t>(above.tris.size()) == count) {
        // no progress on one side (the binned counts were approximate): stop here if neither
        // side shrank, else still split (the other side shrank)
        if (static_cast<std::int32_t>(below.tris.size()) == count && static_cast<std::int32_t>(above.tris.size()) == count) {
          make_leaf();
          continue;
        }
      }
      refs_total += double(below.tris.size() + above.tris.size()) - double(count);
      const auto child = static_cast<std::int32_t>(nodes_.size());
      nodes_.push_back({});
      nodes_.push_back({});
      Node& inner = nodes_[static_cast<std::size_t>(job.node)];
      inner.axis = static_cast<std::int8_t>(best_axis);
      inner.split = best_split;
      inner.child_or_first = child;
      inner.count = 0;
      below.node = child;
      above.node = child + 1;
      jobs.push_back(std::move(below));
      jobs.push_back(std::move(above));
    }
    nodes_.shrink_to_fit();
    refs_.shrink_to_fit();
    if (!repeats_.empty()) repeats_.resize(refs_.size(), false);
  }

  /// Sorts the triangles of a large leaf (whose references will start at `at`) by their
  /// vertices, then by id, so copies are adjacent, and marks each copy of the one before it.
  void mark_copies(std::vector<std::int32_t>& tris, std::size_t at) {
    using Key = std::array<S, 9>;
    const auto key = [&](std::int32_t t) {
      const Triangle<S> x = mesh_.triangle(t);
      return Key{x.a.x(), x.a.y(), x.a.z(), x.b.x(), x.b.y(), x.b.z(), x.c.x(), x.c.y(), x.c.z()};
    };
    std::vector<std::pair<Key, std::int32_t>> keyed(tris.size());
    for (std::size_t j = 0; j < tris.size(); ++j) keyed[j] = {key(tris[j]), tris[j]};
    std::sort(keyed.begin(), keyed.end());
    for (std::size_t j = 0; j < tris.size(); ++j) {
      tris[j] = keyed[j].second;
      if (j == 0 || keyed[j].first != keyed[j - 1].first) continue;
      if (repeats_.size() < at + tris.size()) repeats_.resize(at + tris.size(), false);
      repeats_[at + j] = true;
    }
  }

  static S half_area(const Aabb<S>& b) {
    const Vec3<S> e = b.max - b.min;
    return e[0] * e[1] + e[1] * e[2] + e[2] * e[0];
  }

  TriangleMesh<S> mesh_;
  KdTreeConfig cfg_;
  std::vector<Node> nodes_;
  std::vector<std::int32_t> refs_;
  std::vector<bool> repeats_;  // repeats_previous() by reference; empty when no leaf holds copies
  Aabb<S> root_box_;
  int depth_ = 0;
};

}  // namespace impact
