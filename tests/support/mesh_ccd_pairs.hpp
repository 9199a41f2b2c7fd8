// SPDX-License-Identifier: MIT
// The primitive pairs of mesh CCD, as mesh_ccd and mesh_self_ccd name them, for the brute-force
// loops of the mesh CCD tests (tests/ccd/test_mesh_ccd.cpp) and fuzz target (fuzz_mesh_ccd.cpp):
// every pair enumerated, and a query's contacts as a set of keys.
#pragma once

#include "impact/ccd/mesh_ccd.hpp"

#include <array>
#include <cstdint>
#include <set>
#include <utility>

namespace impact::test {

/// A contact's key: {0, vertex_mesh, vertex, face, 0} (vertex-face) or {1, a0, a1, b0, b1}.
using MeshCcdKey = std::array<std::int32_t, 5>;

template <class S> std::set<MeshCcdKey> contact_keys(const MeshCcdResult<S>& r) {
  std::set<MeshCcdKey> k;
  for (const auto& c : r.contacts) {
    if (c.kind == MeshCcdKind::VertexFace)
      k.insert({0, c.vertex_mesh, c.vertex, c.face, 0});
    else
      k.insert({1, c.a0, c.a1, c.b0, c.b1});
  }
  return k;
}

/// The distinct edges of a face array, each with its smaller vertex first.
inline std::set<std::array<std::int32_t, 2>> unique_edges(const Faces& F) {
  std::set<std::array<std::int32_t, 2>> e;
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      std::int32_t a = F(f, k), b = F(f, (k + 1) % 3);
      if (a > b) std::swap(a, b);
      e.insert({a, b});
    }
  return e;
}

/// Calls vf(mesh, v, f) for every vertex v of a triangle of one mesh against every triangle f of the
/// other (mesh 0: a vertex of `a` against a face of `b`; 1: the reverse, two meshes only; self CCD:
/// once, a vertex of its own face skipped) and ee(a0, a1, b0, b1) for every edge of `a` against
/// every edge of `b` (each with its smaller vertex first; self: every unordered pair of edges
/// without a shared vertex once, (a0, a1) < (b0, b1)): the pairs mesh CCD tests, named as it names
/// its contacts.
template <class VF, class EE> void for_each_primitive_pair(const Faces& a, const Faces& b, bool self, VF&& vf, EE&& ee) {
  const auto vertex_face = [&](int mesh, const Faces& fv, const Faces& ff) {
    std::set<std::int32_t> verts;
    for (Eigen::Index f = 0; f < fv.rows(); ++f)
      for (int j = 0; j < 3; ++j) verts.insert(fv(f, j));
    for (std::int32_t v : verts)
      for (std::int32_t f = 0; f < ff.rows(); ++f)
        if (!(self && (ff(f, 0) == v || ff(f, 1) == v || ff(f, 2) == v))) vf(mesh, v, f);
  };
  vertex_face(0, a, b);
  if (!self) vertex_face(1, b, a);
  const auto eb = unique_edges(b);
  for (const auto& x : unique_edges(a))
    for (const auto& y : eb)
      if (!(self && (x[0] == y[0] || x[0] == y[1] || x[1] == y[0] || x[1] == y[1] || !(x < y)))) ee(x[0], x[1], y[0], y[1]);
}

}  // namespace impact::test
