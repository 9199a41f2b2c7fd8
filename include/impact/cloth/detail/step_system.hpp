// SPDX-License-Identifier: MIT
/// \file
/// Internals of cloth_collision_step: the combined system (cloth vertices first, then every
/// obstacle's, with infinite mass) kept between steps in the workspace, and the candidate
/// primitive pair. The stages over one step are Stepper's (stepper.hpp). Not part of the
/// interface.
#pragma once

#include "impact/ccd/mesh_ccd.hpp"
#include "impact/cloth/detail/start_intersections.hpp"
#include "impact/cloth/step_options.hpp"
#include "impact/core/types.hpp"

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace impact::detail::cloth {

/// A candidate primitive pair: vertex-face (v[0] against face v[1..3]) or edge-edge.
struct Prim {
  std::uint8_t ee = 0;
  std::int32_t v[4] = {-1, -1, -1, -1};
  friend bool operator<(const Prim& a, const Prim& b) {
    if (a.ee != b.ee) return a.ee < b.ee;
    return std::lexicographical_compare(a.v, a.v + 4, b.v, b.v + 4);
  }
  friend bool operator==(const Prim& a, const Prim& b) {
    return a.ee == b.ee && a.v[0] == b.v[0] && a.v[1] == b.v[1] && a.v[2] == b.v[2] && a.v[3] == b.v[3];
  }
};

/// The broad phase's and the passes' per-step arrays (Stepper's, which sets every one up again in
/// each step before reading it): kept between steps only for their storage, so that a step at
/// millions of candidates does not allocate and fault in its arrays afresh.
template <class S>
struct StepBuffers {
  std::vector<Prim> cand, found;
  std::vector<Aabb<S>> ebox, gbox, tbox, old_gbox, old_tbox;
  std::vector<double> d0, path, key, toi;
  std::vector<std::uint8_t> d0_exact, changed, status;
  std::vector<std::uint32_t> stamp, inc_off, inc, inc_fill, todo, run;
  std::vector<CcdResult<S>> res;
  std::vector<PiercePlane> plane0;
  std::vector<std::pair<std::int32_t, std::int32_t>> pair_stack;
  Vertices<S> x1_seen;
};

/// Sets v to n copies of x. Storage that must grow gets half as much again in reserve: the
/// candidates grow by up to a third per step while a stack lands, and an array allocated at
/// exactly its size would be allocated, and its pages faulted in, afresh in each such step.
template <class T>
void refill(std::vector<T>& v, std::size_t n, const T& x) {
  if (n > v.capacity()) {
    v.clear();
    v.reserve(n + n / 2);
  }
  v.assign(n, x);
}

/// Everything kept between steps (in a workspace): combined arrays, the tree.
template <class S>
struct System {
  Faces F;                         // cloth triangles, then every obstacle's (offset)
  std::vector<std::uint8_t> tri_obstacle;
  std::int32_t n_cloth = 0;
  Vertices<S> X0, X1;              // combined positions
  std::vector<double> w;           // inverse masses (0 = infinite)
  SweptMeshBvh<S> tree;
  bool has_tree = false;
  Faces tree_faces;                // the faces the tree was built for
  S tree_inflate = S(0);
  // With the tree: each node's parent (-1 at the root) and each triangle's leaf, for refitting
  // only the leaves whose triangles grew and their ancestors (Stepper::refit_grown).
  std::vector<std::int32_t> tree_parent, tri_leaf;
  // With the tree: each node's triangle count (the self-walk's fixed split rule) and the walk's
  // front from the last gathering (Stepper::self_pairs): node pairs where it stopped, in walk
  // order (empty: walk from the root), with the share of non-overlapping entries of the last walk
  // from the root, per overlapping leaf pair, for deciding when the front has gone stale.
  std::vector<std::int32_t> tree_count;
  std::vector<std::pair<std::int32_t, std::int32_t>> front, front_next;
  double front_apart_per_leaf = 0;
  // With the faces (Stepper::build_ownership): the vertices (bits 0-2) and edges (bits 3-5) each
  // triangle owns, the vertex -> incident triangles index (CSR), and the faces they were built for.
  std::vector<std::uint8_t> own;
  std::vector<std::uint32_t> vtri_off;
  std::vector<std::int32_t> vtri;
  Faces own_faces;
  // The last step's combined end positions, when that step's x0 was checked free of
  // intersections and it ended collision_free with nothing excluded (Stepper::note_end): then a
  // next x0 equal to them, for the same faces, is free of intersections too (check_pierce).
  Vertices<S> clean_end;
  bool clean_end_valid = false;
  StepBuffers<S> buf;
};

inline std::string pair_name(const Prim& p) {
  auto s = [](std::int32_t v) { return std::to_string(v); };
  if (p.ee) return "edge (" + s(p.v[0]) + "," + s(p.v[1]) + ")-edge (" + s(p.v[2]) + "," + s(p.v[3]) + ")";
  return "vertex " + s(p.v[0]) + "-face (" + s(p.v[1]) + "," + s(p.v[2]) + "," + s(p.v[3]) + ")";
}

inline ClothPair to_pair(const Prim& p) {
  ClothPair c;
  c.edge_edge = p.ee != 0;
  for (int k = 0; k < 4; ++k) c.v[k] = p.v[k];
  return c;
}

}  // namespace impact::detail::cloth
