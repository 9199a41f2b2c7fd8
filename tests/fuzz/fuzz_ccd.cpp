// SPDX-License-Identifier: MIT
// Fuzz target: vertex_face_ccd and edge_edge_ccd (impact/ccd) against the exact integer reference
// of the tests (support/exact_ccd.hpp). The input gives the kind of query, float or double, a
// coordinate range (2^1 .. 2^20, small ranges are full of exact degeneracies) and a power-of-two
// scale (exact), then the 24 integer coordinates. Every "no hit" must be proven contact-free by
// the reference (it certifies NoContact or gives up; giving up on a no-hit is a finding, as in
// tests/ccd/test_ccd_exact.cpp); every hit must have a time of impact in [0, 1].
#include "fuzz_input.hpp"
#include "impact/ccd/edge_edge.hpp"
#include "impact/ccd/vertex_face.hpp"
#include "support/exact_ccd.hpp"

#include <cmath>
#include <cstdint>
#include <string>

namespace {

std::string describe(const impact::test::IntCcdQuery& q, int shift, bool is_float) {
  std::string s = std::string(q.vertex_face ? "vertex-face" : "edge-edge") + (is_float ? " float" : " double") +
                  " scale 2^-" + std::to_string(shift) + ":";
  for (const auto& p : q.points) s += " (" + std::to_string(p[0]) + "," + std::to_string(p[1]) + "," + std::to_string(p[2]) + ")";
  return s;
}

template <class S> void check(const impact::test::IntCcdQuery& q, int shift) {
  std::array<impact::Vec3<S>, 8> p;
  for (std::size_t k = 0; k < 8; ++k)
    for (std::size_t i = 0; i < 3; ++i) p[k][int(i)] = static_cast<S>(std::ldexp(static_cast<double>(q.points[k][i]), -shift));
  const impact::CcdOptions o;
  const auto r = q.vertex_face ? impact::vertex_face_ccd(p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7], o)
                               : impact::edge_edge_ccd(p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7], o);
  const bool is_float = sizeof(S) == 4;
  if (r.hit) {
    if (!(r.toi >= S(0) && r.toi <= S(1))) impact::fuzz::fail("hit with toi outside [0, 1]: " + describe(q, shift, is_float));
    return;
  }
  using impact::test::ExactAnswer;
  if (impact::test::certify_no_contact(q, {}, 200000) == ExactAnswer::NoContact) return;
  if (impact::test::certify_no_contact(q, {}, 4000000) == ExactAnswer::NoContact) return;
  impact::fuzz::fail("no hit reported, but the exact reference cannot exclude a contact: " + describe(q, shift, is_float));
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  impact::fuzz::Input in(data, size);
  impact::test::IntCcdQuery q;
  const std::uint8_t mode = in.byte();
  q.vertex_face = (mode & 1u) == 0;
  const bool is_float = (mode & 2u) != 0;
  const int bits = 1 + in.byte() % 20;                      // coordinates in [-2^bits, 2^bits]
  const int shift = is_float ? in.byte() % 24 : in.byte() % 64;  // exact scale 2^-shift
  const std::int64_t r = std::int64_t(1) << bits;
  for (auto& point : q.points)
    for (auto& x : point) x = in.range(-r, r);
  if (is_float) check<float>(q, shift);
  else check<double>(q, shift);
  return 0;
}
