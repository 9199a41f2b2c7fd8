// SPDX-License-Identifier: MIT
// Fuzz target: mesh_ccd and mesh_self_ccd (impact/ccd/mesh_ccd.hpp) against a loop over every
// primitive pair. The input gives self or pair, float or double, a coordinate range (2^1 .. 2^8:
// small grids are full of touching and coincident primitives), an exact power-of-two scale, and
// one or two small meshes (3-8 vertices, 1-8 triangles with any indices: repeated vertices,
// shared and coincident triangles) with integer positions at t = 0 and t = 1. Minimum separation
// 0. Checked:
//  - every contact the mesh query reports is a hit of the same primitive test on the same pair
//    (the brute-force loop runs the same test with the same vertex order);
//  - every hit of the loop that the mesh query does not report (its broad phase or its primitive
//    boxes left the pair out) is proven contact-free by the exact integer reference of the tests
//    (support/exact_ccd.hpp): the broad phase never drops a pair that may touch.
//  - the result is the same on 1 and 2 threads.
#include "fuzz_input.hpp"
#include "impact/ccd/mesh_ccd.hpp"
#include "support/exact_ccd.hpp"
#include "support/mesh_ccd_pairs.hpp"

#include <array>
#include <cmath>
#include <cstdint>
#include <set>
#include <string>
#include <vector>

namespace {

using Key = impact::test::MeshCcdKey;

struct IntMotion {
  std::vector<std::array<std::int64_t, 3>> p0, p1;
  std::vector<std::array<std::int32_t, 3>> faces;
};

IntMotion decode(impact::fuzz::Input& in, std::int64_t r) {
  IntMotion m;
  const int nv = 3 + in.byte() % 6, nf = 1 + in.byte() % 8;
  for (int k = 0; k < nv; ++k) {
    std::array<std::int64_t, 3> a{}, b{};
    for (auto& x : a) x = in.range(-r, r);
    for (auto& x : b) x = in.range(-r, r);
    m.p0.push_back(a);
    m.p1.push_back(b);
  }
  for (int f = 0; f < nf; ++f) m.faces.push_back({static_cast<std::int32_t>(in.byte() % nv), static_cast<std::int32_t>(in.byte() % nv),
                                                  static_cast<std::int32_t>(in.byte() % nv)});
  return m;
}

template <class S> struct Motion {
  impact::Vertices<S> V0, V1;
  impact::Faces F;
};

template <class S> Motion<S> to_motion(const IntMotion& m, int shift) {
  Motion<S> out;
  const auto n = static_cast<Eigen::Index>(m.p0.size());
  out.V0.resize(n, 3);
  out.V1.resize(n, 3);
  for (Eigen::Index v = 0; v < n; ++v)
    for (int i = 0; i < 3; ++i) {
      out.V0(v, i) = static_cast<S>(std::ldexp(static_cast<double>(m.p0[std::size_t(v)][std::size_t(i)]), -shift));
      out.V1(v, i) = static_cast<S>(std::ldexp(static_cast<double>(m.p1[std::size_t(v)][std::size_t(i)]), -shift));
    }
  out.F.resize(static_cast<Eigen::Index>(m.faces.size()), 3);
  for (std::size_t f = 0; f < m.faces.size(); ++f)
    for (int k = 0; k < 3; ++k) out.F(Eigen::Index(f), k) = m.faces[f][std::size_t(k)];
  return out;
}

std::string describe(const Key& k) {
  std::string s = k[0] == 0 ? "vertex-face (vertex mesh " : "edge-edge (";
  for (std::size_t i = 1; i < 5; ++i) s += (i > 1 ? ", " : "") + std::to_string(k[i]);
  return s + ")";
}

template <class S> void check(const IntMotion& a, const IntMotion* b, int shift) {
  const bool self = b == nullptr;
  const IntMotion& bi = self ? a : *b;
  const Motion<S> ma = to_motion<S>(a, shift), mb = to_motion<S>(bi, shift);
  const auto va = impact::make_mesh_motion(ma.V0, ma.V1, ma.F), vb = impact::make_mesh_motion(mb.V0, mb.V1, mb.F);
  const impact::CcdOptions o;
  const auto ta = impact::SweptMeshBvh<S>::build(va), tb = impact::SweptMeshBvh<S>::build(vb);
  const auto run = [&](int threads) { return self ? impact::mesh_self_ccd(va, ta, o, threads) : impact::mesh_ccd(va, ta, vb, tb, o, threads); };
  const auto r = run(1);
  const std::set<Key> got = impact::test::contact_keys(r);
  if (impact::test::contact_keys(run(2)) != got) impact::fuzz::fail("different contacts on 1 and 2 threads");

  // The loop over every primitive pair: the same tests, the same vertex orders as mesh_ccd's.
  const auto P = [](const Motion<S>& m, bool end, std::int32_t v) { return impact::Vec3<S>((end ? m.V1 : m.V0).row(v).transpose()); };
  std::set<Key> all;
  std::vector<std::pair<Key, impact::test::IntCcdQuery>> queries;
  impact::test::for_each_primitive_pair(
      ma.F, mb.F, self,
      [&](int mesh, std::int32_t v, std::int32_t f) {
        const Motion<S>& mv = mesh == 0 ? ma : mb;
        const Motion<S>& mf = mesh == 0 ? mb : ma;
        const IntMotion& iv = mesh == 0 ? a : bi;
        const IntMotion& iff = mesh == 0 ? bi : a;
        const auto& t = iff.faces[std::size_t(f)];
        const auto res = impact::vertex_face_ccd(P(mv, false, v), P(mf, false, t[0]), P(mf, false, t[1]), P(mf, false, t[2]), P(mv, true, v),
                                                 P(mf, true, t[0]), P(mf, true, t[1]), P(mf, true, t[2]), o);
        if (!res.hit) return;
        impact::test::IntCcdQuery q;
        q.vertex_face = true;
        const std::int32_t ids[4] = {v, t[0], t[1], t[2]};
        for (std::size_t k = 0; k < 4; ++k) {
          const IntMotion& m = k == 0 ? iv : iff;
          q.points[k] = m.p0[std::size_t(ids[k])];
          q.points[4 + k] = m.p1[std::size_t(ids[k])];
        }
        const Key key{0, mesh, v, f, 0};
        all.insert(key);
        queries.push_back({key, q});
      },
      [&](std::int32_t a0, std::int32_t a1, std::int32_t b0, std::int32_t b1) {
        const auto res = impact::edge_edge_ccd(P(ma, false, a0), P(ma, false, a1), P(mb, false, b0), P(mb, false, b1), P(ma, true, a0),
                                               P(ma, true, a1), P(mb, true, b0), P(mb, true, b1), o);
        if (!res.hit) return;
        impact::test::IntCcdQuery q;
        q.vertex_face = false;
        q.points = {a.p0[std::size_t(a0)], a.p0[std::size_t(a1)], bi.p0[std::size_t(b0)], bi.p0[std::size_t(b1)],
                    a.p1[std::size_t(a0)], a.p1[std::size_t(a1)], bi.p1[std::size_t(b0)], bi.p1[std::size_t(b1)]};
        const Key key{1, a0, a1, b0, b1};
        all.insert(key);
        queries.push_back({key, q});
      });
  for (const Key& k : got)
    if (!all.count(k)) impact::fuzz::fail("mesh CCD reports a contact the primitive test does not: " + describe(k));
  for (const auto& [key, q] : queries) {
    if (got.count(key)) continue;
    using impact::test::ExactAnswer;
    if (impact::test::certify_no_contact(q, {}, 200000) == ExactAnswer::NoContact) continue;
    if (impact::test::certify_no_contact(q, {}, 4000000) == ExactAnswer::NoContact) continue;
    impact::fuzz::fail("mesh CCD left out a pair that the exact reference cannot prove apart: " + describe(key));
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  impact::fuzz::Input in(data, size);
  const std::uint8_t mode = in.byte();
  const bool self = (mode & 1u) != 0, is_float = (mode & 2u) != 0;
  const int bits = 1 + in.byte() % 8;  // coordinates in [-2^bits, 2^bits]
  const int shift = is_float ? in.byte() % 24 : in.byte() % 64;
  const std::int64_t r = std::int64_t(1) << bits;
  const IntMotion a = decode(in, r);
  const IntMotion b = self ? IntMotion{} : decode(in, r);
  if (is_float) check<float>(a, self ? nullptr : &b, shift);
  else check<double>(a, self ? nullptr : &b, shift);
  return 0;
}
