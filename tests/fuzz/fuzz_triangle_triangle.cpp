// SPDX-License-Identifier: MIT
// Fuzz target: triangles_intersect and triangle_intersection (impact/narrow/triangle_triangle.hpp)
// against an exact integer separating-axis test written in the tests (tests/narrow/int_oracle.hpp,
// independent of the library's predicates). The input gives float or double, a coordinate range
// (2^0 .. 2^19: small ranges are full of coplanar, touching and degenerate pairs), an exact
// power-of-two scale and an integer translation, then the six vertices. The decision must equal
// the oracle's, in both argument orders, and triangle_intersection must be present exactly when
// the triangles intersect.
#include "fuzz_input.hpp"
#include "impact/narrow/triangle_triangle.hpp"
#include "narrow/int_oracle.hpp"

#include <cmath>
#include <cstdint>
#include <string>

namespace {

using impact::test::IPoint;

std::string describe(const std::array<IPoint, 3>& P, const std::array<IPoint, 3>& Q, int shift, bool is_float) {
  std::string s = std::string(is_float ? "float" : "double") + " scale 2^-" + std::to_string(shift) + ":";
  for (const auto* T : {&P, &Q}) {
    s += " [";
    for (const auto& p : *T) s += " (" + std::to_string(p[0]) + "," + std::to_string(p[1]) + "," + std::to_string(p[2]) + ")";
    s += " ]";
  }
  return s;
}

template <class S> void check(const std::array<IPoint, 3>& P, const std::array<IPoint, 3>& Q, int shift) {
  auto tri = [&](const std::array<IPoint, 3>& T) {
    impact::Vec3<S> v[3];
    for (int k = 0; k < 3; ++k)
      for (int i = 0; i < 3; ++i) v[k][i] = static_cast<S>(std::ldexp(static_cast<double>(T[std::size_t(k)][std::size_t(i)]), -shift));
    return impact::Triangle<S>(v[0], v[1], v[2]);
  };
  const auto a = tri(P), b = tri(Q);
  const bool want = impact::test::triangles_intersect_int(P, Q);
  const bool is_float = sizeof(S) == 4;
  if (impact::triangles_intersect(a, b) != want)
    impact::fuzz::fail(std::string("triangles_intersect(a, b) = ") + (want ? "false" : "true") + ", exact " + (want ? "true" : "false") +
                       ": " + describe(P, Q, shift, is_float));
  if (impact::triangles_intersect(b, a) != want)
    impact::fuzz::fail(std::string("triangles_intersect(b, a) disagrees with the exact answer ") + (want ? "true" : "false") + ": " +
                       describe(P, Q, shift, is_float));
  if (impact::triangle_intersection(a, b).has_value() != want)
    impact::fuzz::fail("triangle_intersection disagrees with the exact answer: " + describe(P, Q, shift, is_float));
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  impact::fuzz::Input in(data, size);
  const std::uint8_t mode = in.byte();
  const bool is_float = (mode & 1u) != 0;
  const int bits = in.byte() % 20;                               // coordinates in [-2^bits, 2^bits]
  const int shift = is_float ? in.byte() % 16 : in.byte() % 64;  // exact scale 2^-shift
  const std::int64_t r = std::int64_t(1) << bits;
  // an integer translation of both triangles keeps the coordinates within 2^20 (the oracle's range)
  IPoint offset;
  for (auto& x : offset) x = (mode & 2u) ? in.range(-(std::int64_t(1) << 19), std::int64_t(1) << 19) : 0;
  std::array<IPoint, 3> P, Q;
  for (auto* T : {&P, &Q})
    for (auto& p : *T)
      for (std::size_t i = 0; i < 3; ++i) {
        const std::int64_t x = in.range(-r, r) + offset[i];
        p[i] = x > (std::int64_t(1) << 20) ? (std::int64_t(1) << 20) : x < -(std::int64_t(1) << 20) ? -(std::int64_t(1) << 20) : x;
      }
  // float carries 24 bits: coordinates up to 2^20 are exact
  if (is_float) check<float>(P, Q, shift);
  else check<double>(P, Q, shift);
  return 0;
}
