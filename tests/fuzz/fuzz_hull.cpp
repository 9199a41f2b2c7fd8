// SPDX-License-Identifier: MIT
// Fuzz target: convex_hull() (impact/convex/convex_hull.hpp) on point sets a user might pass, float
// and double, checked against its contract. The input gives the scalar type, a power-of-two length
// scale (2^-20 .. 2^20), a far offset of up to 2^16 sizes, the options (default or a chosen
// tolerance and merge angle), and 4-64 points, each one of: a point on a grid of the scale, a point
// with free mantissa bits, a point on the sphere of the scale, or a near-duplicate of an earlier
// point (moved by small integers times 2^-k of the scale, k in 8..60: the sets that once gave
// sliver faces with noise normals); on request one hostile number (NaN, infinity, out of range) in
// a point or a bad option.
// Findings:
// - a hostile number or bad option not rejected with InvalidInput, or any other exception;
// - a hull vertex that is not an input point;
// - triangles that are not a closed, consistently oriented surface (each directed edge once and its
//   reverse once, V - E + F = 2), indices out of range;
// - faces, face_planes, edges or the vertex graph inconsistent with each other (sizes, indices,
//   unit normals);
// - an input point outside the hull: along any direction d (every face normal, every triangle's
//   normal, the axes) the input points' largest d . p above the hull vertices' largest d . v by
//   more than the tolerance (this needs no trust in the hull's faces: it tests the point against
//   the convex hull of the returned vertices);
// - a face plane that does not support the hull: a hull vertex or an input point above a face's
//   plane (normal . x = offset) by more than the tolerance. The pair tests (separating axes, the
//   particle colliders) take the offsets as the hull's extent along each normal, so such a plane
//   makes them miss a contact.
// The tolerance: the contract's eps (relative_tolerance times half the largest side of the points'
// bounding box) plus the rounding of coordinates as large as the offset, computed in long double.
#include "fuzz_input.hpp"
#include "impact/convex/convex_hull.hpp"
#include "impact/core/error.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace {

using impact::fuzz::Input;
using L = long double;
using V3 = Eigen::Matrix<L, 3, 1>;

struct Report {
  std::ostringstream s;
  Report() { s.precision(21); }
};

template <class S>
V3 row(const impact::Vertices<S>& v, Eigen::Index i) {
  return V3(L(v(i, 0)), L(v(i, 1)), L(v(i, 2)));
}

template <class S>
void check(Input& in) {
  Report rep;
  rep.s << (sizeof(S) == 4 ? "float" : "double");
  const S scale = std::ldexp(S(1), int(in.range(-20, 20)));
  const int far = int(in.range(0, 16));
  impact::Vec3<S> offset(S(in.range(-8, 8)), S(in.range(-8, 8)), S(in.range(-8, 8)));
  offset *= std::ldexp(scale, far);
  impact::ConvexHullOptions options;
  if (in.flag()) options.relative_tolerance = std::ldexp(1.0, -int(in.range(8, 52)));
  if (in.flag()) options.merge_angle = std::ldexp(1.0, -int(in.range(4, 40)));
  const int hostile = int(in.byte() % 16);  // 0-2: a hostile coordinate; 3: a bad option; else none
  const int n = int(in.range(4, 64));
  impact::Vertices<S> p(n, 3);
  for (int i = 0; i < n; ++i) {
    impact::Vec3<S> x;
    switch (i == 0 ? 0 : in.byte() % 4) {
      case 0:  // a grid of the scale
        for (int k = 0; k < 3; ++k) x[k] = S(in.range(-64, 64)) * scale / S(64);
        break;
      case 1:  // free mantissa bits
        for (int k = 0; k < 3; ++k) x[k] = S(std::ldexp(double(std::int32_t(in.u32())), -31)) * scale;
        break;
      case 2: {  // on the sphere of the scale
        impact::Vec3<S> d(S(in.range(-128, 128)), S(in.range(-128, 128)), S(in.range(-128, 128)));
        x = d.norm() > S(0) ? impact::Vec3<S>(d.normalized() * scale) : impact::Vec3<S>(scale, S(0), S(0));
        break;
      }
      default: {  // a near-duplicate of an earlier point
        const int j = int(in.range(0, i - 1));
        const int k = int(in.range(8, 60));
        const S step = std::ldexp(scale, -k);
        x = p.row(j).transpose() - offset;
        for (int c = 0; c < 3; ++c) x[c] += S(in.range(-4, 4)) * step;
        break;
      }
    }
    p.row(i) = (x + offset).transpose();
  }
  bool expect_invalid = false;
  if (hostile <= 2) {
    const S values[3] = {std::numeric_limits<S>::quiet_NaN(), std::numeric_limits<S>::infinity(), S(4) * impact::CoordinateRange<S>::max};
    p(int(in.range(0, n - 1)), int(in.range(0, 2))) = values[hostile];
    expect_invalid = true;
  } else if (hostile == 3) {
    if (in.flag()) options.merge_angle = in.flag() ? -1.0 : std::numeric_limits<double>::quiet_NaN();
    else options.relative_tolerance = std::numeric_limits<double>::infinity();
    expect_invalid = true;
  }
  rep.s << " scale 2^" << std::ilogb(scale) << " offset (" << offset.transpose() << ") tol " << options.relative_tolerance << " merge "
        << options.merge_angle << " points:";
  for (int i = 0; i < n; ++i) rep.s << " (" << p(i, 0) << ", " << p(i, 1) << ", " << p(i, 2) << ")";

  impact::ConvexHull<S> h;
  try {
    h = impact::convex_hull(p, options);
  } catch (const impact::InvalidInput&) {
    return;  // degenerate sets (coplanar, coincident within the tolerance) are rejected too
  } catch (const std::exception& e) {
    impact::fuzz::fail("convex_hull threw " + std::string(e.what()) + " on " + rep.s.str());
  }
  if (expect_invalid) impact::fuzz::fail("a hostile input was accepted: " + rep.s.str());

  // The tolerance, as the contract states it, plus the rounding of the coordinates.
  const L u = L(std::numeric_limits<S>::epsilon());
  V3 lo = row(p, 0), hi = lo;
  L big = 0;
  for (int i = 0; i < n; ++i) {
    lo = lo.cwiseMin(row(p, i));
    hi = hi.cwiseMax(row(p, i));
    big = std::max(big, row(p, i).cwiseAbs().maxCoeff());
  }
  const L extent = (hi - lo).maxCoeff() / 2;
  const L rel = options.relative_tolerance > 0 ? L(S(options.relative_tolerance)) : 1000 * u;
  const L tol = rel * extent * L(1.001) + 64 * u * (big + extent);
  const V3 mid = (lo + hi) / 2;

  // Vertices are input points.
  const Eigen::Index nv = h.vertices.rows();
  if (nv < 4) impact::fuzz::fail("a hull of fewer than 4 vertices: " + rep.s.str());
  for (Eigen::Index v = 0; v < nv; ++v) {
    bool found = false;
    for (int i = 0; i < n && !found; ++i) found = h.vertices.row(v) == p.row(i);
    if (!found) impact::fuzz::fail("hull vertex " + std::to_string(v) + " is not an input point: " + rep.s.str());
  }
  // Triangles: a closed, consistently oriented surface.
  const Eigen::Index nt = h.triangles.rows();
  std::map<std::pair<int, int>, int> directed;
  for (Eigen::Index t = 0; t < nt; ++t)
    for (int k = 0; k < 3; ++k) {
      const int a = h.triangles(t, k), b = h.triangles(t, (k + 1) % 3);
      if (a < 0 || a >= nv || b < 0 || b >= nv || a == b) impact::fuzz::fail("a triangle index out of range or repeated: " + rep.s.str());
      if (++directed[{a, b}] != 1) impact::fuzz::fail("a directed edge in two triangles: " + rep.s.str());
    }
  for (const auto& e : directed)
    if (directed.find({e.first.second, e.first.first}) == directed.end()) impact::fuzz::fail("an edge without its reverse (the surface is not closed): " + rep.s.str());
  if (Eigen::Index(nv) - Eigen::Index(directed.size() / 2) + nt != 2) impact::fuzz::fail("V - E + F != 2: " + rep.s.str());

  // Faces and their planes.
  const std::size_t nf = h.faces.size();
  if (nf == 0 || h.face_planes.size() != 4 * nf) impact::fuzz::fail("faces and face_planes disagree in size: " + rep.s.str());
  std::vector<V3> dirs = {V3::UnitX(), V3::UnitY(), V3::UnitZ(), -V3::UnitX(), -V3::UnitY(), -V3::UnitZ()};
  for (std::size_t f = 0; f < nf; ++f) {
    const impact::HullFace<S>& face = h.faces[f];
    const V3 m(L(face.normal.x()), L(face.normal.y()), L(face.normal.z()));
    if (!(std::abs(m.norm() - 1) <= 64 * u)) impact::fuzz::fail("face " + std::to_string(f) + "'s normal is not unit: " + rep.s.str());
    if (face.vertices.size() < 3) impact::fuzz::fail("a face of fewer than 3 vertices: " + rep.s.str());
    for (int v : face.vertices)
      if (v < 0 || v >= nv) impact::fuzz::fail("a face's vertex index out of range: " + rep.s.str());
    for (int k = 0; k < 3; ++k)
      if (h.face_planes[std::size_t(k) * nf + f] != face.normal[k]) impact::fuzz::fail("face_planes differ from the faces: " + rep.s.str());
    if (h.face_planes[3 * nf + f] != face.offset) impact::fuzz::fail("face_planes' offset differs from the face's: " + rep.s.str());
    // Supporting plane: no hull vertex and no input point above it beyond the tolerance (measured
    // from the centre of the points, so that the offset's rounding counts once).
    const L off = L(face.offset) - m.dot(mid);
    L worst = -std::numeric_limits<L>::infinity();
    int worst_point = -1;
    for (int i = 0; i < n; ++i) {
      const L s = m.dot(row(p, i) - mid) - off;
      if (s > worst) worst = s, worst_point = i;
    }
    if (worst > tol) {
      std::ostringstream w;
      w.precision(6);
      w << "input point " << worst_point << " is " << double(worst / extent) << " extents above face " << f << "'s plane (tolerance "
        << double(tol / extent) << "): ";
      impact::fuzz::fail(w.str() + rep.s.str());
    }
    dirs.push_back(m / m.norm());
  }
  for (Eigen::Index t = 0; t < nt; ++t) {
    const V3 a = row(h.vertices, h.triangles(t, 0)), b = row(h.vertices, h.triangles(t, 1)), c = row(h.vertices, h.triangles(t, 2));
    const V3 m = (b - a).cross(c - a);
    if (m.norm() > 0) dirs.push_back(m / m.norm());
  }
  for (const impact::HullEdge& e : h.edges)
    if (e.v0 < 0 || e.v0 >= nv || e.v1 < 0 || e.v1 >= nv || e.f0 < 0 || std::size_t(e.f0) >= nf || e.f1 < 0 || std::size_t(e.f1) >= nf || e.f0 == e.f1)
      impact::fuzz::fail("an edge with an index out of range: " + rep.s.str());
  if (!h.neighbors.empty()) {
    if (h.neighbor_start.size() != std::size_t(nv) + 1 || h.neighbor_start.back() != int(h.neighbors.size()))
      impact::fuzz::fail("the vertex graph's rows disagree with its size: " + rep.s.str());
    for (int v : h.neighbors)
      if (v < 0 || v >= nv) impact::fuzz::fail("a vertex graph index out of range: " + rep.s.str());
  }

  // Every input point within the tolerance of the convex hull of the returned vertices, along
  // every direction found above.
  for (const V3& d : dirs) {
    L top = -std::numeric_limits<L>::infinity();
    for (Eigen::Index v = 0; v < nv; ++v) top = std::max(top, d.dot(row(h.vertices, v) - mid));
    for (int i = 0; i < n; ++i) {
      const L s = d.dot(row(p, i) - mid) - top;
      if (s > tol) {
        std::ostringstream w;
        w.precision(6);
        w << "input point " << i << " is " << double(s / extent) << " extents outside the hull's vertices along (" << double(d.x()) << ", "
          << double(d.y()) << ", " << double(d.z()) << ") (tolerance " << double(tol / extent) << "): ";
        impact::fuzz::fail(w.str() + rep.s.str());
      }
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  Input in(data, size);
  if (in.flag())
    check<float>(in);
  else
    check<double>(in);
  return 0;
}
