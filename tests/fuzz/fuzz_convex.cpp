// SPDX-License-Identifier: MIT
// Fuzz target: the convex queries (impact/convex) on every pair of shapes (sphere, capsule,
// cylinder, cone, box, convex hull), float and double, checked against each other and against
// their own certificates. The input gives the scalar type, the two shape kinds, a power-of-two
// length scale (2^-20 .. 2^20), each shape's extents (mantissa and a power of two, aspect ratios up
// to 2^12), the hull's points, the poses (a rotation from a quaternion of small integers, a
// translation on a grid of the scale plus a far offset of up to 2^16 sizes) and, on request, one
// hostile number (NaN, infinity, negative, zero, out of range) put into a shape or a pose.
// Findings:
// - a hostile number that is not rejected with InvalidInput by every query, or an exception other
//   than InvalidInput;
// - a distance, depth or normal that is not finite, or a normal that is not unit;
// - answers that disagree beyond the tolerance (relative_tolerance of the size, plus the rounding
//   of the translations): a distance clearly above zero with an intersecting boolean or
//   penetration; a penetration whose certified lower bound is clearly above zero with a
//   non-intersecting boolean; closest points farther apart than the distance;
// - a certified lower bound of the depth (depth - depth_gap) above the overlap along the answer's
//   normal or along the normals found by libccd's penetration or the own EPA without the local
//   certificate (the overlap along any direction bounds the depth from above);
// - a depth that is not an upper bound: b translated by the depth (and the tolerance) along the
//   normal must not still overlap a by more than the tolerance.
// Results that say limit_reached are exempt from the comparisons (the contract lets them be open).
#include "fuzz_input.hpp"
#include "impact/convex/convex_hull.hpp"
#include "impact/convex/query.hpp"
#include "impact/convex/shapes.hpp"
#include "impact/core/error.hpp"

#include <Eigen/Geometry>

#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <sstream>
#include <string>

namespace {

using impact::fuzz::Input;

enum class Kind : std::uint8_t { Sphere, Capsule, Cylinder, Cone, Box, Hull };
constexpr int kKinds = 6;
const char* const kKindNames[kKinds] = {"sphere", "capsule", "cylinder", "cone", "box", "hull"};

/// The hostile number a shape or pose gets (or none), and where.
struct Hostile {
  int target = -1;  ///< -1: none; 0: shape a, 1: shape b, 2: pose a, 3: pose b
  int slot = 0;     ///< which parameter of the target
  double value = 0;
};

template <class S>
S hostile_value(Input& in) {
  switch (in.byte() % 6) {
    case 0: return std::numeric_limits<S>::quiet_NaN();
    case 1: return std::numeric_limits<S>::infinity();
    case 2: return -std::numeric_limits<S>::infinity();
    case 3: return S(-1);
    case 4: return S(0);
    default: return S(4) * impact::CoordinateRange<S>::max;
  }
}

/// A length: scale * (1 + m/64) * 2^e, with e in [-6, 6] in double and [-3, 3] in float (aspect
/// ratios within kMaxFlatness: every such shape is valid).
template <class S>
S extent(Input& in, S scale) {
  const S m = S(1) + S(in.byte()) / S(64);
  const int range = sizeof(S) == 4 ? 3 : 6;
  const int e = int(in.byte() % (2 * range + 1)) - range;
  return std::ldexp(m * scale, e);
}

/// A hostile coordinate: v itself when it is not finite or out of range, else NaN (a coordinate
/// of -1 or 0 is valid).
template <class S>
S hostile_coordinate(S v) {
  return std::isfinite(v) && std::abs(v) <= impact::CoordinateRange<S>::max ? std::numeric_limits<S>::quiet_NaN() : v;
}

struct Describe {
  std::ostringstream s;
  Describe() { s.precision(17); }
};

/// Holds one shape of any kind (only the one of `kind` is set).
template <class S>
struct AnyShape {
  Kind kind = Kind::Sphere;
  std::optional<impact::Sphere<S>> sphere;
  std::optional<impact::Capsule<S>> capsule;
  std::optional<impact::Cylinder<S>> cylinder;
  std::optional<impact::Cone<S>> cone;
  std::optional<impact::Box<S>> box;
  std::optional<impact::ConvexHull<S>> hull;
};

/// Reads a shape of `kind`; a hostile value replaces parameter `slot` when `hostile` is set.
/// Returns false when the constructor rejected the shape (expected exactly when hostile).
template <class S>
bool read_shape(Input& in, Kind kind, S scale, const S* hostile, int slot, AnyShape<S>& out, Describe& d) {
  out.kind = kind;
  S p[3] = {extent(in, scale), extent(in, scale), extent(in, scale)};
  const int used = kind == Kind::Sphere ? 1 : kind == Kind::Box || kind == Kind::Hull ? 3 : 2;
  if (hostile && kind != Kind::Hull) p[slot % used] = *hostile;
  const bool flat_capsule = kind == Kind::Capsule && in.flag();  // half length 0: a sphere
  if (kind == Kind::Capsule && hostile && slot % used == 1 && *hostile == S(0)) p[1] = S(-1);  // 0 is valid there
  d.s << kKindNames[int(kind)] << "(" << p[0] << ", " << p[1] << ", " << p[2] << ") ";
  switch (kind) {
    case Kind::Sphere:
      out.sphere = impact::Sphere<S>{impact::Vec3<S>::Zero(), p[0]};
      impact::validate_shape(*out.sphere, "fuzz");  // Sphere is an aggregate: validated here
      return true;
    case Kind::Capsule: out.capsule.emplace(p[0], flat_capsule && !(hostile && slot % used == 1) ? S(0) : p[1]); return true;
    case Kind::Cylinder: out.cylinder.emplace(p[0], p[1]); return true;
    case Kind::Cone: out.cone.emplace(p[0], p[1]); return true;
    case Kind::Box: out.box.emplace(impact::Vec3<S>(p[0], p[1], p[2])); return true;
    case Kind::Hull: {
      const int n = 4 + int(in.byte() % 9);
      impact::Vertices<S> v(n, 3);
      for (int i = 0; i < n; ++i)
        for (int k = 0; k < 3; ++k) v(i, k) = S(in.range(-8, 8)) * p[k] / S(8);
      if (hostile) v(0, slot % 3) = hostile_coordinate(*hostile);
      out.hull = impact::convex_hull(v);
      return true;
    }
  }
  return false;
}

template <class S>
impact::RigidTransform<S> read_pose(Input& in, S scale, const impact::Vec3<S>& offset, const S* hostile, int slot, Describe& d) {
  impact::RigidTransform<S> pose;
  Eigen::Quaternion<double> q(double(in.range(-8, 8)), double(in.range(-8, 8)), double(in.range(-8, 8)), double(in.range(-8, 8)));
  if (q.squaredNorm() > 0) pose.R = q.normalized().toRotationMatrix().cast<S>();
  for (int k = 0; k < 3; ++k) pose.t[k] = offset[k] + S(in.range(-32, 32)) * scale / S(16);
  if (hostile) {
    if (slot % 2 == 0) {
      pose.t[slot / 2 % 3] = hostile_coordinate(*hostile);
    } else if (std::isfinite(*hostile)) {
      pose.R(slot / 2 % 3, 0) += S(0.5);  // not a rotation
    } else {
      pose.R(slot / 2 % 3, 0) = *hostile;
    }
  }
  d.s << "pose R=[" << pose.R.row(0) << "; " << pose.R.row(1) << "; " << pose.R.row(2) << "] t=(" << pose.t.transpose() << ") ";
  return pose;
}

template <class S>
[[noreturn]] void finding(const std::string& what, const Describe& d) {
  impact::fuzz::fail(what + (sizeof(S) == 4 ? " [float] " : " [double] ") + d.s.str());
}

template <class S, class A, class B>
void check_pair(const A& a, const impact::RigidTransform<S>& pa, const B& b, const impact::RigidTransform<S>& pb, bool hostile, const Describe& d) {
  const impact::ConvexQueryOptions<S> o;
  int rejected = 0;
  bool limit = false, inter = false;
  impact::ConvexDistance<S> dist;
  impact::ConvexContact<S> pen;
  try {
    inter = impact::convex_intersect(a, pa, b, pb, o, &limit);
  } catch (const impact::InvalidInput&) {
    ++rejected;
  }
  try {
    dist = impact::convex_distance(a, pa, b, pb, o);
  } catch (const impact::InvalidInput&) {
    ++rejected;
  }
  try {
    pen = impact::convex_penetration(a, pa, b, pb, o);
  } catch (const impact::InvalidInput&) {
    ++rejected;
  }
  if (hostile) {
    if (rejected != 3) finding<S>("a hostile number was accepted by " + std::to_string(3 - rejected) + " of the 3 queries", d);
    return;
  }
  if (rejected != 0) finding<S>("valid input rejected by " + std::to_string(rejected) + " queries", d);

  const S eps = std::numeric_limits<S>::epsilon();
  const S scale = impact::detail::query_scale<S>(a, b);
  const S reach = std::max({scale, pa.t.cwiseAbs().maxCoeff(), pb.t.cwiseAbs().maxCoeff()});
  // the solvers' tolerance, and the rounding of coordinates of magnitude `reach`, with a margin
  const S tol = S(16) * (o.relative_tolerance * scale + S(64) * eps * reach);
  if (!std::isfinite(dist.distance) || dist.distance < S(0)) finding<S>("distance not finite or negative", d);
  if (pen.intersecting) {
    if (!std::isfinite(pen.depth) || pen.depth < S(0) || !std::isfinite(pen.depth_gap) || pen.depth_gap < S(0))
      finding<S>("depth or depth_gap not finite or negative", d);
    if (!pen.normal.allFinite() || std::abs(pen.normal.norm() - S(1)) > S(1e-3)) finding<S>("normal not unit", d);
  }
  if (limit || dist.limit_reached || pen.limit_reached) return;

  if (dist.distance > tol && (inter || pen.intersecting))
    finding<S>("distance " + std::to_string(double(dist.distance)) + " > tolerance " + std::to_string(double(tol)) +
                   " but intersect=" + std::to_string(inter) + " penetration=" + std::to_string(pen.intersecting),
               d);
  if (dist.distance > tol && std::abs((dist.point_a - dist.point_b).norm() - dist.distance) > tol)
    finding<S>("closest points " + std::to_string(double((dist.point_a - dist.point_b).norm())) + " apart, distance " +
                   std::to_string(double(dist.distance)),
               d);
  if (pen.intersecting && pen.depth - pen.depth_gap > tol && (!inter || dist.distance > tol))
    finding<S>("penetration certified deeper than " + std::to_string(double(pen.depth - pen.depth_gap)) + " but intersect=" +
                   std::to_string(inter) + " distance=" + std::to_string(double(dist.distance)),
               d);
  if (pen.intersecting) {
    // the certified lower bound is below the overlap f(n) = h_A(n) + h_B(-n) along every unit n
    // (f(n) bounds the depth from above): along the answer's own normal, and along the normals of
    // two other solvers (libccd's, and the own EPA without the local certificate), which find the
    // least overlap by other routes
    const S lower = pen.depth - pen.depth_gap;
    const auto overlap = [&](const impact::Vec3<S>& n) {
      return n.dot(impact::support(a, pa, n)) - n.dot(impact::support(b, pb, impact::Vec3<S>(-n)));
    };
    impact::ConvexQueryOptions<S> other = o;
    other.libccd_penetration = true;
    const auto by_libccd = impact::convex_penetration(a, pa, b, pb, other);
    other.libccd_penetration = false;
    other.local_certificate = false;
    const auto by_epa = impact::convex_penetration(a, pa, b, pb, other);
    const impact::Vec3<S> normals[3] = {pen.normal, by_libccd.normal, by_epa.normal};
    const char* names[3] = {"its own normal", "libccd's normal", "EPA's normal"};
    for (int k = 0; k < 3; ++k) {
      if (k == 1 && !by_libccd.intersecting) continue;
      if (k == 2 && !by_epa.intersecting) continue;
      const S len = normals[k].norm();
      if (!(len > S(0.5)) || !normals[k].allFinite()) continue;
      const S f = overlap(impact::Vec3<S>(normals[k] / len));
      if (f < lower - tol)
        finding<S>("certified depth " + std::to_string(double(lower)) + " above the overlap " + std::to_string(double(f)) + " along " +
                       names[k],
                   d);
    }
  }
  if (pen.intersecting && pen.depth > tol) {
    // the depth is an upper bound: b moved out by it along the normal overlaps a by at most tol
    impact::RigidTransform<S> out = pb;
    out.t += (pen.depth + tol) * pen.normal;
    const auto after = impact::convex_penetration(a, pa, b, out, o);
    if (after.intersecting && !after.limit_reached && after.depth - after.depth_gap > S(2) * tol)
      finding<S>("b moved out by the depth " + std::to_string(double(pen.depth)) + " still overlaps by " +
                     std::to_string(double(after.depth - after.depth_gap)),
                 d);
  }
}

template <class S, class A>
void dispatch_b(const A& a, const impact::RigidTransform<S>& pa, const AnyShape<S>& b, const impact::RigidTransform<S>& pb, bool hostile,
                const Describe& d) {
  switch (b.kind) {
    case Kind::Sphere: check_pair(a, pa, *b.sphere, pb, hostile, d); break;
    case Kind::Capsule: check_pair(a, pa, *b.capsule, pb, hostile, d); break;
    case Kind::Cylinder: check_pair(a, pa, *b.cylinder, pb, hostile, d); break;
    case Kind::Cone: check_pair(a, pa, *b.cone, pb, hostile, d); break;
    case Kind::Box: check_pair(a, pa, *b.box, pb, hostile, d); break;
    case Kind::Hull: check_pair(a, pa, *b.hull, pb, hostile, d); break;
  }
}

template <class S>
void dispatch(const AnyShape<S>& a, const impact::RigidTransform<S>& pa, const AnyShape<S>& b, const impact::RigidTransform<S>& pb, bool hostile,
              const Describe& d) {
  switch (a.kind) {
    case Kind::Sphere: dispatch_b(*a.sphere, pa, b, pb, hostile, d); break;
    case Kind::Capsule: dispatch_b(*a.capsule, pa, b, pb, hostile, d); break;
    case Kind::Cylinder: dispatch_b(*a.cylinder, pa, b, pb, hostile, d); break;
    case Kind::Cone: dispatch_b(*a.cone, pa, b, pb, hostile, d); break;
    case Kind::Box: dispatch_b(*a.box, pa, b, pb, hostile, d); break;
    case Kind::Hull: dispatch_b(*a.hull, pa, b, pb, hostile, d); break;
  }
}

template <class S>
void run(Input& in) {
  const Kind ka = Kind(in.byte() % kKinds), kb = Kind(in.byte() % kKinds);
  const int range = sizeof(S) == 4 ? 10 : 20;  // float: extents and offsets stay within CoordinateRange
  const S scale = std::ldexp(S(1), int(in.byte() % (2 * range + 1)) - range);
  Hostile h;
  const std::uint8_t hb = in.byte();
  if (hb >= 224) {  // one input in eight carries a hostile number
    h.target = hb % 4;
    h.slot = int(in.byte() % 6);
  }
  const S bad = h.target >= 0 ? hostile_value<S>(in) : S(0);
  Describe d;
  d.s << "scale " << scale << ": ";
  AnyShape<S> a, b;
  // a hostile shape must be rejected by its constructor (or convex_hull) with InvalidInput
  for (int which = 0; which < 2; ++which) {
    const bool hostile_here = h.target == which;
    try {
      read_shape<S>(in, which == 0 ? ka : kb, scale, hostile_here ? &bad : nullptr, h.slot, which == 0 ? a : b, d);
    } catch (const impact::InvalidInput&) {
      if (hostile_here) return;
      if (which == 0 ? ka == Kind::Hull : kb == Kind::Hull) return;  // a flat or coincident point set: rejected, as documented
      finding<S>("a valid shape was rejected", d);
    }
    if (hostile_here) finding<S>("a shape with a hostile number was accepted", d);
  }
  // both shapes near one point, up to 2^16 sizes from the origin (2^8 in float)
  const int far = int(in.byte() % (sizeof(S) == 4 ? 9 : 17));
  impact::Vec3<S> offset = impact::Vec3<S>::Zero();
  for (int k = 0; k < 3; ++k) offset[k] = S(int(in.byte() % 3) - 1) * std::ldexp(scale, far);
  const impact::RigidTransform<S> pa = read_pose<S>(in, scale, offset, h.target == 2 ? &bad : nullptr, h.slot, d);
  const impact::RigidTransform<S> pb = read_pose<S>(in, scale, offset, h.target == 3 ? &bad : nullptr, h.slot, d);
  dispatch<S>(a, pa, b, pb, h.target >= 2, d);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  Input in(data, size);
  try {
    if (in.flag()) {
      run<float>(in);
    } else {
      run<double>(in);
    }
  } catch (const impact::InvalidInput& e) {
    impact::fuzz::fail(std::string("unexpected InvalidInput: ") + e.what());
  }
  return 0;
}
