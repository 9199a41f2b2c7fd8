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
#include "impact/geometry/transform.hpp"
#include "impact/narrow/triangle_triangle.hpp"

#include <cstdint>
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

/// Conservative: false only when the sphere (centre c, radius r) cannot touch the triangle. Four
/// separating axes: the triangle's normal and its three in-plane edge normals. Much tighter than a
/// sphere around a long thin triangle, which is what makes leaf-versus-node tests pay off. The
/// radius is padded relatively so rounding can only make the test accept more.
template <class S> inline bool sphere_may_touch_triangle(const Vec3<S>& c, S r, const Triangle<S>& t) {
  const S rr = r * (S(1) + S(64) * std::numeric_limits<S>::epsilon());
  const Vec3<S> n = (t.b - t.a).cross(t.c - t.a);
  const S nn = n.squaredNorm();
  if (!(nn > S(0))) return true;  // degenerate triangle: no plane to test against
  const S d = n.dot(c - t.a);
  if (d * d > rr * rr * nn) return false;
  const Vec3<S>* v[3] = {&t.a, &t.b, &t.c};
  for (int k = 0; k < 3; ++k) {
    const Vec3<S>& p = *v[k];
    const Vec3<S> m = (*v[(k + 1) % 3] - p).cross(n);  // points away from the triangle for CCW (a, b, c) about n
    const S e = m.dot(c - p);
    if (e > S(0) && e * e > rr * rr * m.squaredNorm()) return false;
  }
  return true;
}

/// Node test of the mesh queries for sphere trees: the spheres must overlap and, when exactly one
/// node is a leaf, the other node's sphere must touch one of the leaf's triangles. For other BV
/// types, the BV test alone.
template <class BV> struct MeshNodeOverlap {
  using S = typename BvTraits<BV>::Scalar;
  const MeshBvh<BV>& a;
  const MeshBvh<BV>& b;
  RigidTransform<S> b_to_a, a_to_b;
  std::uint64_t* tests;

  bool leaf_touches(const MeshBvh<BV>& m, const BvhNode<BV>& leaf, const Vec3<S>& c, S r) const {
    for (std::int32_t k = leaf.first; k < leaf.first + leaf.count; ++k)
      if (sphere_may_touch_triangle(c, r, m.triangle(m.tree().primitives[static_cast<std::size_t>(k)]))) return true;
    return false;
  }
  bool operator()(const BvhNode<BV>& na, const BvhNode<BV>& nb) const {
    ++*tests;
    if (!BvTraits<BV>::overlap(na.bv, nb.bv, b_to_a)) return false;
    if constexpr (std::is_same_v<BV, Sphere<S>>) {
      if (na.is_leaf() && !nb.is_leaf()) return leaf_touches(a, na, b_to_a.apply(nb.bv.center), nb.bv.radius);
      if (nb.is_leaf() && !na.is_leaf()) return leaf_touches(b, nb, a_to_b.apply(na.bv.center), na.bv.radius);
    }
    return true;
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
  const detail::MeshNodeOverlap<BV> overlap{a, b, b_to_a, b_to_a.inverse(), &result.stats.bv_tests};
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
  traverse_pair_nodes(a.tree(), b.tree(), overlap, visit);
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
  const detail::MeshNodeOverlap<BV> overlap{a, b, b_to_a, b_to_a.inverse(), &st.bv_tests};
  traverse_pair_nodes(
      a.tree(), b.tree(), overlap,
      [&](std::int32_t p, std::int32_t q) {
        ++st.primitive_tests;
        const Triangle<S>& tb = b.triangle(q);
        hit = triangles_intersect(a.triangle(p), Triangle<S>(b_to_a.apply(tb.a), b_to_a.apply(tb.b), b_to_a.apply(tb.c)));
        return !hit;
      });
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
    return BvTraits<BV>::overlap(x, y);
  };
  auto visit = [&](std::int32_t p, std::int32_t q) {
    if (m.adjacent(p, q)) return true;
    ++result.stats.primitive_tests;
    if (!triangles_intersect(m.triangle(p), m.triangle(q))) return true;
    result.colliding = true;
    std::int32_t ia = m.triangle_id(p), ib = m.triangle_id(q);
    const Triangle<S>* ta = &m.triangle(p);
    const Triangle<S>* tb = &m.triangle(q);
    if (ia > ib) std::swap(ia, ib), std::swap(ta, tb);
    result.pairs.emplace_back(ia, ib);
    if (options.contacts) result.contacts.push_back(detail::make_contact(*ta, *tb, RigidTransform<S>{}, ia, ib));
    return options.all_pairs && result.pairs.size() < options.max_pairs;
  };
  traverse_self(m.tree(), overlap, visit);
  return result;
}

}  // namespace impact
