// SPDX-License-Identifier: MIT
/// \file
/// DistanceGrid: conservative lower bounds of the (unsigned) distance from any point to a triangle
/// mesh, from a regular grid of samples taken once. Each cell stores a lower bound of the distance
/// from its centre c to the mesh; since the distance is 1-Lipschitz, dist(p) >= value(c) - |p - c|
/// for every point p and every cell, so one array read answers "how far is the surface at least"
/// in O(1), where a tree query costs O(log n) cache misses. Made for clearance tests such as the
/// particle free ball (response/detail/free_ball.hpp), which skip exact queries for anything that
/// provably stays away from the surface.
///
/// Numerical contract: conservative. The samples are closest_point_on_mesh distances, shrunk by
/// 64 ulps relative plus 64 ulps of the scene's size (more than the query's rounding) and rounded
/// down to 8-bit multiples of a quantum, the smaller of (largest sample / 255) and
/// (cell size / 16), so a cell's bound takes one byte and the bounds stay in cache; samples beyond
/// 255 quanta (16 cells) store 255 quanta, still a valid bound. lower_bound() shrinks its own
/// rounding the same way. Outside the mesh's bounding box the distance to that box is a bound
/// too, and lower_bound() takes the larger of the two. The bound is never above the true
/// distance; it is below it by at most about the cell's half diagonal plus a quantum and the
/// margins for points inside the grid (and nearer than 16 cells), and is 0 (useless, still
/// valid) where the mesh passes. The mesh must not move or deform relative to the frame the grid
/// was built in (rebuild it).
///
/// Start nodes (optional, DistanceGridConfig::start_node_reach > 0): each cell also keeps, for the
/// triangles whose bounding boxes meet the cell grown by the reach (its patch), the deepest node
/// of the mesh's tree whose subtree holds them all (or a mark that there is none) and a slab
/// lo <= n . x <= hi that holds them (n their area-weighted mean normal). start_node(o, e) looks
/// at the segment's midpoint cell when the segment's (padded) box lies in that grown cell (always
/// when the segment spans at most twice the reach along each axis): when both ends are beyond the
/// same side of the slab (by more than the casts' rounding) the segment can meet no triangle;
/// else a ray cast can start at the node and skip the top of the tree. This rules out most of the
/// short segments that pass near a smooth surface without crossing it, which the distance bounds
/// (no tighter than a cell) cannot clear. Exact: the skipped triangles cannot meet the segment's
/// box, and the patch's triangles lie in the slab, which the segment (convex) does not meet.
/// Segments whose box misses the mesh's box meet nothing either.
///
/// Thread safety: immutable after construction; every query is const and may run from any number
/// of threads at once (the particles' parallel step does). The mesh tree it was built from must
/// not be edited (set_vertices) while the grid is in use; rebuild the grid after such an edit.
#pragma once

#include "impact/bvh/compact_bvh.hpp"
#include "impact/bvh/mesh_bvh.hpp"
#include "impact/core/validate.hpp"
#include "impact/core/parallel.hpp"
#include "impact/query/closest_point_mesh.hpp"
#include "impact/query/ray_mesh.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <vector>

namespace impact {

/// Options of a DistanceGrid.
template <class S>
struct DistanceGridConfig {
  /// Cells along the longest side of the mesh's bounding box, in [1, kMaxResolution]; memory is
  /// about 17 * resolution^3 * (the box's volume / the longest side's cube) bytes (1 without start
  /// nodes) once built, plus sizeof(S) a cell during the build. The grid's whole count of cells
  /// (padding included) must not exceed kMaxCells.
  int resolution = 64;
  /// Cells added around the mesh's bounding box on every side, in [0, kMaxPadding]: tighter
  /// bounds just outside.
  int padding = 2;
  /// Samples farther than this from the mesh store this value (a valid lower bound); bounding the
  /// build's closest-point queries makes it faster. >= 0; infinity: exact samples everywhere.
  S max_distance = std::numeric_limits<S>::infinity();
  /// Start nodes and slabs for segments of up to this many cells around their midpoint's cell,
  /// in [0, kMaxReach]; 0: none.
  S start_node_reach = S(1);
  /// Threads of the build (<= 0: the hardware concurrency, 1: serial); the grid is the same, bit
  /// for bit, for every count (each cell is computed on its own).
  int threads = 0;

  static constexpr int kMaxResolution = 4096;
  static constexpr int kMaxPadding = 1024;
  static constexpr int kMaxReach = 64;
  /// 2^27 cells: 2.1 GiB of start nodes and slabs, 128 MiB of bounds.
  static constexpr std::int64_t kMaxCells = std::int64_t(1) << 27;
};

/// Conservative distance bounds to a mesh in the mesh's own (local) frame. See the file comment.
/// Build cost: one bounded closest-point query and one box query per cell; memory 17 bytes per
/// cell (1 for the bound, 16 for the start node and the slab).
template <class S>
class DistanceGrid {
 public:
  DistanceGrid() = default;

  /// Samples the distance to `mesh` (its local frame) on a grid over its bounding box. Throws
  /// InvalidInput, before allocating anything, for a config outside the ranges its fields state.
  template <class BV>
  explicit DistanceGrid(const MeshBvh<BV>& mesh, const DistanceGridConfig<S>& cfg = {}) {
    static_assert(std::is_same_v<typename BvTraits<BV>::Scalar, S>, "DistanceGrid: scalar of the mesh");
    Aabb<S> box;
    const auto& V = mesh.mesh().V;
    for (Eigen::Index i = 0; i < V.rows(); ++i) box.extend(Vec3<S>(V.row(i).transpose()));
    constexpr const char* where = "DistanceGrid";
    using Cfg = DistanceGridConfig<S>;
    validate_in_range(cfg.resolution, 1, Cfg::kMaxResolution, where, "config.resolution");
    validate_in_range(cfg.padding, 0, Cfg::kMaxPadding, where, "config.padding");
    validate_nonnegative_or_inf(cfg.max_distance, where, "config.max_distance");
    validate_nonnegative(cfg.start_node_reach, where, "config.start_node_reach");
    require(cfg.start_node_reach <= S(Cfg::kMaxReach), where, "config.start_node_reach must be at most 64 cells");
    const int res = cfg.resolution, pad = cfg.padding;
    const Vec3<S> ext = box.extent();
    const S h = std::max(ext.maxCoeff() / S(res), std::numeric_limits<S>::min() * S(1e6));
    int n[3];
    std::int64_t total = 1;
    for (int k = 0; k < 3; ++k) {
      // ext[k] / h <= res up to rounding: no overflow, counted in 64 bits
      n[k] = std::max(1, static_cast<int>(std::ceil(std::min(ext[k] / h, S(Cfg::kMaxResolution + 1))))) + 2 * pad;
      total *= n[k];
    }
    if (total > Cfg::kMaxCells)
      throw InvalidInput(std::string(where) + ": " + std::to_string(n[0]) + " x " + std::to_string(n[1]) + " x " + std::to_string(n[2]) +
                         " cells (config.resolution and config.padding) exceed the bound of " + std::to_string(Cfg::kMaxCells));
    box_ = box;
    size_ = box.min.cwiseAbs().cwiseMax(box.max.cwiseAbs()).sum();
    h_ = h;
    inv_h_ = S(1) / h_;
    for (int k = 0; k < 3; ++k) {
      n_[k] = n[k];
      origin_[k] = box.center()[k] - S(0.5) * h_ * S(n_[k]);
    }
    const S eps = std::numeric_limits<S>::epsilon();
    const S scale = box.min.cwiseAbs().cwiseMax(box.max.cwiseAbs()).maxCoeff() + S(2 * pad) * h_;
    const std::size_t cells = static_cast<std::size_t>(n_[0]) * static_cast<std::size_t>(n_[1]) * static_cast<std::size_t>(n_[2]);
    std::vector<S> dist(cells);
    reach_ = cfg.start_node_reach > S(0) ? cfg.start_node_reach * h_ : S(0);
    const auto& tree = mesh.tree();
    std::vector<std::pair<std::int32_t, std::int32_t>> range;  // primitive range of each subtree
    if (reach_ > S(0)) range = subtree_ranges(tree), patches_.resize(cells);
    // Coincident triangles (the same three points, in any order) give the same distances and the
    // same slab: when at least a quarter of the triangles are such copies, samples and patches are
    // taken on a tree of one copy of each, and each copy's leaf positions are kept for the start
    // nodes. Otherwise every cell's closest-point and box queries visited every copy (no tree can
    // prune nodes whose contents are all equal): a resolution-8 grid on 20,000 copies of one
    // triangle took 11 s, on 200,000 copies 81 s.
    const Distinct<BV> distinct = distinct_triangles(mesh);
    const MeshBvh<BV>& sample = distinct.tree ? *distinct.tree : mesh;
    const auto* span = distinct.tree ? &distinct.span : nullptr;
    sampled_triangles_ = sample.num_triangles();
    ClosestPointOptions<S> opt;
    opt.max_distance = cfg.max_distance;
    // one row of cells (fixed y, z) per index: each cell's sample and patch depend on that cell only
    const std::size_t rows = static_cast<std::size_t>(n_[1]) * static_cast<std::size_t>(n_[2]);
    parallel_for(rows, rows >= 64 ? cfg.threads : 1, [&](std::size_t row) {
      std::vector<std::int32_t> ids;  // scratch: the triangles near a cell
      const int y = static_cast<int>(row % static_cast<std::size_t>(n_[1])), z = static_cast<int>(row / static_cast<std::size_t>(n_[1]));
      std::size_t idx = row * static_cast<std::size_t>(n_[0]);
      for (int x = 0; x < n_[0]; ++x, ++idx) {
        const Vec3<S> c = center(x, y, z);
        const auto r = detail::closest_point_on_mesh_unchecked(sample, c, RigidTransform<S>(), opt);
        S d = r ? r->distance : cfg.max_distance;
        d = d * (S(1) - S(64) * eps) - S(64) * eps * (c.cwiseAbs().maxCoeff() + scale);
        dist[idx] = d > S(0) ? d : S(0);
        if (reach_ > S(0)) patches_[idx] = patch(mesh, sample, span, range, grown_cell(c, S(4) * eps * scale), ids);
      }
    });
    // 8-bit storage, rounded down: k * quantum <= the sample (checked with the very expression
    // lower_bound() evaluates)
    S top = S(0);
    for (const S d : dist)
      if (d < std::numeric_limits<S>::infinity()) top = std::max(top, d);
    quantum_ = top > S(0) ? std::min(top / S(kLevels), h_ / S(16)) : S(1);
    S centre_scale = S(0);  // the largest |coordinate| of a cell centre
    for (int k = 0; k < 3; ++k)
      centre_scale = std::max({centre_scale, std::abs(center(0, 0, 0)[k]), std::abs(center(n_[0] - 1, n_[1] - 1, n_[2] - 1)[k])});
    margin_ = S(64) * eps * (S(2) * centre_scale + S(kLevels) * quantum_);
    bounds_.resize(cells);
    for (std::size_t k = 0; k < cells; ++k) {
      const S q = std::floor(std::min(dist[k] / quantum_, S(kLevels)));
      auto v = static_cast<std::uint8_t>(q > S(0) ? q : S(0));
      while (v > 0 && S(v) * quantum_ > dist[k]) --v;
      bounds_[k] = v;
    }
  }

  /// A lower bound (>= 0) of the distance from p (mesh frame) to the mesh. O(1): one read.
  S lower_bound(const Vec3<S>& p) const {
    if (bounds_.empty()) return S(0);
    int i[3];
    cell_of(p, i);  // any cell gives a valid bound
    const S v = S(bounds_[index(i[0], i[1], i[2])]) * quantum_;
    const Vec3<S> c = center(i[0], i[1], i[2]);
    // rounding: 64 ulps of |p|_inf + |c|_inf, bounded once for all points that get a positive
    // bound (then |p - c| < v, so |p|_inf + |c|_inf <= 2 max|c|_inf + max v: margin_)
    const S shrink = S(1) - S(64) * std::numeric_limits<S>::epsilon();
    S b = (v - (p - c).norm()) * shrink - margin_;
    if (!box_.contains(p)) {
      // the distance to the mesh's box: each difference is rounded once, the norm within a few
      // ulps relative
      const Vec3<S> q = p.cwiseMax(box_.min).cwiseMin(box_.max);
      b = std::max(b, (p - q).norm() * shrink);
    }
    return b > S(0) ? b : S(0);
  }

  /// The centre of the cell whose value lower_bound(p) reads (p clamped into the grid; p itself
  /// when the grid is empty). The bound there is that value less the margins, and the ball it
  /// gives holds the ball lower_bound(p) gives around any point of the cell.
  Vec3<S> cell_center(const Vec3<S>& p) const {
    S unused;
    return cell_bound(p, unused);
  }
  /// cell_center(p), with `bound` set to a lower bound (>= 0) of the distance from that centre to
  /// the mesh: lower_bound() there without its distance to the cell's centre (0) nor to the
  /// mesh's box (never larger). O(1): one read, no square root. The empty grid gives p and 0.
  Vec3<S> cell_bound(const Vec3<S>& p, S& bound) const {
    bound = S(0);
    if (bounds_.empty()) return p;
    int i[3];
    cell_of(p, i);
    const S b = S(bounds_[index(i[0], i[1], i[2])]) * quantum_ * (S(1) - S(64) * std::numeric_limits<S>::epsilon()) - margin_;
    bound = b > S(0) ? b : S(0);
    return center(i[0], i[1], i[2]);
  }

  /// The node of the mesh's tree to start a ray cast along the segment o -> e from (mesh frame):
  /// every triangle whose box meets the segment's box (padded as ray_mesh_first_hit pads it) is
  /// in its subtree. kNoTriangle when no triangle can meet the segment (its box misses the
  /// mesh's box, no triangle's box meets the grown cell, or the segment passes beside the cell's
  /// slab); else 0 (the root) when the segment leaves the reach of its midpoint's cell or start
  /// nodes are off. O(1).
  std::int32_t start_node(const Vec3<S>& o, const Vec3<S>& e) const {
    if (bounds_.empty()) return 0;
    const S pad = S(4) * std::numeric_limits<S>::epsilon() * (o.cwiseAbs().maxCoeff() + e.cwiseAbs().maxCoeff());
    const Vec3<S> lo = o.cwiseMin(e).array() - pad, hi = o.cwiseMax(e).array() + pad;
    if ((lo.array() > box_.max.array()).any() || (hi.array() < box_.min.array()).any()) return kNoTriangle;
    if (patches_.empty()) return 0;
    int i[3];
    cell_of(Vec3<S>((o + e) / S(2)), i);
    const Aabb<S> q = grown_cell(center(i[0], i[1], i[2]), S(0));
    if (!((lo.array() >= q.min.array()).all() && (hi.array() <= q.max.array()).all())) return 0;
    const Patch& c = patches_[index(i[0], i[1], i[2])];
    // both ends beyond the same side of the slab (by more than the casts' rounding): the segment
    // is, and it cannot meet the triangles of the grown cell, which are in the slab
    const Vec3<S> n = c.normal();
    const S so = n.dot(o), se = n.dot(e);
    const S m = S(256) * std::numeric_limits<S>::epsilon() * (o.cwiseAbs().sum() + e.cwiseAbs().sum() + size_);
    if (std::min(so, se) > S(c.hi) + m || std::max(so, se) < S(c.lo) - m) return kNoTriangle;
    return c.node;
  }
  /// start_node() when no triangle can be met.
  static constexpr std::int32_t kNoTriangle = -1;

  bool empty() const { return bounds_.empty(); }
  /// Triangles the build sampled: the mesh's count, or the count of distinct triangles when at
  /// least a quarter of them were coincident copies of others (the same three points).
  std::int32_t sampled_triangles() const { return sampled_triangles_; }
  /// Edge length of the (cubic) cells.
  S cell_size() const { return h_; }
  /// Cells along x, y, z.
  Eigen::Vector3i dims() const { return {n_[0], n_[1], n_[2]}; }
  /// Centre of cell (x, y, z), computed the same way by the build and by lower_bound().
  Vec3<S> center(int x, int y, int z) const {
    return {origin_[0] + (S(x) + S(0.5)) * h_, origin_[1] + (S(y) + S(0.5)) * h_, origin_[2] + (S(z) + S(0.5)) * h_};
  }
  /// The stored bound at the centre of cell (x, y, z).
  S value(int x, int y, int z) const { return S(bounds_[index(x, y, z)]) * quantum_; }
  std::size_t memory_bytes() const { return bounds_.size() * sizeof(bounds_[0]) + patches_.size() * sizeof(Patch); }

 private:
  static constexpr int kLevels = 255;  // the largest stored bound, in quanta
  /// What a cell knows of the triangles whose boxes meet it grown by the reach: the deepest node
  /// holding them all (or kNoTriangle), and a slab lo <= n . x <= hi holding them (lo = -inf,
  /// hi = inf when there is none).
  struct Patch {
    std::int32_t node = 0;
    std::int16_t n[2] = {0, 0};  // the slab's normal, octahedral (normal())
    float lo = -std::numeric_limits<float>::infinity(), hi = std::numeric_limits<float>::infinity();

    /// The slab's normal (not unit: the build computes lo and hi with this very vector).
    Vec3<S> normal() const {
      const S u = S(n[0]) / S(32767), v = S(n[1]) / S(32767), w = S(1) - std::abs(u) - std::abs(v);
      if (w >= S(0)) return {u, v, w};
      return {std::copysign(S(1) - std::abs(v), u), std::copysign(S(1) - std::abs(u), v), w};
    }
    /// Stores the octahedral code of the unit vector m.
    void set_normal(const Vec3<S>& m) {
      const S l1 = std::abs(m[0]) + std::abs(m[1]) + std::abs(m[2]);
      S u = m[0] / l1, v = m[1] / l1;
      if (m[2] < S(0)) {
        const S fu = std::copysign(S(1) - std::abs(v), u), fv = std::copysign(S(1) - std::abs(u), v);
        u = fu, v = fv;
      }
      n[0] = static_cast<std::int16_t>(std::lround(std::clamp(u, S(-1), S(1)) * S(32767)));
      n[1] = static_cast<std::int16_t>(std::lround(std::clamp(v, S(-1), S(1)) * S(32767)));
    }
  };
  static_assert(sizeof(Patch) == 16, "DistanceGrid: a patch is 16 bytes");

  std::size_t index(int x, int y, int z) const {
    return (static_cast<std::size_t>(z) * static_cast<std::size_t>(n_[1]) + static_cast<std::size_t>(y)) *
               static_cast<std::size_t>(n_[0]) +
           static_cast<std::size_t>(x);
  }
  void cell_of(const Vec3<S>& p, int* i) const {
    for (int k = 0; k < 3; ++k) {
      const S u = (p[k] - origin_[k]) * inv_h_;  // clamped into the grid
      i[k] = u >= S(n_[k] - 1) ? n_[k] - 1 : (u >= S(1) ? static_cast<int>(u) : 0);
    }
  }
  /// The cell around centre c grown by the reach, and by `extra` more (the build's safety margin).
  Aabb<S> grown_cell(const Vec3<S>& c, S extra) const {
    const S g = S(0.5) * h_ + reach_ + extra;
    return {c.array() - g, c.array() + g};
  }
  template <class BV>
  static std::vector<std::pair<std::int32_t, std::int32_t>> subtree_ranges(const Bvh<BV>& tree) {
    std::vector<std::pair<std::int32_t, std::int32_t>> r(tree.nodes.size());
    for (std::size_t j = tree.nodes.size(); j-- > 0;) {  // children come after their parent
      const auto& n = tree.nodes[j];
      if (n.is_leaf())
        r[j] = {n.first, n.first + n.count - 1};
      else
        r[j] = {r[static_cast<std::size_t>(n.left())].first, r[static_cast<std::size_t>(n.right())].second};
    }
    return r;
  }
  /// The mesh's distinct triangles when at least a quarter of them are coincident copies (looked
  /// for only when at least an eighth are copies of their neighbour in leaf order): a tree
  /// of one copy of each (the first in leaf order, its vertex order kept) and, for each of its
  /// triangles (by row), the first and last leaf positions of its copies in the mesh's tree.
  template <class BV> struct Distinct {
    std::optional<MeshBvh<BV>> tree;
    std::vector<std::pair<std::int32_t, std::int32_t>> span;  // by the distinct tree's leaf position
  };
  template <class BV> static Distinct<BV> distinct_triangles(const MeshBvh<BV>& mesh) {
    using Key = std::array<S, 9>;  // the three vertices, sorted lexicographically
    const std::int32_t m = mesh.num_triangles();
    const auto key_of = [&](std::int32_t k) {
      const Triangle<S> t = mesh.triangle(k);
      std::array<std::array<S, 3>, 3> v;
      for (int j = 0; j < 3; ++j) v[static_cast<std::size_t>(j)] = {t[j].x(), t[j].y(), t[j].z()};
      std::sort(v.begin(), v.end());
      Key out;
      for (std::size_t j = 0; j < 9; ++j) out[j] = v[j / 3][j % 3];
      return out;
    };
    // Copies share their centroid, so the tree keeps most of them next to each other in leaf
    // order: too few adjacent copies and the sort below (n log n) is not worth it. A copy has
    // the same coordinates, so the first look compares unsorted vertices.
    std::int32_t adjacent_copies = 0;
    for (std::int32_t k = 1; k < m; ++k) {
      const Triangle<S> a = mesh.triangle(k - 1), b = mesh.triangle(k);
      const auto in_b = [&](const Vec3<S>& x) { return x == b.a || x == b.b || x == b.c; };
      adjacent_copies += in_b(a.a) && in_b(a.b) && in_b(a.c) && key_of(k - 1) == key_of(k);
    }
    if (std::int64_t(adjacent_copies) * 8 < std::int64_t(m)) return {};
    std::vector<Key> key(static_cast<std::size_t>(m));
    for (std::int32_t k = 0; k < m; ++k) key[static_cast<std::size_t>(k)] = key_of(k);
    std::vector<std::int32_t> order(static_cast<std::size_t>(m));
    for (std::int32_t k = 0; k < m; ++k) order[static_cast<std::size_t>(k)] = k;
    std::sort(order.begin(), order.end(), [&](std::int32_t a, std::int32_t b) {
      const Key &ka = key[static_cast<std::size_t>(a)], &kb = key[static_cast<std::size_t>(b)];
      return ka < kb || (ka == kb && a < b);
    });
    std::vector<std::size_t> starts;  // first index in `order` of each group of copies
    for (std::size_t i = 0; i < order.size(); ++i)
      if (i == 0 || key[static_cast<std::size_t>(order[i])] != key[static_cast<std::size_t>(order[i - 1])]) starts.push_back(i);
    Distinct<BV> out;
    if (starts.size() * 4 > static_cast<std::size_t>(m) * 3) return out;
    const std::size_t g = starts.size();
    TriangleMesh<S> u;
    u.V.resize(static_cast<Eigen::Index>(3 * g), 3);
    u.F.resize(static_cast<Eigen::Index>(g), 3);
    std::vector<std::pair<std::int32_t, std::int32_t>> by_row(g);
    for (std::size_t i = 0; i < g; ++i) {
      const std::size_t end = i + 1 < g ? starts[i + 1] : order.size();
      const std::int32_t first = order[starts[i]], last = order[end - 1];  // ascending within a group
      const Triangle<S> t = mesh.triangle(first);
      for (int j = 0; j < 3; ++j) u.V.row(static_cast<Eigen::Index>(3 * i + static_cast<std::size_t>(j))) = t[j].transpose();
      u.F.row(static_cast<Eigen::Index>(i)) << int(3 * i), int(3 * i + 1), int(3 * i + 2);
      by_row[i] = {first, last};
    }
    out.tree.emplace(u, mesh.config());
    out.span.resize(g);
    for (std::int32_t j = 0; j < static_cast<std::int32_t>(g); ++j)
      out.span[static_cast<std::size_t>(j)] = by_row[static_cast<std::size_t>(out.tree->triangle_id(j))];
    return out;
  }

  /// The patch of the grown cell q (leaf positions are primitive ids in a MeshBvh). The slab's
  /// normal is the area-weighted mean normal of the triangles; its bounds are the extreme
  /// n . vertex, widened by their rounding and rounded outward to float. The triangles are
  /// gathered from `sample`: the mesh itself, or its distinct triangles with `span` giving the
  /// mesh's leaf positions of each one's copies. `ids` is scratch.
  template <class BV>
  static Patch patch(const MeshBvh<BV>& mesh, const MeshBvh<BV>& sample, const std::vector<std::pair<std::int32_t, std::int32_t>>* span,
                     const std::vector<std::pair<std::int32_t, std::int32_t>>& range, const Aabb<S>& q, std::vector<std::int32_t>& ids) {
    Patch out;
    ids.clear();
    traverse(
        sample.tree(), [&](const BV& bv) { return detail::may_overlap(q, bv); },
        [&](std::int32_t k) {
          ids.push_back(k);
          return true;
        });
    if (ids.empty()) {
      out.node = kNoTriangle;
      return out;
    }
    std::int32_t lo_id = std::numeric_limits<std::int32_t>::max(), hi_id = -1;
    if (span) {
      for (const std::int32_t k : ids) {
        lo_id = std::min(lo_id, (*span)[static_cast<std::size_t>(k)].first);
        hi_id = std::max(hi_id, (*span)[static_cast<std::size_t>(k)].second);
      }
    } else {
      const auto [lo, hi] = std::minmax_element(ids.begin(), ids.end());
      lo_id = *lo, hi_id = *hi;
    }
    out.node = deepest_node(mesh.tree(), range, lo_id, hi_id);
    Vec3<S> sum = Vec3<S>::Zero();
    for (const std::int32_t k : ids) sum += sample.triangle(k).scaled_normal();
    if (!(sum.norm() > S(0))) return out;
    out.set_normal(sum / sum.norm());
    const Vec3<S> n = out.normal();
    S lo = std::numeric_limits<S>::infinity(), hi = -lo, size = S(0);
    for (const std::int32_t k : ids)
      for (int j = 0; j < 3; ++j) {
        const Vec3<S> v = sample.triangle(k)[j];  // triangle() returns by value
        const S t = n.dot(v);
        lo = std::min(lo, t);
        hi = std::max(hi, t);
        size = std::max(size, v.cwiseAbs().sum());
      }
    const S m = S(8) * std::numeric_limits<S>::epsilon() * size;  // the dot products' rounding
    out.lo = detail::round_to_float(lo - m, -1);
    out.hi = detail::round_to_float(hi + m, 1);
    return out;
  }
  /// Deepest node whose subtree holds the primitives lo..hi (its range contains both).
  template <class BV>
  static std::int32_t deepest_node(const Bvh<BV>& tree, const std::vector<std::pair<std::int32_t, std::int32_t>>& range,
                                   std::int32_t lo, std::int32_t hi) {
    std::int32_t n = 0;
    for (;;) {
      const auto& node = tree.nodes[static_cast<std::size_t>(n)];
      if (node.is_leaf()) return n;
      const auto& l = range[static_cast<std::size_t>(node.left())];
      const auto& r = range[static_cast<std::size_t>(node.right())];
      if (l.first <= lo && hi <= l.second)
        n = node.left();
      else if (r.first <= lo && hi <= r.second)
        n = node.right();
      else
        return n;
    }
  }

  Vec3<S> origin_ = Vec3<S>::Zero();
  S h_ = S(1), inv_h_ = S(1);
  S reach_ = S(0);
  int n_[3] = {0, 0, 0};
  S quantum_ = S(1);                   // bounds_ unit
  S margin_ = S(0);                    // lower_bound()'s rounding margin
  Aabb<S> box_;                        // the mesh's bounding box
  S size_ = S(0);                      // the largest |x|_1 of the box
  std::int32_t sampled_triangles_ = 0;  // sampled_triangles()
  std::vector<std::uint8_t> bounds_;   // lower bounds of the distance at the cell centres
  std::vector<Patch> patches_;         // start node and slab of each cell
};

}  // namespace impact
