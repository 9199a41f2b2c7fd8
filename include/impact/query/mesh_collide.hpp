// SPDX-License-Identifier: MIT
/// \file
/// Mesh–mesh collision: which triangles of mesh A intersect which triangles of mesh B, each mesh
/// under its own rigid pose, and mesh self-collision. Pair traversal of the two MeshBvh trees in
/// A's frame (B's nodes are moved by the relative transform on the fly: neither tree is rebuilt or
/// copied), exact triangle–triangle tests at the leaves.
///
/// Semantics (as FCL): meshes are surfaces. Two meshes collide when a triangle of one intersects
/// a triangle of the other; touching counts as colliding. A mesh entirely inside a closed mesh does
/// not collide with it. The triangle test is exact for the coordinates it is given; B's vertices are
/// rounded once when moved into A's frame, so answers can differ from other libraries only for
/// configurations within rounding of touching.
#pragma once

#include "impact/bvh/mesh_bvh.hpp"
#include "impact/bvh/traverse_pair.hpp"
#include "impact/core/config.hpp"
#include "impact/geometry/obb_pair_frame.hpp"
#include "impact/geometry/obb_slabs.hpp"
#include "impact/geometry/rotation_defect.hpp"
#include "impact/geometry/transform.hpp"
#include "impact/narrow/triangle_triangle.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <type_traits>
#include <limits>
#include <utility>
#include <vector>

namespace impact {

/// Work counters of a query, for benchmarks and for tests that check work is skipped.
struct QueryStats {
  std::uint64_t bv_tests = 0;         ///< BV–BV overlap tests
  std::uint64_t primitive_tests = 0;  ///< triangle–triangle tests
};

struct CollideOptions {
  /// false: boolean query, stops at the first colliding pair. true: report every colliding pair.
  bool all_pairs = false;
  /// Also compute contact information (a point of the intersection, both normals) per pair.
  bool contacts = false;
  /// Stop after this many pairs (all_pairs mode).
  std::size_t max_pairs = std::numeric_limits<std::size_t>::max();
};

/// Contact of two intersecting triangles, in the common (world) frame of the poses.
template <class S> struct MeshContact {
  std::int32_t triangle_a = -1, triangle_b = -1;  ///< rows of each mesh's F
  Vec3<S> point;                                  ///< a point of the intersection
  Vec3<S> normal_a, normal_b;                     ///< unit triangle normals (zero for degenerate triangles)
};

template <class S> struct CollideResult {
  bool colliding = false;
  std::vector<std::pair<std::int32_t, std::int32_t>> pairs;  ///< (row of F_a, row of F_b)
  std::vector<MeshContact<S>> contacts;                      ///< filled when options.contacts
  QueryStats stats;
};

namespace detail {

/// Conservative: false only when the closed sphere (centre c, radius r) provably shares no point
/// with the closed triangle t, for the exact values given. Four separating axes: the triangle's
/// normal and its three in-plane edge normals. Much tighter than a sphere around a long thin
/// triangle, which is what makes leaf-versus-node tests pay off. float input is evaluated in double.
///
/// Why it is conservative (u = unit roundoff of the evaluation type T, no overflow: any inf or NaN
/// gives "may touch"). An axis w may be any vector: its value is not trusted, only used. The sphere
/// and the triangle are disjoint when every vertex v gives w.(c - v) > r |w| (the triangle lies
/// wholly beyond the sphere on one side), or every vertex gives w.(v - c) > r |w| (other side).
/// For each vertex, q = fl(c - v) has |q_i - (c - v)_i| <= u |c - v|_i, and s = fl(w . q) then
/// differs from w.(c - v) by at most gamma_4 A_v with A_v = sum_i |w_i| |c_i - v_i| (Higham,
/// Accuracy and Stability of Numerical Algorithms, 3.1: any order of a 3-term dot product, FMA or
/// not). With qmax the componentwise largest |q| over the vertices, beta = fl(8u |w|.qmax) + mu is
/// at least twice gamma_4 A_v for every v (the rounding of |w|.qmax is below 4u of it), and mu =
/// the least normal number covers the absolute errors of products that underflow. Then lo =
/// fl(min_v s - beta) > 0 gives min_v w.(c - v) >= lo / (1 + u) (the half of beta left over covers
/// the rounding of the subtraction); the same holds for -max_v s on the other side (the side is
/// the one the first vertex suggests: a separation on the other side would need the first vertex
/// there too). The reach
/// fl(rr fl(rr fl(w.w))) + mu, rr = fl(r (1 + 8u)), is at least (r |w|)^2 (1 + 8u) when w.w is
/// normal (checked; an intermediate that underflows leaves a true value below mu), and lo^2 >
/// reach, computed, implies (lo / (1 + u))^2 > (r |w|)^2: the exact separation.
/// The error scale is the distance from c to the vertices actually used, not the triangle's size
/// alone: a small sphere at a vertex of a large triangle is culled only when it is apart by more
/// than about 8u times its distance to the far vertices, as it must be when the axis itself is
/// rounded at the scale of the triangle.
/// With `complete`, the axes also include the directions from each vertex to c and from each edge
/// to c (e x ((c - a) x e)): with the normal, these hold the direction from the triangle's closest
/// point to c whatever its feature (face, edge, vertex; also for segments and points), so a ball
/// apart by more than the rounding bound is always separated: a test of the ball against the
/// triangle that never misses a touching pair, and reports a non-touching one only within about
/// 8u times the distances from c to the vertices (the scene's sphere–mesh leaf test). `hint`, when
/// given, is tried first (for example c minus a rounded closest point: usually the one axis needed).
template <class S>
inline bool sphere_may_touch_triangle(const Vec3<S>& c, S r, const Triangle<S>& t, bool complete = false, const Vec3<S>* hint = nullptr) {
  using T = std::conditional_t<(sizeof(S) < sizeof(double)), double, S>;
  constexpr T u = std::numeric_limits<T>::epsilon() / T(2);
  constexpr T mu = std::numeric_limits<T>::min();
  constexpr T inf = std::numeric_limits<T>::infinity();
  const Vec3<T> p = c.template cast<T>();
  const Vec3<T> v0 = t.a.template cast<T>(), v1 = t.b.template cast<T>(), v2 = t.c.template cast<T>();
  const Vec3<T> q0 = p - v0;
  const T rr = T(r) * (T(1) + T(8) * u);
  // True when w separates the sphere from the triangle (on the + side of w, or on either side).
  // A quick look at the first vertex rules most axes out; "does not separate" is always a safe
  // answer, so only a claimed separation is confirmed with the bound.
  auto separates = [&](const Vec3<T>& w, bool both_sides) {
    const T ww = w.squaredNorm();
    const T reach2 = rr * (rr * ww) + mu;  // >= (r |w|)^2 (1 + 8u), see below
    const T s0 = w.dot(q0);
    if (!(s0 * s0 > reach2) || (s0 < T(0) && !both_sides)) return false;
    if (!(ww >= mu)) return false;  // subnormal axis: no verdict
    const Vec3<T> q1 = p - v1, q2 = p - v2;
    const Vec3<T> qmax = q0.cwiseAbs().cwiseMax(q1.cwiseAbs()).cwiseMax(q2.cwiseAbs());
    const T beta = T(8) * u * w.cwiseAbs().dot(qmax) + mu;  // bounds the error of each s
    if (!(beta < inf)) return false;                           // an overflow or NaN in w or q
    const T s1 = w.dot(q1), s2 = w.dot(q2);
    const T lo = s0 > T(0) ? std::min(s0, std::min(s1, s2)) - beta : -std::max(s0, std::max(s1, s2)) - beta;
    return lo > T(0) && lo * lo > reach2;
  };
  if (hint && separates(hint->template cast<T>(), false)) return false;
  const Vec3<T> e0 = v1 - v0, e2 = v0 - v2;
  const Vec3<T> n = e0.cross(-e2);
  if (separates(n, true)) return false;
  // in-plane edge normals, pointing away from the triangle for CCW (a, b, c) about n
  if (separates(e0.cross(n), false)) return false;
  if (separates((v2 - v1).cross(n), false)) return false;
  if (separates(e2.cross(n), false)) return false;
  if (!complete) return true;
  const Vec3<T> q1 = p - v1, q2 = p - v2;
  if (separates(q0, false) || separates(q1, false) || separates(q2, false)) return false;
  // e x (q x e) is of the third power of the lengths: scaled to a largest component of 1 (any
  // scaling is allowed) so that its squared norm neither over- nor underflows
  const auto scaled = [&](const Vec3<T>& w) {
    const T m = w.cwiseAbs().maxCoeff();
    return m > T(0) && m < inf ? Vec3<T>(w / m) : w;
  };
  const Vec3<T> e1 = v2 - v1;
  if (separates(scaled(e0.cross(q0.cross(e0))), false) || separates(scaled(e1.cross(q1.cross(e1))), false) ||
      separates(scaled(e2.cross(q2.cross(e2))), false))
    return false;
  return true;
}

/// Per-query padding of the node tests of mesh_collide for a relative transform b_to_a = (M, t)
/// that is not exactly the identity. Each bound below is a forward error bound at the scale of the
/// inputs actually used: P_a and P_b bound the coordinates (and node centres) of each mesh
/// (MeshBvh::coordinate_bound), u is the unit roundoff of S, gamma_k = k u / (1 - k u) <= (k+1) u.
///  - The narrow phase tests A's triangle against fl(M v + t) for B's vertices v. Component i of
///    fl(M p + t) is off by at most gamma_4 (sum_j |M_ij| |p_j| + |t_i|) <= e_b := 8u (|M|_inf P_b +
///    |t|_inf) for |p|_inf <= P_b (Higham 3.1); in length, sqrt(3) e_b.
///  - M is the rounded product of the poses, maybe not orthonormal. With G = M^T M - I,
///    |G|_2 <= sum_ij |G_ij| <= g := (sum_ij |fl(G_ij)|)(1 + 16u) + 16u (|M|_F^2 + 3) (each entry
///    rounded by gamma_4 (sum_k |M_ki| |M_kj| + 1)), so |M|_2 <= sqrt(1 + g) and the least singular
///    value of M is at least sqrt(1 - g); M M^T - I has the same 2-norm as G.
///  - Sphere of B (centre c, radius r) seen from A: every vertex fl(M v + t) of B's triangles in it
///    lies within |M|_2 r + 2 sqrt(3) e_b of fl(M c + t) (both rounded by at most sqrt(3) e_b).
///  - Sphere of A (centre c, radius r) seen from B, for B's leaf triangles tested in B's frame at
///    c' = fl(M^T c + t'), t' = fl(-(M^T t)): if a point x of A's triangle (|x - c| <= r) lies on
///    B's moved triangle, the same barycentric point z of B's triangle has |M z + t - x| <=
///    sqrt(3) e_b. With rho = M c' + t - c = (M M^T - I)(c - t) + M (d1 + d2), d2 the rounding of
///    t' (<= gamma_3 |M|_1 |t|_inf a component) and d1 that of c' (<= gamma_4 (|M|_1 P_a + |t'|_inf)),
///    |z - c'| <= (r + sqrt(3) e_b + |rho|) / sqrt(1 - g), which is the radius used (g < 1/2 is
///    required, else this cull is off).
///  - Box of B (centre cb, half extents eb, rounded from its min/max by at most 2u P_b) seen from A
///    (centre ca, half extents ea, rounded by at most 2u P_a): obb_overlap covers its own rounding
///    for an orthonormal R. The narrow phase's vertex rounding and the rounding of fl(M cb + t) - ca
///    (at most e_b + u (|M|_inf P_b + |t|_inf + P_a) a component) enlarge A's box by a cube
///    (Minkowski sum, exact for an axis-aligned box). For a non-orthonormal M, the radius of B on
///    the axes built from M's columns is off by at most g times the sum of B's half extents: B's
///    half extents are enlarged by 4 g sum(eb) (each unit of padding adds at least 1 - 2g to B's
///    radius on any axis obb_overlap uses).
/// Every computed pad is rounded up by a factor (1 + 4u) or more; P_a, P_b, |t| and the norms are
/// exact or rounded within that factor.
template <class S> struct PosePad {
  bool identity = true;  ///< M = I and t = 0 exactly: B's vertices are not moved by rounding
  S stretch = 1;         ///< >= |M|_2
  S b_abs = 0;           ///< 2 sqrt(3) e_b: added to B's sphere radius seen from A
  bool a_ok = true;      ///< the cull of B's leaf triangles against A's sphere may run
  S a_scale = 1, a_abs = 0;  ///< A's sphere radius seen from B: (r + a_abs) a_scale
  S box_a = 0, box_b = 0, box_g = 0;  ///< AABB: ea + box_a, eb + box_b + box_g sum(eb)

  PosePad() = default;
  PosePad(const RigidTransform<S>& x, S pa, S pb) {
    const Mat3<S>& M = x.R;
    identity = M == Mat3<S>::Identity() && (x.t.array() == S(0)).all();
    if (identity) return;
    constexpr S u = std::numeric_limits<S>::epsilon() / S(2);
    const S up = S(1) + S(4) * u;
    const S g = rotation_defect_bound(M);
    const S m_inf = M.cwiseAbs().rowwise().sum().maxCoeff(), m_one = M.cwiseAbs().colwise().sum().maxCoeff();
    const S t_inf = x.t.cwiseAbs().maxCoeff();
    const S sqrt3 = S(1.7320508075688773) * up;
    stretch = std::sqrt(S(1) + g) * up;
    const S e_b = S(8) * u * (m_inf * pb + t_inf) * up;
    b_abs = S(2) * sqrt3 * e_b * up;
    a_ok = g < S(0.5);
    if (a_ok) {
      const S t2_inf = (m_one * t_inf) * (S(1) + S(4) * u);  // |t'|_inf bound
      const S d2 = S(4) * u * m_one * t_inf;
      const S d1 = S(5) * u * (m_one * pa + t2_inf);
      const S rho = g * sqrt3 * (pa + t_inf) + stretch * sqrt3 * (d1 + d2);
      a_abs = (sqrt3 * e_b + rho) * up;
      a_scale = up * up / std::sqrt(S(1) - g);
    }
    box_a = (e_b + S(2) * u * (m_inf * pb + t_inf + pa) + S(2) * u * pa) * S(2) * up;
    box_b = S(4) * u * pb * up;
    box_g = S(4) * g * up;
  }
};

/// Node test of the mesh queries: the BVs must overlap (spheres and AABBs padded by PosePad for the
/// rounding of the relative transform; other BVs by their traits) and, for sphere trees when exactly one node is a leaf, the other node's
/// sphere must touch one of the leaf's triangles. Conservative: never false for a node pair under
/// which the narrow phase would find a pair (see PosePad and sphere_may_touch_triangle).
template <class BV> struct MeshNodeOverlap {
  using S = typename BvTraits<BV>::Scalar;
  static constexpr bool kSphere = std::is_same_v<BV, Sphere<S>>;
  static constexpr bool kObb = std::is_same_v<BV, Obb<S>>;
  static constexpr bool kPadded = kSphere || std::is_same_v<BV, Aabb<S>>;
  /// Oriented boxes: the edge axes the walk's node test tries, a_i x b_j for i, j < 2 (obb_overlap;
  /// the in-plane axes of the fitted boxes). The five left out rejected 119 of the bunny's 26,822
  /// node tests (1,000 boolean queries); without them the walk tests 1.4 % more node pairs at 10 %
  /// fewer instructions in all (env/rob: 5.3 % more pairs, 5.4 % fewer instructions). The root
  /// pair keeps all nine (first_overlap).
  static constexpr int kObbEdgeAxes = 2;
  struct NoFrame {
    explicit NoFrame(const RigidTransform<S>&) {}
  };
  struct Unused {};  // a member this BV's test does not use: nothing to set up per query
  const MeshBvh<BV>& a;
  const MeshBvh<BV>& b;
  const RigidTransform<S>& b_to_a;  ///< the query's own (it outlives the node test)
  std::conditional_t<kSphere, RigidTransform<S>, Unused> a_to_b;
  std::uint64_t* tests;
  std::conditional_t<kPadded, PosePad<S>, Unused> pad;
  /// oriented boxes: X's defect bounded once for every pair of validated poses
  /// (ObbPairFrame::validated_product_defect: x must be relative_transform of two poses that passed
  /// validate_pose, as in collide and collides)
  std::conditional_t<kObb, ObbPairFrame<S>, NoFrame> frame;
  struct NoImage {};
  /// oriented boxes: the image of the last node of B tested, reused while the walk splits A's
  /// nodes against it (a query's own object: never shared between threads); its axes are computed
  /// by the first test that gets past the balls
  mutable std::conditional_t<kObb, typename ObbPairFrame<S>::Image, NoImage> image_b;
  mutable const BvhNode<BV>* imaged_b = nullptr;
  /// oriented boxes: true until the first node test (the walk's first pair, the roots')
  mutable bool first_test = true;

  template <class B = BV, std::enable_if_t<std::is_same_v<B, Obb<S>>, int> = 0>
  static ObbPairFrame<S> make_frame(const RigidTransform<S>& x) {
    return ObbPairFrame<S>(x, ObbPairFrame<S>::validated_product_defect());
  }
  template <class B = BV, std::enable_if_t<!std::is_same_v<B, Obb<S>>, int> = 0>
  static NoFrame make_frame(const RigidTransform<S>& x) {
    return NoFrame(x);
  }
  template <class B = BV, std::enable_if_t<std::is_same_v<B, Sphere<S>>, int> = 0>
  static RigidTransform<S> make_inverse(const RigidTransform<S>& x) {
    return x.inverse();
  }
  template <class B = BV, std::enable_if_t<!std::is_same_v<B, Sphere<S>>, int> = 0>
  static Unused make_inverse(const RigidTransform<S>&) {
    return {};
  }

  MeshNodeOverlap(const MeshBvh<BV>& a_, const MeshBvh<BV>& b_, const RigidTransform<S>& x, std::uint64_t* counter)
      : a(a_), b(b_), b_to_a(x), a_to_b(make_inverse(x)), tests(counter), frame(make_frame(x)) {
    // oriented boxes bound the rounding and the defect of the transform in their own test
    if constexpr (kPadded) pad = PosePad<S>(x, a_.coordinate_bound(), b_.coordinate_bound());
  }

  /// The first node test of a walk, for oriented boxes: where a node is its tree's root, the
  /// slabs measured around the whole mesh (MeshBvh::root_slabs) are tried too when the 15 axes
  /// fail (the bunny against itself, the bench's 1,000 poses: 504 -> 616 decided at the roots).
  /// Only there: the pairs of B's root with A's inner nodes pass the 15 axes too often to pay for
  /// them (env/rob: median 1.49 -> 1.96 µs with the slabs on every pair with a root). Out of line,
  /// so that the walk's own node test stays as small as it was.
  IMPACT_NOINLINE bool first_overlap(const BvhNode<BV>& na, const BvhNode<BV>& nb) const {
    const ObbSlabs<S>* sa = &na == a.tree().nodes.data() && a.root_slabs().valid ? &a.root_slabs() : nullptr;
    const ObbSlabs<S>* sb = &nb == b.tree().nodes.data() && b.root_slabs().valid ? &b.root_slabs() : nullptr;
    return frame.overlaps_with_slabs(na.bv, image_b, nb.bv, sa, sb);
  }
  bool leaf_touches(const MeshBvh<BV>& m, const BvhNode<BV>& leaf, const Vec3<S>& c, S r) const {
    for (std::int32_t k = leaf.first; k < leaf.first + leaf.count; ++k)
      if (sphere_may_touch_triangle(c, r, m.triangle(m.tree().primitives[static_cast<std::size_t>(k)]))) return true;
    return false;
  }
  bool operator()(const BvhNode<BV>& na, const BvhNode<BV>& nb) const {
    ++*tests;
    if constexpr (std::is_same_v<BV, Sphere<S>>) {
      constexpr S u = std::numeric_limits<S>::epsilon() / S(2);
      const Vec3<S> cb = pad.identity ? nb.bv.center : b_to_a.apply(nb.bv.center);
      const S rb = pad.identity ? nb.bv.radius : (pad.stretch * nb.bv.radius + pad.b_abs) * (S(1) + S(4) * u);
      const S rs = na.bv.radius + rb;
      // the squared distance and the squared sum are each within a relative 4u of their values
      if (!((na.bv.center - cb).squaredNorm() <= rs * rs * (S(1) + S(16) * u))) return false;
      if (na.is_leaf() && !nb.is_leaf()) return leaf_touches(a, na, cb, rb);
      if (nb.is_leaf() && !na.is_leaf()) {
        if (pad.identity) return leaf_touches(b, nb, na.bv.center, na.bv.radius);
        if (!pad.a_ok) return true;
        return leaf_touches(b, nb, a_to_b.apply(na.bv.center), (na.bv.radius + pad.a_abs) * pad.a_scale);
      }
      return true;
    } else if constexpr (std::is_same_v<BV, Aabb<S>>) {
      if (pad.identity) return BvTraits<BV>::overlap(na.bv, nb.bv);
      const Vec3<S> ea = (na.bv.max - na.bv.min) / S(2) + Vec3<S>::Constant(pad.box_a);
      const Vec3<S> eb0 = (nb.bv.max - nb.bv.min) / S(2);
      const Vec3<S> eb = eb0 + Vec3<S>::Constant(pad.box_b + pad.box_g * eb0.sum());
      const Vec3<S> tb = b_to_a.apply(nb.bv.center()) - na.bv.center();
      return obb_overlap<S>(ea, b_to_a.R, tb, eb);
    } else if constexpr (kObb) {
      if (imaged_b != &nb) {
        image_b = frame.image_centre(nb.bv);
        imaged_b = &nb;
      }
      if (first_test) {
        first_test = false;
        return first_overlap(na, nb);
      }
      return frame.template overlaps<kObbEdgeAxes>(na.bv, image_b, nb.bv);
    } else {
      return BvTraits<BV>::overlap(na.bv, nb.bv, b_to_a);  // other BVs bound their own rounding (see their traits)
    }
  }
};

/// The walk order of the boolean queries: of two children, the one whose centre is nearer the
/// other node's centre first. A stopped walk reaches a colliding pair sooner on average (the bunny
/// against itself, SAH OBB trees, 1,000 random poses: 192 -> 95 node tests for the colliding ones);
/// a walk that finds nothing visits the same node pairs either way. A split of a node of A compares
/// in A's frame, against the other node's centre moved by X (for oriented boxes, the image the
/// node test has just computed, `overlap`); a split of a node of B compares in B's frame, against
/// X^T (c_a - t): one product per split, none for the children. A heuristic only: X off a rotation
/// by rounding changes which child is nearer at ties at most. For spheres and AABBs the first
/// `kFree` node tests keep the tree's order: most queries are decided within a few (the poses far
/// apart), and they would only pay for the comparisons. Oriented boxes order every split: their
/// node test costs several times the comparison (the bunny against itself, 1,000 poses, callgrind:
/// +86 instructions per query on the 817 free poses, -21,500 on the 183 colliding ones).
template <class BV> struct NearestChildFirst {
  using S = typename BvTraits<BV>::Scalar;
  static constexpr std::uint64_t kFree = MeshNodeOverlap<BV>::kObb ? 0 : 8;
  const RigidTransform<S>& b_to_a;
  const std::uint64_t& tests;  // the query's node tests so far
  const MeshNodeOverlap<BV>* overlap = nullptr;
  bool right_first_a(const BV& left, const BV& right, const BV& other_b) const {
    if constexpr (kFree > 0) {
      if (tests < kFree) return false;
    }
    Vec3<S> c;
    if constexpr (MeshNodeOverlap<BV>::kObb) {
      if (overlap && overlap->imaged_b && &overlap->imaged_b->bv == &other_b) c = overlap->image_b.center;
      else c = b_to_a.apply(BvTraits<BV>::center(other_b));
    } else {
      c = b_to_a.apply(BvTraits<BV>::center(other_b));
    }
    return (BvTraits<BV>::center(right) - c).squaredNorm() < (BvTraits<BV>::center(left) - c).squaredNorm();
  }
  bool right_first_b(const BV& other_a, const BV& left, const BV& right) const {
    if constexpr (kFree > 0) {
      if (tests < kFree) return false;
    }
    const Vec3<S> c = b_to_a.R.transpose() * (BvTraits<BV>::center(other_a) - b_to_a.t);
    return (BvTraits<BV>::center(right) - c).squaredNorm() < (BvTraits<BV>::center(left) - c).squaredNorm();
  }
};

template <class S> MeshContact<S> make_contact(const Triangle<S>& ta, const Triangle<S>& tb_in_a, const RigidTransform<S>& pose_a,
                                              std::int32_t ia, std::int32_t ib) {
  MeshContact<S> c;
  c.triangle_a = ia;
  c.triangle_b = ib;
  const auto hit = triangle_intersection(ta, tb_in_a);
  const Vec3<S> p = hit ? hit->point : ta.centroid();
  c.point = pose_a.apply(p);
  c.normal_a = pose_a.rotate(ta.normal());
  c.normal_b = pose_a.rotate(tb_in_a.normal());
  return c;
}

}  // namespace detail

/// Colliding triangle pairs of mesh a (at pose_a) and mesh b (at pose_b). Both trees must use the
/// same BV type. Boolean mode (default) stops at the first pair found. Throws InvalidInput when a
/// pose is not rigid (validate_pose).
template <class BV>
CollideResult<typename BvTraits<BV>::Scalar> collide(const MeshBvh<BV>& a, const RigidTransform<typename BvTraits<BV>::Scalar>& pose_a,
                                                     const MeshBvh<BV>& b, const RigidTransform<typename BvTraits<BV>::Scalar>& pose_b,
                                                     const CollideOptions& options = {}) {
  using S = typename BvTraits<BV>::Scalar;
  validate_pose(pose_a, "collide", "pose_a");
  validate_pose(pose_b, "collide", "pose_b");
  CollideResult<S> result;
  const RigidTransform<S> b_to_a = relative_transform(pose_a, pose_b);
  const detail::MeshNodeOverlap<BV> overlap(a, b, b_to_a, &result.stats.bv_tests);
  auto visit = [&](std::int32_t p, std::int32_t q) {
    ++result.stats.primitive_tests;
    const Triangle<S>& ta = a.triangle(p);
    const Triangle<S>& tb = b.triangle(q);
    const Triangle<S> tb_a(b_to_a.apply(tb.a), b_to_a.apply(tb.b), b_to_a.apply(tb.c));
    if (!triangles_intersect(ta, tb_a)) return true;
    result.colliding = true;
    result.pairs.emplace_back(a.triangle_id(p), b.triangle_id(q));
    if (options.contacts) result.contacts.push_back(detail::make_contact(ta, tb_a, pose_a, a.triangle_id(p), b.triangle_id(q)));
    return options.all_pairs && result.pairs.size() < options.max_pairs;  // boolean mode stops here
  };
  if (options.all_pairs)
    traverse_pair_nodes(a.tree(), b.tree(), overlap, visit);
  else
    traverse_pair_nodes(a.tree(), b.tree(), overlap, visit, 0, 0, detail::NearestChildFirst<BV>{b_to_a, result.stats.bv_tests, &overlap});
  return result;
}

/// Boolean query: true when the meshes intersect. Stops at the first colliding pair. Throws
/// InvalidInput when a pose is not rigid (validate_pose).
template <class BV>
bool collides(const MeshBvh<BV>& a, const RigidTransform<typename BvTraits<BV>::Scalar>& pose_a, const MeshBvh<BV>& b,
              const RigidTransform<typename BvTraits<BV>::Scalar>& pose_b, QueryStats* stats = nullptr) {
  using S = typename BvTraits<BV>::Scalar;
  validate_pose(pose_a, "collides", "pose_a");
  validate_pose(pose_b, "collides", "pose_b");
  const RigidTransform<S> b_to_a = relative_transform(pose_a, pose_b);
  QueryStats st;
  bool hit = false;
  const detail::MeshNodeOverlap<BV> overlap(a, b, b_to_a, &st.bv_tests);
  traverse_pair_nodes(
      a.tree(), b.tree(), overlap,
      [&](std::int32_t p, std::int32_t q) {
        ++st.primitive_tests;
        const Triangle<S>& tb = b.triangle(q);
        hit = triangles_intersect(a.triangle(p), Triangle<S>(b_to_a.apply(tb.a), b_to_a.apply(tb.b), b_to_a.apply(tb.c)));
        return !hit;
      },
      0, 0, detail::NearestChildFirst<BV>{b_to_a, st.bv_tests, &overlap});
  if (stats) *stats = st;
  return hit;
}

/// Self-collision: pairs of triangles of one mesh that intersect, excluding adjacent triangles
/// (those sharing a vertex index, whose contact is the shared vertex or edge). Pairs are reported
/// once, as (smaller row, larger row).
template <class BV> CollideResult<typename BvTraits<BV>::Scalar> self_collide(const MeshBvh<BV>& m, const CollideOptions& options = {}) {
  using S = typename BvTraits<BV>::Scalar;
  CollideResult<S> result;
  auto overlap = [&](const BV& x, const BV& y) {
    ++result.stats.bv_tests;
    if constexpr (std::is_same_v<BV, Sphere<S>>) {
      // padded: the squared distance and the squared sum are each within a relative 4u
      const S rs = x.radius + y.radius;
      return (x.center - y.center).squaredNorm() <= rs * rs * (S(1) + S(8) * std::numeric_limits<S>::epsilon());
    } else {
      return BvTraits<BV>::overlap(x, y);  // exact comparisons for boxes
    }
  };
  auto visit = [&](std::int32_t p, std::int32_t q) {
    if (m.adjacent(p, q)) return true;
    ++result.stats.primitive_tests;
    if (!triangles_intersect(m.triangle(p), m.triangle(q))) return true;
    result.colliding = true;
    std::int32_t ia = m.triangle_id(p), ib = m.triangle_id(q);
    Triangle<S> ta = m.triangle(p), tb = m.triangle(q);
    if (ia > ib) std::swap(ia, ib), std::swap(ta, tb);
    result.pairs.emplace_back(ia, ib);
    if (options.contacts) result.contacts.push_back(detail::make_contact(ta, tb, RigidTransform<S>{}, ia, ib));
    return options.all_pairs && result.pairs.size() < options.max_pairs;
  };
  traverse_self(m.tree(), overlap, visit);
  return result;
}

}  // namespace impact
