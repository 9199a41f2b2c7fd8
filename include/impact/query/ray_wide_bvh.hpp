// SPDX-License-Identifier: MIT
/// \file
/// First-hit ray (or segment) casts through a WideBvh (bvh/wide_bvh.hpp): nearest-first, the
/// four children of a node tested at once (SSE when compiled with it, else a scalar loop of the
/// same IEEE operations in the same order: the same answers bit for bit; the eight of an 8-wide
/// node with AVX and FMA when the CPU has them, the node loop compiled for them by a target
/// attribute and picked at run time, else SSE on two halves), the nearest entered child descended
/// at once and the others kept on a stack with their entry parameter. The node test runs in
/// float (the boxes are floats; its entry is lowered and its exit raised by a bound on its
/// rounding, so it enters every box the double slab test WideSlab enters, never later: WideFloatSlab,
/// query/wide_slab.hpp, for SSE and the scalar loop; WideFusedAvx, query/wide_fused_slab.hpp, one
/// multiply-add a plane, for the AVX loop: their keys differ in the last bits, so the loops may
/// order two nearly equal children differently, never the t they return), or in S through WideSlab
/// for rays it cannot take (magnitudes beyond 2^60, a zero direction component). The triangles of a leaf, stored in blocks of four coordinate by
/// coordinate (WideTriangleBlock), go four at a time through the watertight test's own operations
/// in SIMD (BlockTest, query/wide_leaf_filter.hpp: SSE2, or AVX when the CPU has it), which passes
/// the triangles the scalar test hits and those with an edge function within the ray's bound of
/// the error bands (PreparedRay::band for the tree's box: near an edge, where the scalar test may
/// take an exact sign); in double the hit values (t, barycentrics) of the other lanes come from
/// the lanes themselves (the same operations, so the same bits), in float and near an edge the
/// scalar test itself decides them.
///
/// Numerical contract: that of query/ray_mesh.hpp. Every crossing is decided by the same
/// watertight narrow-phase rule on the mesh's own coordinates (detail::ray_mesh_triangle_hit: the
/// exact hit/miss decision of the closed triangle for the ray's line, narrow/ray_triangle.hpp; a
/// ray through a shared edge or vertex of a closed mesh hits a triangle around it, never none;
/// the t = 0 tie rule). The node tests are conservative: the double slab test runs in S on the
/// float boxes (rounded outward, exact in S) with its exit parameter padded (PBRT's robust slab
/// test), and the float one widens that, so no triangle the ray crosses is pruned by rounding.
/// Ties as in ray_mesh_first_hit: after a hit, nodes entered at or after its t are pruned; a
/// triangle's t is never below the entry into its own box (detail::ray_mesh_triangle_hit), which
/// the float boxes hold, the slab test is monotone in the box and the float key is never above
/// it, so that pruning is exact: the t returned is the smallest of a loop over every triangle
/// (which triangle among equal ones depends on the visiting order).
#pragma once

#include "impact/bvh/traversal_stack.hpp"
#include "impact/bvh/wide_bvh.hpp"
#include "impact/core/next_float.hpp"
#include "impact/query/ray_mesh.hpp"
#include "impact/query/wide_fused_slab.hpp"
#include "impact/query/wide_leaf_filter.hpp"
#include "impact/query/wide_slab.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <type_traits>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#if defined(__AVX__)
#include <immintrin.h>
#endif

namespace impact {

namespace detail {

/// True when the ray passes validate_ray's checks (finite origin and direction within
/// CoordinateRange, the direction's largest component at least min_scale, t_max >= 0 or +inf):
/// the same rule in a few comparisons (NaN fails them all); validate_ray throws for the others.
template <class S> inline bool ray_in_range(const Ray<S>& ray) {
  constexpr S hi = CoordinateRange<S>::max;
#if defined(__SSE2__)
  if constexpr (std::is_same_v<S, double>) {  // the six coordinates two a register
    const __m128d abs_mask = _mm_castsi128_pd(_mm_set1_epi64x(0x7fffffffffffffffLL));
    const __m128d vhi = _mm_set1_pd(hi), vmin = _mm_set1_pd(CoordinateRange<S>::min_scale);
    const __m128d o01 = _mm_and_pd(_mm_loadu_pd(ray.origin.data()), abs_mask);
    const __m128d o2d0 = _mm_and_pd(_mm_set_pd(ray.direction[0], ray.origin[2]), abs_mask);
    const __m128d d12 = _mm_and_pd(_mm_loadu_pd(ray.direction.data() + 1), abs_mask);
    const __m128d in = _mm_and_pd(_mm_and_pd(_mm_cmple_pd(o01, vhi), _mm_cmple_pd(o2d0, vhi)), _mm_cmple_pd(d12, vhi));
    // the largest direction component >= min_scale: some component is (NaN fails `in`)
    const int scale = _mm_movemask_pd(_mm_cmpge_pd(d12, vmin)) | (_mm_movemask_pd(_mm_cmpge_pd(o2d0, vmin)) & 2);
    return _mm_movemask_pd(in) == 3 && scale != 0 && ray.t_max >= S(0);
  }
#endif
  bool ok = ray.t_max >= S(0);
  S dmax = S(0);
  for (int i = 0; i < 3; ++i) {
    const S ad = std::abs(ray.direction[i]);
    ok = ok & (std::abs(ray.origin[i]) <= hi) & (ad <= hi);
    dmax = ad > dmax ? ad : dmax;
  }
  return ok && dmax >= CoordinateRange<S>::min_scale;
}

/// A pending child of a wide cast: a lower bound of its entry in S (its float key, or the key in S
/// rounded down) and its reference.
struct WideEntry {
  float key;
  std::int32_t first, count;
};

/// The pending children of the AVX node loop when the tree's depth bounds them (N entries at
/// most: IMPACT_ASSERT): TraversalStack's push and pop with the top kept as a pointer, so a push
/// is three stores and a pop one decrement, and the loop holds one register for it, not an index
/// and its scaled copy. The loop keeps an entry at its bottom (WideCast::kStackBottom) and never
/// asks whether it is empty.
template <int N> class WideFixedStack {
 public:
  WideFixedStack() : top_(slots_) {}  // the slots stay uninitialised
  WideFixedStack(const WideFixedStack&) = delete;
  WideFixedStack& operator=(const WideFixedStack&) = delete;
  void push(const WideEntry& e) {
    IMPACT_ASSERT(top_ < slots_ + N);
    *top_++ = e;
  }
  WideEntry pop() { return *--top_; }

 private:
  WideEntry slots_[N];
  WideEntry* top_;
};

/// The state of one cast through a WideBvh (ray_wide_first_hit_unchecked), shared by its node
/// loop and its leaves: the best hit so far and the bounds derived from it, the ray prepared for
/// the triangle test (at the first leaf: most short casts reach none).
template <class S, int W = 4> struct WideCast {
  using Node = WideBvhNodeN<W>;
  const WideBvh<S, W>& wide;
  const Vec3<S>& o;  // the ray in the mesh's frame (the caller's: it outlives the cast)
  const Vec3<S>& d;
  const Vec3<S> inv;
  const S t_max;
  const bool use_simd;
  const bool use_avx;  // the 8-wide AVX node loop (AVX and FMA) and the AVX leaf test when the CPU has them
  // without SIMD: the scalar loop with the AVX loop's fused node test (WideFusedRay::entered_scalar,
  // 8-wide), for the tests that compare the two loops node by node
  bool fused_scalar = false;
  float slab_error = 0.0f;  // the float node test's absolute error (its e; 0 when it is not used)
  S best;  // after a hit only a strictly earlier one replaces it: nodes entered at best are pruned
  std::int32_t best_block = -1;  // the best hit's block (-1: no hit yet) and lane (leaf-order position: hit_position)
  int best_lane = 0;
  Vec3<S> best_bary;  // (set with best_block)
  // the float node test's exit bound (a float >= best) and entry bound (before a hit a float <=
  // t_max, after it the largest float < best)
  float exit_f = 0.0f, bound_f = 0.0f;
  // after a hit: float keys at or above tie_f may be within rounding of the hit (redecide)
  float tie_f = std::numeric_limits<float>::infinity();
  /// What the triangle tests need of the ray: made at the first leaf (most short casts reach
  /// none, and then pay nothing for it, not even its default members).
  struct LeafSetup {
    PreparedRay<S> pr;
    BlockTest<S> block_test;
    /// The ray's band bound (PreparedRay::band) and the block test's depth bound
    /// (BlockTest::bound_plane) for the tree's box `box` (WideBvh::box).
    LeafSetup(const Ray<S>& ray, bool avx, const std::array<double, 8>& box) : pr(ray) {  // made in place
      pr.bound_band(box_corner(box, 0), box_corner(box, 4));
      block_test.set(pr, avx);
      block_test.bound_plane(box_corner(box, 0), box_corner(box, 4));
    }
  };
  /// The corner of WideBvh::box from `at` (0: lower, 4: upper), in S (its floats: exact).
  static Vec3<S> box_corner(const std::array<double, 8>& box, std::size_t at) { return Vec3<S>(S(box[at]), S(box[at + 1]), S(box[at + 2])); }
  std::optional<LeafSetup> leaf_setup;
  std::optional<WideSlab<S>> slab;  // in S: set up when first needed
  std::size_t node_tests = 0, triangle_tests = 0;

  /// `o_` and `d_` must outlive the cast.
  WideCast(const WideBvh<S, W>& w, const Vec3<S>& o_, const Vec3<S>& d_, S t_max_, bool simd, bool avx = true)
      : wide(w), o(o_), d(d_), inv(safe_inverse(d_)), t_max(t_max_), use_simd(simd), use_avx(avx), best(t_max_) {
    float_bounds(double(t_max_), bound_f, exit_f);
  }

  /// The keys in S of a node's children (WideSlab, or the box test for a zero direction component).
  void double_keys(const Node& n, S (&keys)[W]) {
    if (!slab) slab.emplace(o, inv);
    if (std::isfinite(inv[0]) && std::isfinite(inv[1]) && std::isfinite(inv[2])) {
      slab->keys(n, best, keys, use_simd);
      return;
    }
    for (int c = 0; c < W; ++c) {
      const Aabb<S> box(Vec3<S>(S(n.bounds[0][c]), S(n.bounds[2][c]), S(n.bounds[4][c])),
                        Vec3<S>(S(n.bounds[1][c]), S(n.bounds[3][c]), S(n.bounds[5][c])));
      const auto t = n.count[c] < 0 ? std::nullopt : ray_box_entry(o, inv, box, best);
      keys[c] = t ? *t : std::numeric_limits<S>::quiet_NaN();
    }
  }
  /// True once a hit is recorded.
  bool has_hit() const { return best_block >= 0; }
  /// The best hit's leaf-order position (after a hit).
  std::int32_t hit_position() const { return wide.block_first(best_block) + best_lane; }
  /// The children entered by the test in S (at or before t_max, after a hit before it), with their
  /// keys rounded down to float.
  int double_mask(const Node& n, float (&fk)[W]) {
    S keys[W];
    double_keys(n, keys);
    const S limit = has_hit() ? next_down(best) : best;
    int mask = 0;
    for (int c = 0; c < W; ++c) {
      const bool in = keys[c] <= limit && n.count[c] >= 0;
      mask |= (in ? 1 : 0) << c;
      fk[c] = in ? float_round_down(double(keys[c])) : 0.0f;
    }
    return mask;
  }
  /// The triangle in lane c of block b (a candidate of the block test) by the narrow-phase rule; a
  /// strictly earlier hit replaces the best one. In double with SIMD from the block test's values
  /// (test_lane) unless the lane is near an edge, else by the scalar test.
  void test(std::int32_t b, int c, const typename BlockTest<S>::LaneValues& values) {
    if constexpr (BlockTest<S>::kHasValues) {
      if (use_simd && !((values.near >> c) & 1)) {
        test_lane(b, c, values);
        return;
      }
    }
    PreparedRay<S>& pr = leaf_setup->pr;
    pr.ray.t_max = best;
    const auto h = ray_mesh_triangle_hit(pr, inv, wide.block_triangle(b, c));
    if (h && (!has_hit() || h->t < best)) record(b, c, h->t, Vec3<S>(h->u, h->v, h->w));
  }
  /// test() from the block test's values of lane c (`values`: the scalar test's own
  /// intermediate values, so the same decision and hit values bit for bit): the depth checked
  /// against the current best, then the rest of ray_mesh_triangle_hit (the entry into the
  /// triangle's box, the t = 0 rule).
  void test_lane(std::int32_t b, int c, const typename BlockTest<S>::LaneValues& values) {
    const S det = values.det[c], tt = values.tt[c];
    const S tmd = best * det;
    if (det > S(0) ? (tt < S(0) || tt > tmd) : (tt > S(0) || tt < tmd)) return;
    const S inv_det = S(1) / det;
    const std::optional<S> th = detail::mesh_hit_t(o, inv, wide.block_triangle(b, c), std::min(S(tt * inv_det), best), det > S(0), best);
    if (th && (!has_hit() || *th < best))
      record(b, c, *th, Vec3<S>(S(values.eu[c] * inv_det), S(values.ev[c] * inv_det), S(values.ew[c] * inv_det)));
  }
  /// A new best hit: triangle in lane c of block b at t (>= 0). The float bounds from one rounding
  /// of t (float_hit_bounds); the tie bound at most t - 4 (t 2^-19 + e) (float_tie_bound: the
  /// slack of docs/rays-history.md, e = slab_error >= 2^-100, set by the node loop before any leaf).
  void record(std::int32_t b, int c, S t, const Vec3<S>& bary) {
    best = t;
    best_block = b;
    best_lane = c;
    best_bary = bary;
    float_hit_bounds(double(t), exit_f, bound_f);
    tie_f = float_tie_bound(bound_f, slab_error);
  }
  /// The triangles of a leaf (its blocks from `block`): four at a time through the block test
  /// (the scalar test's decisions, SIMD), the candidates by test(); without SIMD each by the
  /// scalar test.
  IMPACT_NOINLINE void leaf(std::int32_t block, std::int32_t count) {
    if (!leaf_setup) leaf_setup.emplace(Ray<S>(o, d, t_max), use_avx, wide.box());
    const BlockTest<S>& block_test = leaf_setup->block_test;
    const bool repeats = wide.has_repeats();
    const std::int32_t first = wide.block_first(block);
    typename BlockTest<S>::LaneValues values;  // of the block being tested, when it passes a lane
    for (std::int32_t q = 0; q < count; q += 4, ++block) {
      const int lanes = static_cast<int>(std::min<std::int32_t>(4, count - q));
      int todo = (1 << lanes) - 1;
      if (use_simd) {
        const int m = wide.packed() ? block_test.candidates(wide.packed_blocks()[static_cast<std::size_t>(block)], lanes, best, &values)
                                    : block_test.candidates(wide.full_blocks()[static_cast<std::size_t>(block)], lanes, best, &values);
        todo &= m;
      }
      if (repeats) {
        for (int c = 0; c < lanes; ++c) {
          if (wide.repeats_previous(first + q + c)) todo &= ~(1 << c);  // the triangle just tested, again (coincident copies)
          else ++triangle_tests;
        }
      } else {
        triangle_tests += static_cast<std::size_t>(lanes);
      }
      while (todo) {
        const int c = lowest_bit(todo);
        todo &= todo - 1;
        test(block, c, values);
      }
    }
  }
#if defined(IMPACT_WIDE_AVX)
  /// leaf() for the AVX loop of a cast in double (compiled for AVX; call only when the CPU has
  /// it, with SIMD): each block's lanes decided and finished at once (BlockTest::hits_avx: the
  /// watertight test, the entry into each triangle's box, the t = 0 rule), then taken in lane
  /// order, a lane after a new hit in the same block re-decided against it, so the same hits as
  /// leaf() bit for bit. A tree with repeated triangles goes to leaf().
  IMPACT_NOINLINE IMPACT_WIDE_AVX_TARGET void leaf_avx(std::int32_t block, std::int32_t count) {
    if (wide.has_repeats()) {
      leaf(block, count);
      return;
    }
    if (!lane_test) make_lane_test();
    triangle_tests += static_cast<std::size_t>(count);
    const bool packed = wide.packed();
    for (std::int32_t q = 0; q < count; q += 4, ++block) {
      const int lanes = static_cast<int>(std::min<std::int32_t>(4, count - q));
      if (packed) {
        leaf_block_avx(wide.packed_blocks()[static_cast<std::size_t>(block)], block, lanes);
      } else {
        leaf_block_avx(wide.full_blocks()[static_cast<std::size_t>(block)], block, lanes);
      }
    }
  }
  /// One block of leaf_avx (a function of its own: the ray's values are read from the test at
  /// each block, not hoisted out of a loop and spilled): block_avx.
  template <class T> IMPACT_NOINLINE IMPACT_WIDE_AVX_TARGET void leaf_block_avx(const WideTriangleBlock<T>& blk, std::int32_t block, int lanes) {
    block_avx(blk, block, lanes);
  }
  /// The lanes of one block hit (the first `lanes`), taken in lane order; a lane near an edge
  /// (LaneHits::near) by the scalar rule, as test() takes it. hits_avx decides
  /// against the best B as the block begins; after a hit of this block lowered it to B' < B,
  /// test_lane would keep a later lane exactly when its depth check passes against B', its box
  /// is entered before B' and max(min(q, B'), entry) < B' (q = tt / det): that needs q < B' and
  /// entry < B', and then the value is hits_avx's max(min(q, B), entry) and the box test against
  /// B' agrees with the one against B. So the depth re-check and th < B' give test_lane's answer.
  /// Inlined into its two callers (GCC and Clang only, as IMPACT_WIDE_AVX).
  template <class T> __attribute__((always_inline)) IMPACT_WIDE_AVX_TARGET void block_avx(const WideTriangleBlock<T>& blk, std::int32_t block, int lanes) {
    typename BlockTest<S>::LaneHits h;  // of the block, when it hits a lane
    const int hit = lane_test->hits_avx_inline(blk, lanes, best, h);
    int m = hit | h.near;
    bool lowered = false;  // by a lane of this block: later lanes are re-decided against it
    while (m) {
      const int c = lowest_bit(m);
      m &= m - 1;
      if (IMPACT_UNLIKELY(!((hit >> c) & 1))) {  // near an edge: the scalar rule against the best
        lowered |= near_edge_lane(block, c);
        continue;
      }
      const S th = h.t[c];
      if (lowered) {  // (hits_avx decided against the best as the block began)
        const S det = h.det[c], tt = h.tt[c], tmd = best * det;
        if (det > S(0) ? (tt < S(0) || tt > tmd) : (tt > S(0) || tt < tmd)) continue;
      }
      if (has_hit() && !(th < best)) continue;
      const S inv_det = h.inv_det[c];
      record(block, c, th, Vec3<S>(S(h.eu[c] * inv_det), S(h.ev[c] * inv_det), S(h.ew[c] * inv_det)));
      lowered = true;
    }
  }
  /// The triangle in lane c of block b, near an edge, by the scalar rule (test() without values;
  /// leaf_setup made here if needed): true when it is the new best hit.
  IMPACT_NOINLINE bool near_edge_lane(std::int32_t b, int c) {
    if (!leaf_setup) leaf_setup.emplace(Ray<S>(o, d, t_max), use_avx, wide.box());
    PreparedRay<S>& pr = leaf_setup->pr;
    pr.ray.t_max = best;
    const auto h = ray_mesh_triangle_hit(pr, inv, wide.block_triangle(b, c));
    if (!h || (has_hit() && !(h->t < best))) return false;
    record(b, c, h->t, Vec3<S>(h->u, h->v, h->w));
    return true;
  }
  std::optional<BlockTest<S>> lane_test;  // leaf_avx's test, made at its first leaf
  /// Makes lane_test (at a cast's first leaf; kept out of the node loop's code), with the ray's
  /// band bound for the tree's box.
  IMPACT_NOINLINE void make_lane_test() {
    lane_test.emplace(o, d, inv);
    lane_test->bound_band(box_corner(wide.box(), 0), box_corner(wide.box(), 4));
  }
  /// leaf_avx() of a leaf of one block (at most four triangles) in a tree of float blocks
  /// without repeated triangles (WideBvh::packed_without_repeats; run_avx checks both, the most
  /// common leaf): one call from the node loop, where leaf_avx made two and its checks and loop
  /// (bunny, long rays: 869 -> 842 instructions a ray). Inlining it into the node loop too saves
  /// no more (846) and costs short casts, which rarely reach a leaf, 4 a ray.
  IMPACT_NOINLINE IMPACT_WIDE_AVX_TARGET void leaf_one_block_avx(std::int32_t block, std::int32_t count) {
    if (IMPACT_UNLIKELY(!lane_test)) make_lane_test();
    triangle_tests += static_cast<std::size_t>(count);
    block_avx(wide.packed_blocks()[static_cast<std::size_t>(block)], block, static_cast<int>(count));
  }
#endif
  /// After a hit, at a node whose float keys of entered children are within rounding of it: the
  /// keys in S decide (exact ties with the hit are pruned, as WideSlab prunes them: a ray through
  /// a vertex would otherwise open every leaf around it).
  IMPACT_NOINLINE int redecide(const Node& n, float (&fk)[W]) { return double_mask(n, fk); }

  /// Descends to the nearest entered child of `mask` (keys fk), pushing the others farthest first.
  template <class Stack> void descend(const Node& n, int mask, const float (&fk)[W], Stack& stack, std::int32_t& first, std::int32_t& count) {
    const int c0 = lowest_bit(mask);
    const int rest = mask & (mask - 1);
    if (!rest) {  // one child (the common case)
      first = n.first[c0];
      count = n.count[c0];
      return;
    }
    const int c1 = lowest_bit(rest);
    if (!(rest & (rest - 1))) {  // two: the nearer first (ties: the lower slot)
      const bool swap = fk[c0] > fk[c1];
      const int near = swap ? c1 : c0, far = swap ? c0 : c1;
      stack.push({fk[far], n.first[far], n.count[far]});
      prefetch_child(n.first[far], n.count[far]);
      first = n.first[near];
      count = n.count[near];
      return;
    }
    int order[W];
    const int m = order_children(mask, fk, order);
    for (int j = m - 1; j > 0; --j) {
      stack.push({fk[order[j]], n.first[order[j]], n.count[order[j]]});
      prefetch_child(n.first[order[j]], n.count[order[j]]);
    }
    first = n.first[order[0]];
    count = n.count[order[0]];
  }

  /// Starts loading the cache line of a node's references (first, count) with its planes: the
  /// loads of the references wait for the node test's mask, and in an 8-wide node they are on a
  /// line of their own.
  static void prefetch_references(const Node& n) {
#if defined(__SSE2__)
    _mm_prefetch(reinterpret_cast<const char*>(n.first), _MM_HINT_T0);
#else
    (void)n;
#endif
  }

  /// Starts loading the lines of a child the loop has pushed or is about to test as a leaf (three
  /// lines: an 8-wide node's planes, a 4-wide node and the next line, a leaf's first block), as
  /// Embree's traversal prefetches the children it keeps: a pushed child is popped after the
  /// nearer one's subtree, its lines by then in L1, and a leaf's block arrives while the loop
  /// spills its registers and calls the leaf test. No effect on the answers.
  void prefetch_child(std::int32_t f, std::int32_t c) const {
#if defined(__SSE2__)
    // Addresses by integer arithmetic: a leaf's in the float blocks, which are empty in a tree
    // kept in S (rare), where the address means nothing; a prefetch takes any address (it never
    // faults). (Written with a test of packed() instead, GCC 12 dropped the prefetches.)
    const std::uintptr_t a = c == 0 ? reinterpret_cast<std::uintptr_t>(wide.nodes().data()) + static_cast<std::uintptr_t>(f) * sizeof(Node)
                                    : reinterpret_cast<std::uintptr_t>(wide.packed_blocks().data()) +
                                          static_cast<std::uintptr_t>(f) * sizeof(WideTriangleBlock<float>);
    for (std::uintptr_t line = 0; line < 192; line += 64) _mm_prefetch(reinterpret_cast<const char*>(a + line), _MM_HINT_T0);
#else
    (void)f, (void)c;
#endif
  }
  /// The traversal: nearest child first, the others on the stack with their keys (a fixed array
  /// when the tree's depth bounds it, else a stack with a heap overflow).
  void run() {
#if defined(IMPACT_WIDE_AVX)
    if constexpr (W == 8) {
      if (use_simd && use_avx && wide_fma_available() && run_avx_loop()) return;
    }
#endif
    run_without_avx();
  }
#if defined(IMPACT_WIDE_AVX)
  /// The AVX loop (8-wide; call only when wide_fma_available()), its stack a local of its own
  /// frame (the top in a register). False, having done nothing, when its float test cannot take
  /// the ray: then run_without_avx().
  bool run_avx_loop() {
    return wide.depth() <= kFixedDepth ? run_avx<WideFixedStack<(W - 1) * kFixedDepth + 1>>()
                                       : run_avx<TraversalStack<WideEntry, 128>>();
  }
#endif
  /// The traversal with the SSE or scalar node test.
  void run_without_avx() {
    if constexpr (W == 8) {
      if (fused_scalar && !use_simd) {
        const WideFusedRay fused(o, inv, wide.coordinate_bound(), wide.box(), double(t_max));
        if (fused.usable()) {
          slab_error = fused.e;
          run_on_stack(fused);
          return;
        }
      }
    }
    const WideFloatSlab<S, W> float_slab(o, inv, wide.coordinate_bound());
    slab_error = float_slab.absolute_error();
    run_on_stack(float_slab);
  }
  /// run() with the node test `slab` on the stack the tree's depth calls for.
  template <class Slab> void run_on_stack(const Slab& float_slab) {
    if (wide.depth() <= kFixedDepth) {
      TraversalStack<WideEntry, (W - 1) * kFixedDepth, StackOverflow::None> stack;  // W - 1 entries a level at most
      run(stack, float_slab);
    } else {
      TraversalStack<WideEntry, 128> stack;
      run(stack, float_slab);
    }
  }
  static constexpr int kFixedDepth = 40;

  /// The nearest pending child still at or below `bound` (popping the others); false when none.
  template <class Stack> static bool pop_below(Stack& stack, float bound, std::int32_t& first, std::int32_t& count) {
    while (!stack.empty()) {
      const WideEntry e = stack.pop();
      if (e.key <= bound) {
        first = e.first;
        count = e.count;
        return true;
      }
    }
    return false;
  }
#if defined(IMPACT_WIDE_AVX)
  /// The bottom entry of the AVX loop's stack: a key below every bound (so pop_to stops there),
  /// count -1 (no child's: empty slots are never entered), which ends the walk.
  static constexpr WideEntry kStackBottom = {-std::numeric_limits<float>::infinity(), 0, -1};
  /// pop_below for a stack with kStackBottom at its bottom: pops up to the nearest entry at or
  /// below `bound` (the bottom if none), which becomes (first, count).
  template <class Stack> static void pop_to(Stack& stack, float bound, std::int32_t& first, std::int32_t& count) {
    WideEntry e = stack.pop();
    while (e.key > bound) e = stack.pop();
    first = e.first;
    count = e.count;
  }
  /// The traversal of an 8-wide tree with the fused AVX node test (WideFusedAvx; compiled for AVX
  /// and FMA, called when the CPU has both): the loop of run() with eight children tested at once,
  /// on a Stack of its own with kStackBottom at its bottom (a pop is one comparison a popped entry,
  /// and the walk ends where the leaves' path meets a count of -1), the node test's state made in
  /// the same frame (in double in one pass). False, having done nothing, when the node test cannot
  /// take the ray.
  template <class Stack> IMPACT_WIDE_FMA_TARGET bool run_avx();
  /// descend() for the keys in an AVX register: the same order (by key, ties by the lower slot),
  /// three or more children ranked without a sort (a child's rank: the entered children with a
  /// smaller key, or an equal key in a lower slot). Inlined into run_avx: GCC does so by itself,
  /// Clang 14 did not (a call a node; bunny, long rays: 1,017 -> 893 instructions a cast).
  template <class Stack>
  __attribute__((always_inline)) IMPACT_WIDE_AVX_TARGET void descend_avx(const Node& n, int mask, __m256 keys, Stack& stack, std::int32_t& first, std::int32_t& count) {
    const int c0 = lowest_bit(mask);
    const int rest = mask & (mask - 1);
    if (!rest) {  // one child (the common case)
      first = n.first[c0];
      count = n.count[c0];
      return;
    }
    alignas(32) float fk[W];
    _mm256_store_ps(fk, keys);
    const int c1 = lowest_bit(rest);
    if (!(rest & (rest - 1))) {  // two: the nearer first (ties: the lower slot)
      // chosen by a mask, not a jump: which of two boxes a ray enters first is a coin toss
      const int swap = -static_cast<int>(fk[c0] > fk[c1]);
      const int near = c0 ^ ((c0 ^ c1) & swap), far = c0 ^ c1 ^ near;
      stack.push({fk[far], n.first[far], n.count[far]});
      prefetch_child(n.first[far], n.count[far]);
      first = n.first[near];
      count = n.count[near];
      return;
    }
    int order[W];
    int m = 0;
    for (unsigned bits = static_cast<unsigned>(mask); bits; bits &= bits - 1, ++m) {
      const int c = lowest_bit(static_cast<int>(bits));
      const __m256 kc = _mm256_set1_ps(fk[c]);
      const int before = (_mm256_movemask_ps(_mm256_cmp_ps(keys, kc, _CMP_LT_OQ)) |
                          (_mm256_movemask_ps(_mm256_cmp_ps(keys, kc, _CMP_EQ_OQ)) & ((1 << c) - 1))) &
                         mask;
      order[__builtin_popcount(static_cast<unsigned>(before))] = c;
    }
    for (int j = m - 1; j > 0; --j) {
      stack.push({fk[order[j]], n.first[order[j]], n.count[order[j]]});
      prefetch_child(n.first[order[j]], n.count[order[j]]);
    }
    first = n.first[order[0]];
    count = n.count[order[0]];
  }
#endif

  template <class Stack, class Slab> void run(Stack& stack, const Slab& float_slab) {
    const Node* nodes = wide.nodes().data();
    std::int32_t first = 0, count = 0;  // the root: an inner node
    std::size_t tests = 0;
    const bool in_float = float_slab.usable();  // (false for an infinite 1 / d)
#if defined(__SSE2__)
    if constexpr (std::is_same_v<Slab, WideFloatSlab<S, W>>) {
      if (in_float && use_simd) {
        const typename WideFloatSlab<S, W>::Sse fs = float_slab.sse();  // a copy the node loop keeps in registers
        for (;;) {
          // the bounds as of the last leaf, in registers for the node loop
          const __m128 exit_v = _mm_set1_ps(exit_f), bound_v = _mm_set1_ps(bound_f), tie_v = _mm_set1_ps(tie_f);
          const float bound = bound_f;
          while (count == 0) {
            const Node& n = nodes[first];
            prefetch_references(n);
            ++tests;
            __m128 lo[W / 4];
            int mask = fs.entered(n, exit_v, bound_v, lo);
            if (mask) {
              float fk[W];
              int ties = 0;
              for (int g = 0; g < W / 4; ++g) {
                _mm_storeu_ps(fk + 4 * g, lo[g]);
                ties |= _mm_movemask_ps(_mm_cmpge_ps(lo[g], tie_v)) << (4 * g);
              }
              if (IMPACT_UNLIKELY(ties & mask)) {
                mask = redecide(n, fk);
                if (!mask) {
                  if (!pop_below(stack, bound, first, count)) {
                    node_tests += tests;
                    return;
                  }
                  continue;
                }
              }
              descend(n, mask, fk, stack, first, count);
              continue;
            }
            if (!pop_below(stack, bound, first, count)) {
              node_tests += tests;
              return;
            }
          }
          if (wide.packed()) prefetch_child(first, count);
          leaf(first, count);
          if (!pop_below(stack, bound_f, first, count)) {
            node_tests += tests;
            return;
          }
        }
      }
    }
#endif
    for (;;) {
      if (count > 0) {
        leaf(first, count);
      } else {
        const Node& n = nodes[first];
        ++tests;
        float fk[W];
        int mask;
        if (in_float) {
          if constexpr (std::is_same_v<Slab, WideFusedRay>) {
            mask = float_slab.entered_scalar(n, bound_f, fk);  // (its bound_f <= exit_f: no exit of its own)
          } else {
            mask = float_slab.entered_scalar(n, exit_f, bound_f, fk);
          }
          int ties = 0;
          for (int c = 0; c < W; ++c) ties |= (fk[c] >= tie_f ? 1 : 0) << c;
          if (IMPACT_UNLIKELY(mask & ties)) mask = redecide(n, fk);
        } else {
          mask = double_mask(n, fk);
        }
        if (mask) {
          descend(n, mask, fk, stack, first, count);
          continue;
        }
      }
      if (!pop_below(stack, bound_f, first, count)) break;
    }
    node_tests += tests;
  }
};

#if defined(IMPACT_WIDE_AVX)
template <class S, int W>
template <class Stack>
IMPACT_WIDE_FMA_TARGET bool WideCast<S, W>::run_avx() {
  static_assert(W == 8, "the AVX node loop: 8-wide nodes");
  WideFusedAvx fs;  // in registers for the node loop
  if constexpr (std::is_same_v<S, double>) {
    if (!fs.set(o, inv, double(wide.coordinate_bound()), wide.box(), t_max, slab_error)) return false;
  } else {
    const WideFusedRay fused(o, inv, wide.coordinate_bound(), wide.box(), double(t_max));
    if (!fused.usable()) return false;
    slab_error = fused.e;
    fs.set(fused);
  }
  Stack stack;
  stack.push(kStackBottom);  // (pop_to stops there: no emptiness check, count -1 ends the walk)
  const Node* nodes = wide.nodes().data();
  std::int32_t first = 0, count = 0;  // the root: an inner node
  for (;;) {
    const __m256 bound_v = _mm256_set1_ps(bound_f), tie_v = _mm256_set1_ps(tie_f);
    const float bound = bound_f;
    while (count == 0) {
      const Node& n = nodes[first];
      prefetch_references(n);
      ++node_tests;  // (in memory: the loop has more live integers than registers)
      __m256 lo, entered;
      int mask = fs.entered(n, bound_v, lo, entered);
      if (mask) {
        // an entered child's key at or above tie_f (the sign bits of both comparisons: vtestps)
        if (IMPACT_UNLIKELY(!_mm256_testz_ps(_mm256_cmp_ps(lo, tie_v, _CMP_GE_OQ), entered))) {
          float fk[W];
          _mm256_storeu_ps(fk, lo);
          mask = redecide(n, fk);
          if (!mask) {
            pop_to(stack, bound, first, count);
            continue;
          }
          lo = _mm256_loadu_ps(fk);
        }
        descend_avx(n, mask, lo, stack, first, count);
        continue;
      }
      pop_to(stack, bound, first, count);
    }
    // The stack's bottom is tested here and after each leaf's pop, apart from the leaves' loop and
    // its exit to the node loop: GCC spills the node test's AVX registers around the leaf calls,
    // and with one test at the loop's top every cast paid that spill on its way out (bunny short
    // 323.8 -> 312.2 instructions a ray, docs/rays-history.md).
    if (count < 0) return true;
    for (;;) {
      if (wide.packed()) prefetch_child(first, count);  // (before the spill and the call: the block test reads it late)
      if constexpr (std::is_same_v<S, double>) {
        if (IMPACT_LIKELY(count <= 4 && wide.packed_without_repeats())) {
          leaf_one_block_avx(first, count);
        } else {
          leaf_avx(first, count);
        }
      } else {
        leaf(first, count);
      }
      pop_to(stack, bound_f, first, count);
      if (count < 0) return true;
      if (count == 0) break;
    }
  }
}
#endif

/// The cast of ray_wide_first_hit_unchecked once its ray, in the mesh's frame (o, d), is known
/// to have a non-zero direction and t_max >= 0 (ray_in_range implies both: the public overload
/// without a pose comes here directly, but for the 8-wide tree in double with AVX).
/// With kCheckRay (the public 8-wide cast in double without a pose, when the CPU has AVX and FMA;
/// `ray` not yet checked but for t_max >= 0): the AVX loop first, and ray_in_range (validate_ray)
/// only for a ray its node test does not take (WideFusedAvx::set's limits imply the rest).
template <bool kCheckRay = false, class S, int W>
std::optional<RayMeshHit<S>> ray_wide_cast(const WideBvh<S, W>& wide, const Ray<S>& ray, const Vec3<S>& o, const Vec3<S>& d,
                                           const RigidTransform<S>* pose, RayMeshStats* stats, bool use_simd = true, bool use_avx = true,
                                           bool fused_scalar = false) {
  if (wide.empty()) {
    if constexpr (kCheckRay) {
      if (!ray_in_range(ray)) validate_ray(ray, "ray_mesh_first_hit");
    }
    return std::nullopt;
  }
  WideCast<S, W> cast(wide, o, d, ray.t_max, use_simd, use_avx);
  cast.fused_scalar = fused_scalar;
#if defined(IMPACT_WIDE_AVX)
  if constexpr (kCheckRay && W == 8) {
    if (!cast.run_avx_loop()) {
      if (!ray_in_range(ray)) validate_ray(ray, "ray_mesh_first_hit");
      cast.run_without_avx();
    }
    if (!cast.has_hit()) return std::nullopt;  // (most short casts)
  } else {
    cast.run();
  }
#else
  static_assert(!kCheckRay, "the folded argument check needs the AVX cast");
  cast.run();
#endif
  if (stats) {
    stats->node_tests += W * cast.node_tests;
    stats->triangle_tests += cast.triangle_tests;
  }
  if (!cast.has_hit()) return std::nullopt;
  RayMeshHit<S> hit;
  hit.t = cast.best;
  hit.leaf_index = cast.hit_position();
  hit.triangle = wide.block_triangle_id(cast.best_block, cast.best_lane);  // (not ids_[leaf_index]: a cache miss more)
  hit.barycentric = cast.best_bary;
  hit.point = ray.origin + cast.best * ray.direction;
  const Vec3<S> nrm = wide.block_triangle(cast.best_block, cast.best_lane).normal();
  hit.normal = pose ? Vec3<S>(pose->R * nrm) : nrm;
  hit.front_face = d.dot(nrm) < S(0);
  return hit;
}

/// ray_mesh_first_hit through a WideBvh without the argument checks; `pose` null for the mesh's
/// own frame. `use_simd` false forces the scalar node test and leaf loop (for the tests that
/// compare the two: the same answers, triangle included), with `fused_scalar` (8-wide) the AVX
/// loop's node test in it (the same nodes visited as the AVX loop).
/// The direction's largest component must be at least CoordinateRange::min_scale (else squared
/// norms underflow and hits are missed): callers with unvalidated rays (a particle's leg) scale
/// it first (detail::cast_short_ray, geometry/ray.hpp).
template <class S, int W>
std::optional<RayMeshHit<S>> ray_wide_first_hit_unchecked(const WideBvh<S, W>& wide, const Ray<S>& ray, const RigidTransform<S>* pose,
                                                          RayMeshStats* stats, bool use_simd = true, bool use_avx = true,
                                                          bool fused_scalar = false) {
  Vec3<S> posed_o, posed_d;  // the ray in the mesh's frame when posed (else the caller's, not copied)
  if (pose) {
    posed_o = pose->R.transpose() * (ray.origin - pose->t);
    posed_d = pose->R.transpose() * ray.direction;
  }
  const Vec3<S>& o = pose ? posed_o : ray.origin;
  const Vec3<S>& d = pose ? posed_d : ray.direction;
  if (d.squaredNorm() == S(0) || !(ray.t_max >= S(0))) return std::nullopt;
  return ray_wide_cast(wide, ray, o, d, pose, stats, use_simd, use_avx, fused_scalar);
}

}  // namespace detail

/// First hit of the ray origin + t * direction, t in [0, ray.t_max], against the mesh of `wide`
/// placed in the world by `pose`: the contract of ray_mesh_first_hit (query/ray_mesh.hpp), the
/// same t, through the 4-wide tree. RayMeshHit::leaf_index is the leaf-order position in `wide`
/// (WideBvh::triangle). Throws InvalidInput for a non-finite origin or direction, a zero
/// direction, t_max NaN or negative (validate_ray), or a pose that is not rigid (validate_pose).
template <class S, int W>
std::optional<RayMeshHit<S>> ray_mesh_first_hit(const WideBvh<S, W>& wide, const Ray<S>& ray, const RigidTransform<S>& pose,
                                                RayMeshStats* stats = nullptr) {
  if (!detail::ray_in_range(ray)) validate_ray(ray, "ray_mesh_first_hit");
  validate_pose(pose, "ray_mesh_first_hit");
  return detail::ray_wide_first_hit_unchecked(wide, ray, &pose, stats);
}

/// The same first hit with the ray in the mesh's own frame (no pose to check or apply).
template <class S, int W> std::optional<RayMeshHit<S>> ray_mesh_first_hit(const WideBvh<S, W>& wide, const Ray<S>& ray) {
#if defined(IMPACT_WIDE_AVX)
  if constexpr (W == 8 && std::is_same_v<S, double>) {
    // The argument check folded into the AVX cast's set-up: its node test takes a ray only when
    // every origin component is within 2^60 and every 1 / d component within [2^-60, 2^60]
    // (WideFusedAvx::set), which implies ray_in_range but for t_max (all three direction
    // components finite, at least 2^-60 > min_scale and at most about 2^60 < max; NaN fails).
    // Only a ray it does not take is checked, then cast with the other node tests.
    if (ray.t_max >= S(0) && detail::wide_fma_available())
      return detail::ray_wide_cast<true>(wide, ray, ray.origin, ray.direction, static_cast<const RigidTransform<S>*>(nullptr), nullptr);
  }
#endif
  if (!detail::ray_in_range(ray)) validate_ray(ray, "ray_mesh_first_hit");
  // (ray_in_range: a non-zero direction and t_max >= 0, the unchecked cast's own checks)
  return detail::ray_wide_cast(wide, ray, ray.origin, ray.direction, static_cast<const RigidTransform<S>*>(nullptr), nullptr);
}

}  // namespace impact
