// SPDX-License-Identifier: MIT
/// \file
/// The bridge to libccd (Debian libccd-dev, target impact::convex): any two shapes with a support
/// function (convex/shapes.hpp, convex/convex_hull.hpp) under rigid poses, handed to libccd's
/// boolean tests (GJK: ccdGJKIntersect; MPR: ccdMPRIntersect) and penetration solvers (EPA:
/// ccdGJKPenetration; MPR: ccdMPRPenetration). libccd works in double whatever S is.
///
/// Bounded iterations: libccd bounds GJK and MPR's last phase by ccd_t::max_iterations, but its
/// EPA and its MPR portal discovery and refinement loop until their tolerance is met. Here every
/// support-function call is counted; past CcdSettings::max_iterations calls the support functions
/// of both shapes return the same point, which ends every libccd loop at its next test (the
/// Minkowski difference stops growing), and the result says limit_reached. So no query hangs, and
/// a query stopped by the bound is reported, never silently returned as converged.
///
/// Thread safety: the functions keep their state on the stack; any number of threads may call
/// them at once on shared shapes.
#pragma once

#include "impact/convex/shapes.hpp"
#include "impact/core/types.hpp"
#include "impact/geometry/transform.hpp"

#include <ccd/ccd.h>

#include <algorithm>
#include <type_traits>

namespace impact {

/// Which libccd algorithm answers a query.
enum class CcdAlgorithm : unsigned char {
  Gjk,  ///< boolean: ccdGJKIntersect; penetration: ccdGJKPenetration (GJK + EPA, minimal depth)
  Mpr   ///< boolean: ccdMPRIntersect; penetration: ccdMPRPenetration (depth along the portal direction)
};

/// libccd's settings for one query. libccd's tolerances and its internal zero tests are absolute,
/// so the shapes are handed to it in a normalised frame: centred on the midpoint of their interior
/// points and divided by `length_scale` (convex/query.hpp passes the larger shape's size). The
/// tolerances below are in that frame, i.e. relative to length_scale; the answers are scale and
/// translation invariant up to rounding.
struct CcdSettings {
  int max_iterations = 128;       ///< support calls per shape (and GJK/MPR iterations)
  double length_scale = 1;        ///< > 0: the unit of the normalised frame
  double epa_tolerance = 1e-16;   ///< libccd's ccd_t::epa_tolerance (squared relative length)
  double mpr_tolerance = 1e-10;   ///< libccd's ccd_t::mpr_tolerance (relative length)
};

/// Outcome of a libccd penetration query, in world coordinates.
template <class S>
struct CcdPenetration {
  bool intersecting = false;
  S depth = S(0);                     ///< libccd's depth (EPA: the inner polytope's distance, a lower bound)
  Vec3<S> normal = Vec3<S>::UnitZ();  ///< unit, from a towards b
  Vec3<S> point = Vec3<S>::Zero();    ///< contact point (libccd's "pos")
  int iterations = 0;                 ///< support calls per shape
  bool limit_reached = false;
};

namespace detail {

struct CcdCounter {
  long calls = 0;
  long limit = 0;
  bool exhausted = false;
};

/// Support in double of a shape whose scalar is S (the shape's own support, then cast).
template <class S, class Shape>
struct CcdShape {
  const Shape* shape;
  Mat3<double> R;
  Vec3<double> t;       // pose translation in the normalised frame (divided by the scale)
  Vec3<double> center;  // interior point in the normalised frame
  double inv_scale;
  CcdCounter* counter;
  bool counts;

  static void support_fn(const void* obj, const ccd_vec3_t* dir, ccd_vec3_t* out) {
    const auto& o = *static_cast<const CcdShape*>(obj);
    if (o.counts && ++o.counter->calls > o.counter->limit) o.counter->exhausted = true;
    if (o.counter->exhausted) {
      out->v[0] = out->v[1] = out->v[2] = 0;
      return;
    }
    const Vec3<double> d(dir->v[0], dir->v[1], dir->v[2]);
    const Vec3<S> local = (o.R.transpose() * d).template cast<S>();
    const Vec3<double> p = o.R * (support(*o.shape, local).template cast<double>() * o.inv_scale) + o.t;
    out->v[0] = p.x();
    out->v[1] = p.y();
    out->v[2] = p.z();
  }
  static void center_fn(const void* obj, ccd_vec3_t* c) {
    const auto& o = *static_cast<const CcdShape*>(obj);
    c->v[0] = o.center.x();
    c->v[1] = o.center.y();
    c->v[2] = o.center.z();
  }
};

template <class S, class Shape>
CcdShape<S, Shape> make_ccd_shape(const Shape& s, const RigidTransform<S>& pose, const Vec3<double>& origin, double scale,
                                  CcdCounter& counter, bool counts) {
  const double inv = 1 / scale;
  CcdShape<S, Shape> o{&s, pose.R.template cast<double>(), (pose.t.template cast<double>() - origin) * inv, Vec3<double>::Zero(), inv,
                       &counter, counts};
  o.center = o.R * (interior_point(s).template cast<double>() * inv) + o.t;
  return o;
}

/// The origin of the normalised frame: the midpoint of the two shapes' interior points.
template <class S, class A, class B>
Vec3<double> ccd_origin(const A& a, const RigidTransform<S>& pa, const B& b, const RigidTransform<S>& pb) {
  return (pa.apply(interior_point(a)).template cast<double>() + pb.apply(interior_point(b)).template cast<double>()) / 2;
}

template <class OA, class OB>
ccd_t make_ccd(const CcdSettings& settings) {
  ccd_t ccd;
  CCD_INIT(&ccd);
  ccd.support1 = &OA::support_fn;
  ccd.support2 = &OB::support_fn;
  ccd.center1 = &OA::center_fn;
  ccd.center2 = &OB::center_fn;
  ccd.max_iterations = static_cast<unsigned long>(settings.max_iterations);
  ccd.epa_tolerance = settings.epa_tolerance;
  ccd.mpr_tolerance = settings.mpr_tolerance;
  return ccd;
}

/// The set-up of one libccd query: both shapes in the normalised frame (CcdSettings) sharing one
/// support-call counter, and libccd's ccd_t for them. The shapes point at the counter: a query is
/// neither copied nor moved, and not const (the support functions count through the pointer).
template <class S, class A, class B>
struct LibccdQuery {
  CcdCounter counter;
  Vec3<double> origin;
  CcdShape<S, A> a;
  CcdShape<S, B> b;
  ccd_t ccd;

  LibccdQuery(const A& sa, const RigidTransform<S>& pa, const B& sb, const RigidTransform<S>& pb, const CcdSettings& settings)
      : counter{0, settings.max_iterations, false},
        origin(ccd_origin(sa, pa, sb, pb)),
        a(make_ccd_shape(sa, pa, origin, settings.length_scale, counter, true)),
        b(make_ccd_shape(sb, pb, origin, settings.length_scale, counter, false)),
        ccd(make_ccd<CcdShape<S, A>, CcdShape<S, B>>(settings)) {}
  LibccdQuery(const LibccdQuery&) = delete;
  LibccdQuery& operator=(const LibccdQuery&) = delete;
};

}  // namespace detail

/// libccd's boolean test of shape a at pose pa against shape b at pose pb. `limit_reached`, when
/// not null, is set when the iteration bound stopped the solver (the answer is then "no
/// intersection found within the bound").
template <class S, class A, class B>
bool ccd_intersect(const A& a, const RigidTransform<S>& pa, const B& b, const RigidTransform<S>& pb, CcdAlgorithm algorithm,
                   const CcdSettings& settings, bool* limit_reached = nullptr) {
  detail::LibccdQuery<S, A, B> q(a, pa, b, pb, settings);
  const int hit = algorithm == CcdAlgorithm::Mpr ? ccdMPRIntersect(&q.a, &q.b, &q.ccd) : ccdGJKIntersect(&q.a, &q.b, &q.ccd);
  // GJK runs at most max_iterations + 1 support calls: reaching that many means the bound decided.
  const bool exhausted =
      q.counter.exhausted || (algorithm == CcdAlgorithm::Gjk && !hit && q.counter.calls >= settings.max_iterations + 1);
  if (limit_reached) *limit_reached = exhausted;
  return hit != 0;
}

/// libccd's penetration query (EPA for CcdAlgorithm::Gjk, MPR otherwise): the depth, direction
/// (from a towards b) and contact point when the shapes intersect.
template <class S, class A, class B>
CcdPenetration<S> ccd_penetration(const A& a, const RigidTransform<S>& pa, const B& b, const RigidTransform<S>& pb,
                                  CcdAlgorithm algorithm, const CcdSettings& settings) {
  detail::LibccdQuery<S, A, B> q(a, pa, b, pb, settings);
  ccd_real_t depth = 0;
  ccd_vec3_t dir, pos;
  dir.v[0] = dir.v[1] = dir.v[2] = 0;
  pos.v[0] = pos.v[1] = pos.v[2] = 0;
  const int rc = algorithm == CcdAlgorithm::Mpr ? ccdMPRPenetration(&q.a, &q.b, &q.ccd, &depth, &dir, &pos)
                                                : ccdGJKPenetration(&q.a, &q.b, &q.ccd, &depth, &dir, &pos);
  CcdPenetration<S> out;
  out.iterations = static_cast<int>(std::min<long>(q.counter.calls, settings.max_iterations));
  out.limit_reached = q.counter.exhausted;
  if (rc != 0) return out;
  out.intersecting = true;
  out.depth = S(depth * settings.length_scale);
  const Vec3<double> n(dir.v[0], dir.v[1], dir.v[2]);
  const double len = n.norm();
  out.normal = len > 0 ? Vec3<S>((n / len).template cast<S>()) : Vec3<S>::UnitZ();
  out.point = (Vec3<double>(pos.v[0], pos.v[1], pos.v[2]) * settings.length_scale + q.origin).template cast<S>();
  return out;
}

}  // namespace impact
