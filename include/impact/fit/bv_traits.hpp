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
#include "impact/geometry/aabb.hpp"
#include "impact/geometry/obb.hpp"
#include "impact/geometry/sphere.hpp"
#include "impact/geometry/transform.hpp"

namespace impact {

/// Options for fitting BVs; only spheres have a choice of method.
struct FitConfig {
  SphereFit sphere = SphereFit::AabbCenter;
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
  static bool overlap(const Sphere<S>& a, const Sphere<S>& b, const RigidTransform<S>& xf) {
    const S r = a.radius + b.radius;
    return (a.center - xf.apply(b.center)).squaredNorm() <= r * r * (S(1) + S(4) * std::numeric_limits<S>::epsilon());
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

}  // namespace impact
