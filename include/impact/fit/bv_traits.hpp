// SPDX-License-Identifier: MIT
/// \file
/// BvTraits<BV>: what the hierarchy needs to know about a bounding volume, so that the builder, refit
/// and both traversals are written once for every BV type.
///  - Scalar                    the scalar type
///  - fit(points, n, config)    a BV around points (fitting a node around its primitives' vertices
///                              is tighter than merging its children's BVs)
///  - merge(a, b)               a BV around two BVs (refit of inner nodes, broad phase)
///  - size(bv)                  a length used by pair traversal to descend the larger node first
///  - overlap(a, b)             both in one frame
///  - overlap(a, b, xf)         b given in its own frame, xf maps b's frame into a's frame
///  - transformed(bv, xf)       a BV around xf(bv) (exact for spheres; a looser box for AABBs)
/// Each overlap test is conservative: it never returns false for touching or overlapping volumes.
#pragma once

#include "impact/fit/bounding_sphere.hpp"
#include "impact/fit/obb_fit.hpp"
#include "impact/geometry/aabb.hpp"
#include "impact/geometry/obb.hpp"
#include "impact/geometry/obb_pair_frame.hpp"
#include "impact/geometry/sphere.hpp"
#include "impact/geometry/transform.hpp"

namespace impact {

/// Options for fitting BVs: spheres and oriented boxes have a choice of method.
struct FitConfig {
  SphereFit sphere = SphereFit::AabbCenter;
  /// How oriented boxes choose their axes. MeshBvh passes each node's triangles as consecutive
  /// vertex triples, so the default weighs the triangles by area (see fit/obb_fit.hpp).
  ObbFit obb = ObbFit::TriangleArea;
};

template <class BV> struct BvTraits;

template <class S_> struct BvTraits<Sphere<S_>> {
  using S = S_;
  using Scalar = S_;
  static constexpr const char* name = "sphere";

  static Sphere<S> fit(const Vec3<S>* pts, std::size_t n, const FitConfig& cfg = {}) { return bounding_sphere(pts, n, cfg.sphere); }
  static Sphere<S> merge(const Sphere<S>& a, const Sphere<S>& b) { return impact::merge(a, b); }
  static S size(const Sphere<S>& a) { return a.radius; }
  static Vec3<S> center(const Sphere<S>& a) { return a.center; }
  static bool overlap(const Sphere<S>& a, const Sphere<S>& b) { return impact::overlap(a, b); }
  /// b's centre is moved by xf with rounding at the scale of the coordinates, not of the radii:
  /// each component of fl(M c + t) is within e = 8u (|M|_inf |c|_inf + |t|_inf) of M c + t
  /// (Higham 3.1), so sqrt(3) e is added to the radii. xf is taken as rigid; the mesh queries pad
  /// for a rounded, not quite orthonormal relative pose and for the moved vertices
  /// (query/mesh_collide.hpp, PosePad).
  static bool overlap(const Sphere<S>& a, const Sphere<S>& b, const RigidTransform<S>& xf) {
    constexpr S u = std::numeric_limits<S>::epsilon() / S(2);
    const S e = S(8) * u * (xf.R.cwiseAbs().rowwise().sum().maxCoeff() * b.center.cwiseAbs().maxCoeff() + xf.t.cwiseAbs().maxCoeff());
    const S r = (a.radius + b.radius + S(1.7320508075688774) * e) * (S(1) + S(4) * u);
    return (a.center - xf.apply(b.center)).squaredNorm() <= r * r * (S(1) + S(16) * u);
  }
  static Sphere<S> transformed(const Sphere<S>& a, const RigidTransform<S>& xf) { return {xf.apply(a.center), a.radius}; }
  static Sphere<S> inflated(const Sphere<S>& a, S margin) { return {a.center, a.radius + margin}; }
};

template <class S_> struct BvTraits<Aabb<S_>> {
  using S = S_;
  using Scalar = S_;
  static constexpr const char* name = "aabb";

  static Aabb<S> fit(const Vec3<S>* pts, std::size_t n, const FitConfig& = {}) {
    Aabb<S> box;
    for (std::size_t i = 0; i < n; ++i) box.extend(pts[i]);
    return box;
  }
  static Aabb<S> merge(const Aabb<S>& a, const Aabb<S>& b) { return impact::merge(a, b); }
  static S size(const Aabb<S>& a) { return a.half_diagonal(); }
  static Vec3<S> center(const Aabb<S>& a) { return a.center(); }
  static bool overlap(const Aabb<S>& a, const Aabb<S>& b) { return impact::overlap(a, b); }
  /// b is an oriented box in a's frame: separating-axis test (15 axes).
  static bool overlap(const Aabb<S>& a, const Aabb<S>& b, const RigidTransform<S>& xf) {
    const Vec3<S> ea = (a.max - a.min) / S(2);
    const Vec3<S> eb = (b.max - b.min) / S(2);
    const Vec3<S> tb = xf.apply(b.center()) - a.center();
    return obb_overlap<S>(ea, xf.R, tb, eb);
  }
  static Aabb<S> transformed(const Aabb<S>& a, const RigidTransform<S>& xf) {
    const Vec3<S> c = xf.apply(a.center());
    const Vec3<S> e = xf.R.cwiseAbs() * ((a.max - a.min) / S(2));
    return {c - e, c + e};
  }
  static Aabb<S> inflated(const Aabb<S>& a, S margin) { return {a.min.array() - margin, a.max.array() + margin}; }
};

template <class S_> struct BvTraits<Obb<S_>> {
  using S = S_;
  using Scalar = S_;
  static constexpr const char* name = "obb";

  static Obb<S> fit(const Vec3<S>* pts, std::size_t n, const FitConfig& cfg = {}) { return fit_obb(pts, n, cfg.obb); }
  /// A box around both, on the axes of the larger one (refit by merging). Its corners are rounded
  /// to S, so the result is grown by a bound of that rounding.
  static Obb<S> merge(const Obb<S>& a, const Obb<S>& b) {
    if ((a.half.array() < S(0)).any()) return b;
    if ((b.half.array() < S(0)).any()) return a;
    Vec3<S> ca[8], cb[8], pts[16];
    obb_corners(a, ca);
    obb_corners(b, cb);
    std::copy(ca, ca + 8, pts);
    std::copy(cb, cb + 8, pts + 8);
    Obb<S> m = fit_obb_with_axes(pts, 16, size(a) >= size(b) ? a.axes : b.axes);
    const S grow = S(8) * std::numeric_limits<S>::epsilon() *
                   (std::max(a.center.cwiseAbs().maxCoeff(), b.center.cwiseAbs().maxCoeff()) + std::max(a.half.sum(), b.half.sum()));
    m.half.array() += grow;
    m.radius += grow * S(2);  // the corners' ball, grown as the box (sqrt(3) times the per-axis growth)
    return m;
  }
  static S size(const Obb<S>& a) { return a.half.norm(); }
  static Vec3<S> center(const Obb<S>& a) { return a.center; }
  static bool overlap(const Obb<S>& a, const Obb<S>& b) { return ObbPairFrame<S>::overlaps_in_one_frame(a, b); }
  /// Separating-axis test (15 axes) of a and xf(b) in a's frame. Conservative under rounding and
  /// for an xf.R that is a rotation only within rotation_tolerance (see ObbPairFrame, which pair
  /// traversals use directly to reuse a's frame across tests).
  static bool overlap(const Obb<S>& a, const Obb<S>& b, const RigidTransform<S>& xf) {
    return ObbPairFrame<S>(xf).overlaps(a, b);
  }
  static Obb<S> transformed(const Obb<S>& a, const RigidTransform<S>& xf) {
    Obb<S> o{xf.apply(a.center), xf.R * a.axes, a.half, a.radius};
    const S grow = S(16) * std::numeric_limits<S>::epsilon() * (o.center.cwiseAbs().maxCoeff() + a.half.sum());
    o.half.array() += grow;
    o.radius += S(2) * grow + S(4) * std::numeric_limits<S>::epsilon() * a.radius;
    return o;
  }
  static Obb<S> inflated(const Obb<S>& a, S margin) { return {a.center, a.axes, (a.half.array() + margin).matrix(), a.radius + margin}; }
};

namespace detail {

/// True for the BVs whose ray and closest-point keys are lower bounds of every triangle's computed
/// value, not only up to rounding (boxes, and oriented boxes through their axis-aligned hulls;
/// query/ray_mesh.hpp, query/closest_point_mesh.hpp): those queries prune nodes at the best value
/// found, and equal the brute-force loops bit for bit.
template <class BV> inline constexpr bool exact_query_keys = false;
template <class S> inline constexpr bool exact_query_keys<Aabb<S>> = true;
template <class S> inline constexpr bool exact_query_keys<Obb<S>> = true;

}  // namespace detail

}  // namespace impact
