// SPDX-License-Identifier: MIT
/// \file
/// Procedural triangle meshes for tests, benchmarks and examples: UV sphere, icosphere, torus,
/// box (closed, outward-oriented, no duplicate positions), a flat grid (an open cloth-like sheet)
/// and a random triangle soup. Everything here is deterministic and platform-independent: the
/// soup uses its own SplitMix64 generator rather than the standard distributions, whose output
/// differs between standard libraries. Invalid parameters throw InvalidInput: sizes that are not
/// finite, not positive or outside CoordinateRange (core/validate.hpp), too few segments, or more
/// than detail::generators::kMaxTriangles triangles.
#pragma once

#include "impact/core/error.hpp"
#include "impact/geometry/triangle_mesh.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <unordered_map>
#include <vector>

namespace impact {

namespace detail {

/// SplitMix64 (Steele, Lea, Flood 2014): a tiny 64-bit generator whose output sequence is fixed by
/// its definition, so results are identical on every platform and standard library.
class SplitMix64 {
 public:
  explicit SplitMix64(std::uint64_t seed) : state_(seed) {}
  std::uint64_t next() {
    std::uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  /// Uniform in [0, 1) from the top 53 bits.
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
  /// Uniform in [lo, hi).
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }

 private:
  std::uint64_t state_;
};

namespace generators {

inline void require(bool ok, const char* fn, const std::string& why) {
  if (!ok) throw InvalidInput(std::string(fn) + ": " + why);
}

inline constexpr double pi = 3.14159265358979323846;

/// The most triangles a generator makes (2^26, about 3 GB of double vertices for a soup): larger
/// requests throw InvalidInput instead of overflowing an int or the memory.
inline constexpr std::int64_t kMaxTriangles = std::int64_t(1) << 26;

inline void require_triangles(std::int64_t triangles, const char* fn) {
  require(triangles <= kMaxTriangles, fn,
          "would make " + std::to_string(triangles) + " triangles, more than " + std::to_string(kMaxTriangles));
}

/// A length parameter: finite and within [CoordinateRange::min_scale, CoordinateRange::max] (a
/// generated mesh must pass validate_mesh).
template <class S> bool length_ok(S x) { return x >= CoordinateRange<S>::min_scale && x <= CoordinateRange<S>::max; }

}  // namespace generators

}  // namespace detail

/// Closed UV sphere of the given radius centred at the origin, poles on the z axis: `slices`
/// (>= 3) segments around z, `stacks` (>= 2) bands from pole to pole. Outward-oriented (counter-
/// clockwise seen from outside). Vertices: slices*(stacks-1) + 2; triangles: 2*slices*(stacks-1).
/// Throws InvalidInput on radius <= 0 or too few segments.
template <class S> TriangleMesh<S> make_uv_sphere(S radius, int slices = 32, int stacks = 16) {
  detail::generators::require(detail::generators::length_ok(radius), "make_uv_sphere", "radius must be positive, finite and within CoordinateRange");
  detail::generators::require(slices >= 3 && stacks >= 2, "make_uv_sphere", "needs slices >= 3 and stacks >= 2");
  detail::generators::require_triangles(2 * std::int64_t(slices) * (std::int64_t(stacks) - 1), "make_uv_sphere");
  const int rings = stacks - 1;
  TriangleMesh<S> m;
  m.V.resize(Eigen::Index(slices) * rings + 2, 3);
  m.F.resize(2 * Eigen::Index(slices) * rings, 3);
  const double r = static_cast<double>(radius);
  const int north = 0, south = static_cast<int>(Eigen::Index(slices) * rings + 1);
  m.V.row(north) << S(0), S(0), radius;
  m.V.row(south) << S(0), S(0), -radius;
  // 64-bit index arithmetic: the counts are bounded above, the compiler cannot see it
  auto ring_vertex = [slices](int i, int j) { return static_cast<int>(1 + std::int64_t(i) * slices + (j % slices)); };
  for (int i = 0; i < rings; ++i) {
    const double theta = detail::generators::pi * (i + 1) / stacks;
    for (int j = 0; j < slices; ++j) {
      const double phi = 2 * detail::generators::pi * j / slices;
      m.V.row(ring_vertex(i, j)) << static_cast<S>(r * std::sin(theta) * std::cos(phi)),
          static_cast<S>(r * std::sin(theta) * std::sin(phi)), static_cast<S>(r * std::cos(theta));
    }
  }
  Eigen::Index t = 0;
  for (int j = 0; j < slices; ++j) m.F.row(t++) << north, ring_vertex(0, j), ring_vertex(0, j + 1);
  for (int i = 0; i + 1 < rings; ++i) {
    for (int j = 0; j < slices; ++j) {
      const int a = ring_vertex(i, j), b = ring_vertex(i, j + 1), c = ring_vertex(i + 1, j), d = ring_vertex(i + 1, j + 1);
      m.F.row(t++) << a, c, d;
      m.F.row(t++) << a, d, b;
    }
  }
  for (int j = 0; j < slices; ++j) m.F.row(t++) << ring_vertex(rings - 1, j), south, ring_vertex(rings - 1, j + 1);
  return m;
}

/// Closed icosphere: a regular icosahedron inscribed in the sphere of the given radius, each
/// triangle split 1 -> 4 `subdivisions` times (0..10) with new vertices projected onto the
/// sphere. Outward-oriented. Triangles: 20 * 4^subdivisions; vertices: 10 * 4^subdivisions + 2.
/// Throws InvalidInput on radius <= 0 or subdivisions outside [0, 10].
template <class S> TriangleMesh<S> make_icosphere(S radius, int subdivisions = 3) {
  detail::generators::require(detail::generators::length_ok(radius), "make_icosphere", "radius must be positive, finite and within CoordinateRange");
  detail::generators::require(subdivisions >= 0 && subdivisions <= 10, "make_icosphere", "subdivisions must be in [0, 10]");
  const double g = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Eigen::Vector3d> P = {{-1, g, 0}, {1, g, 0}, {-1, -g, 0}, {1, -g, 0}, {0, -1, g}, {0, 1, g},
                                    {0, -1, -g}, {0, 1, -g}, {g, 0, -1}, {g, 0, 1}, {-g, 0, -1}, {-g, 0, 1}};
  for (auto& p : P) p.normalize();
  std::vector<Eigen::Vector3i> T = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                                    {11, 10, 2}, {10, 7, 6}, {7, 1, 8},   {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                                    {3, 8, 9},  {4, 9, 5},  {2, 4, 11},  {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (int level = 0; level < subdivisions; ++level) {
    std::unordered_map<std::uint64_t, int> midpoint;
    auto mid = [&](int a, int b) {
      const std::uint64_t key = (static_cast<std::uint64_t>(std::min(a, b)) << 32) | static_cast<std::uint32_t>(std::max(a, b));
      const auto it = midpoint.find(key);
      if (it != midpoint.end()) return it->second;
      P.push_back((P[static_cast<std::size_t>(a)] + P[static_cast<std::size_t>(b)]).normalized());
      const int id = static_cast<int>(P.size()) - 1;
      midpoint.emplace(key, id);
      return id;
    };
    std::vector<Eigen::Vector3i> next;
    next.reserve(4 * T.size());
    for (const auto& t : T) {
      const int ab = mid(t[0], t[1]), bc = mid(t[1], t[2]), ca = mid(t[2], t[0]);
      next.emplace_back(t[0], ab, ca);
      next.emplace_back(t[1], bc, ab);
      next.emplace_back(t[2], ca, bc);
      next.emplace_back(ab, bc, ca);
    }
    T = std::move(next);
  }
  TriangleMesh<S> m;
  m.V.resize(static_cast<Eigen::Index>(P.size()), 3);
  m.F.resize(static_cast<Eigen::Index>(T.size()), 3);
  const double r = static_cast<double>(radius);
  for (std::size_t i = 0; i < P.size(); ++i) m.V.row(static_cast<Eigen::Index>(i)) = (r * P[i]).cast<S>().transpose();
  for (std::size_t t = 0; t < T.size(); ++t) m.F.row(static_cast<Eigen::Index>(t)) = T[t].transpose();
  return m;
}

/// Closed torus around the z axis centred at the origin: major radius R (centre of the tube to
/// the axis), minor radius r (tube), 0 < r < R; `nu` (>= 3) segments around the axis, `nv` (>= 3)
/// around the tube. Outward-oriented. Vertices: nu*nv; triangles: 2*nu*nv; enclosed volume tends
/// to 2 pi^2 R r^2. Throws InvalidInput on invalid radii or too few segments.
template <class S> TriangleMesh<S> make_torus(S R, S r, int nu = 48, int nv = 24) {
  detail::generators::require(r > S(0) && R > r, "make_torus", "needs 0 < r < R");
  detail::generators::require(detail::generators::length_ok(r) && detail::generators::length_ok(S(R + r)), "make_torus",
                              "R + r and r must be finite and within CoordinateRange");
  detail::generators::require(nu >= 3 && nv >= 3, "make_torus", "needs nu >= 3 and nv >= 3");
  detail::generators::require_triangles(2 * std::int64_t(nu) * std::int64_t(nv), "make_torus");
  TriangleMesh<S> m;
  m.V.resize(Eigen::Index(nu) * nv, 3);
  m.F.resize(2 * Eigen::Index(nu) * nv, 3);
  auto id = [nu, nv](int i, int j) { return static_cast<int>(std::int64_t(i % nu) * nv + (j % nv)); };
  for (int i = 0; i < nu; ++i) {
    const double theta = 2 * detail::generators::pi * i / nu;
    for (int j = 0; j < nv; ++j) {
      const double phi = 2 * detail::generators::pi * j / nv;
      const double rho = static_cast<double>(R) + static_cast<double>(r) * std::cos(phi);
      m.V.row(id(i, j)) << static_cast<S>(rho * std::cos(theta)), static_cast<S>(rho * std::sin(theta)),
          static_cast<S>(static_cast<double>(r) * std::sin(phi));
    }
  }
  Eigen::Index t = 0;
  for (int i = 0; i < nu; ++i) {
    for (int j = 0; j < nv; ++j) {
      const int a = id(i, j), b = id(i + 1, j), c = id(i + 1, j + 1), d = id(i, j + 1);
      m.F.row(t++) << a, b, c;
      m.F.row(t++) << a, c, d;
    }
  }
  return m;
}

/// Flat open grid in the z = 0 plane covering [-size/2, size/2]^2, a cloth-like sheet of nx by ny
/// square cells (each split in two triangles), normals along +z. Vertices: (nx+1)*(ny+1), row
/// major in x (vertex (i, j) is i + j*(nx+1)); triangles: 2*nx*ny. Throws InvalidInput on
/// nx < 1, ny < 1 or size <= 0.
template <class S> TriangleMesh<S> make_grid(int nx, int ny, S size = S(1)) {
  detail::generators::require(nx >= 1 && ny >= 1, "make_grid", "needs nx >= 1 and ny >= 1");
  detail::generators::require(detail::generators::length_ok(size), "make_grid", "size must be positive, finite and within CoordinateRange");
  detail::generators::require_triangles(2 * std::int64_t(nx) * std::int64_t(ny), "make_grid");
  TriangleMesh<S> m;
  m.V.resize((Eigen::Index(nx) + 1) * (Eigen::Index(ny) + 1), 3);
  m.F.resize(2 * Eigen::Index(nx) * ny, 3);
  const double h = static_cast<double>(size);
  auto id = [nx](int i, int j) { return static_cast<int>(i + std::int64_t(j) * (std::int64_t(nx) + 1)); };
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i)
      m.V.row(id(i, j)) << static_cast<S>(h * (double(i) / nx - 0.5)), static_cast<S>(h * (double(j) / ny - 0.5)), S(0);
  Eigen::Index t = 0;
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      const int a = id(i, j), b = id(i + 1, j), c = id(i + 1, j + 1), d = id(i, j + 1);
      m.F.row(t++) << a, b, c;
      m.F.row(t++) << a, c, d;
    }
  }
  return m;
}

/// Closed axis-aligned box centred at the origin with the given half extents (all > 0): 8
/// vertices, 12 outward-oriented triangles. Vertex k has coordinate +h where bit k is set along
/// that axis (bit 0: x, bit 1: y, bit 2: z), -h otherwise. Throws InvalidInput on a non-positive
/// half extent.
template <class S> TriangleMesh<S> make_box(const Vec3<S>& half_extents) {
  detail::generators::require(detail::generators::length_ok(half_extents.minCoeff()) && detail::generators::length_ok(half_extents.maxCoeff()) &&
                                  all_finite(half_extents),
                              "make_box", "half extents must be positive, finite and within CoordinateRange");
  TriangleMesh<S> m;
  m.V.resize(8, 3);
  for (int k = 0; k < 8; ++k)
    m.V.row(k) << ((k & 1) ? half_extents.x() : -half_extents.x()), ((k & 2) ? half_extents.y() : -half_extents.y()),
        ((k & 4) ? half_extents.z() : -half_extents.z());
  m.F.resize(12, 3);
  m.F << 0, 4, 6, 0, 6, 2,  // -x
      1, 3, 7, 1, 7, 5,     // +x
      0, 1, 5, 0, 5, 4,     // -y
      2, 6, 7, 2, 7, 3,     // +y
      0, 2, 3, 0, 3, 1,     // -z
      4, 5, 7, 4, 7, 6;     // +z
  return m;
}

/// Random triangle soup of n (>= 1) separate triangles (no shared vertices: vertex 3t+k is corner
/// k of triangle t). Each triangle's centre is uniform in [-extent, extent]^3 and its corners are
/// uniform in the cube of side `tri_size` around that centre. Deterministic for a given seed on
/// every platform (SplitMix64, computed in double then cast to S). Throws InvalidInput on n < 1,
/// extent < 0 or tri_size <= 0.
template <class S> TriangleMesh<S> make_random_soup(int n, std::uint64_t seed, S extent = S(1), S tri_size = S(0.1)) {
  detail::generators::require(n >= 1, "make_random_soup", "needs n >= 1");
  detail::generators::require_triangles(n, "make_random_soup");
  detail::generators::require(extent >= S(0) && tri_size > S(0), "make_random_soup", "needs extent >= 0 and tri_size > 0");
  detail::generators::require(detail::generators::length_ok(S(extent + tri_size)), "make_random_soup",
                              "extent + tri_size must be finite and within CoordinateRange");
  detail::SplitMix64 rng(seed);
  const double e = static_cast<double>(extent), h = 0.5 * static_cast<double>(tri_size);
  TriangleMesh<S> m;
  m.V.resize(3 * static_cast<Eigen::Index>(n), 3);
  m.F.resize(n, 3);
  for (int t = 0; t < n; ++t) {
    double c[3];
    for (double& x : c) x = rng.uniform(-e, e);
    for (int k = 0; k < 3; ++k) {
      for (int d = 0; d < 3; ++d) m.V(3 * t + k, d) = static_cast<S>(c[d] + rng.uniform(-h, h));
      m.F(t, k) = 3 * t + k;
    }
  }
  return m;
}

}  // namespace impact
