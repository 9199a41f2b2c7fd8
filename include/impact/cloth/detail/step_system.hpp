// SPDX-License-Identifier: MIT
/// \file
/// Internals of cloth_collision_step: the combined system (cloth vertices first, then every
/// obstacle's, with infinite mass), the swept tree over all its triangles, the candidate
/// primitive pairs, and the stages. Not part of the interface.
#pragma once

#include "impact/bvh/traverse.hpp"
#include "impact/ccd/mesh_ccd.hpp"
#include "impact/cloth/detail/relax_contacts.hpp"
#include "impact/cloth/step_options.hpp"
#include "impact/cloth/zone_projection.hpp"
#include "impact/core/error.hpp"
#include "impact/core/parallel.hpp"
#include "impact/narrow/closest_point.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <string>
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

template <class D>
void check_coords(const Eigen::MatrixBase<D>& X, const std::string& what) {
  for (Eigen::Index i = 0; i < X.rows(); ++i)
    for (Eigen::Index j = 0; j < X.cols(); ++j) {
      const double c = static_cast<double>(X(i, j));
      if (!std::isfinite(c)) throw InvalidInput(what + ": row " + std::to_string(i) + " has a NaN or infinite coordinate");
      if (std::abs(c) >= 1e30) throw InvalidInput(what + ": row " + std::to_string(i) + " has a coordinate beyond 1e30");
    }
}

template <class S>
void validate_step(const Faces& F, const Eigen::Matrix<S, Eigen::Dynamic, 1>& wm, const Vertices<S>& x0, const Vertices<S>& x1,
                   const ClothObstacles<S>& obs, const ClothCollisionOptions<S>& o) {
  const std::string fn = "cloth_collision_step: ";
  validate_mesh(x0, F, "cloth_collision_step (cloth at x0)");
  if (x1.rows() != x0.rows()) throw InvalidInput(fn + "x1 has " + std::to_string(x1.rows()) + " rows, x0 has " + std::to_string(x0.rows()));
  if (wm.rows() != x0.rows())
    throw InvalidInput(fn + "inverse_mass has " + std::to_string(wm.rows()) + " entries for " + std::to_string(x0.rows()) + " vertices");
  check_coords(x0, fn + "x0");
  check_coords(x1, fn + "x1");
  for (Eigen::Index i = 0; i < wm.rows(); ++i)
    if (!std::isfinite(static_cast<double>(wm[i])) || wm[i] < S(0))
      throw InvalidInput(fn + "inverse_mass[" + std::to_string(i) + "] is negative, NaN or infinite (0 means infinite mass)");
  for (std::size_t k = 0; k < obs.rigid.size(); ++k) {
    const auto& r = obs.rigid[k];
    const std::string w = fn + "rigid obstacle " + std::to_string(k);
    if (!r.mesh) throw InvalidInput(w + ": no mesh");
    validate_mesh(r.mesh->V, r.mesh->F, w);
    check_coords(r.mesh->V, w);
    if (!r.pose0.is_finite() || !r.pose1.is_finite()) throw InvalidInput(w + ": pose with a NaN or infinite entry");
  }
  for (std::size_t k = 0; k < obs.kinematic.size(); ++k) {
    const auto& r = obs.kinematic[k];
    const std::string w = fn + "kinematic obstacle " + std::to_string(k);
    if (!r.x0 || !r.x1 || !r.faces) throw InvalidInput(w + ": missing x0, x1 or faces");
    validate_mesh(*r.x0, *r.faces, w);
    if (r.x1->rows() != r.x0->rows()) throw InvalidInput(w + ": x0 and x1 have different vertex counts");
    check_coords(*r.x0, w + " x0");
    check_coords(*r.x1, w + " x1");
  }
  const double h = static_cast<double>(o.thickness);
  if (!(h > 0) || !std::isfinite(h)) throw InvalidInput(fn + "thickness must be positive and finite");
  const double pd = static_cast<double>(o.proximity_distance);
  if (!std::isfinite(pd) || (pd != 0 && pd < h)) throw InvalidInput(fn + "proximity_distance must be 0 (2 h) or >= thickness");
  if (!std::isfinite(double(o.friction)) || o.friction < S(0)) throw InvalidInput(fn + "friction must be finite and >= 0");
  if (!std::isfinite(double(o.separation_margin)) || o.separation_margin < S(0) || o.separation_margin > S(10))
    throw InvalidInput(fn + "separation_margin must be in [0, 10]");
  if (o.impulse_passes < 0 || o.max_zone_iterations < 0 || o.max_projection_iterations < 1)
    throw InvalidInput(fn + "negative pass or iteration count");
  if (o.impulse_relax_rounds < 0) throw InvalidInput(fn + "impulse_relax_rounds must be >= 0");
  if (o.proximity_rounds < 1) throw InvalidInput(fn + "proximity_rounds must be >= 1");
  if (!(o.proximity_tolerance > S(0)) || !std::isfinite(double(o.proximity_tolerance)))
    throw InvalidInput(fn + "proximity_tolerance must be positive and finite");
  if (!(o.projection_tolerance > S(0)) || !std::isfinite(double(o.projection_tolerance)))
    throw InvalidInput(fn + "projection_tolerance must be positive and finite");
  if (!(o.ccd.tolerance >= 0) || !std::isfinite(o.ccd.tolerance) || o.ccd.max_iterations < 1 || o.ccd.recheck_iterations < 0)
    throw InvalidInput(fn + "ccd options: tolerance must be finite and >= 0, max_iterations >= 1, recheck_iterations >= 0");
}

/// The stages over one step. Positions are the combined sys.X0 / sys.X1.
template <class S>
class Stepper {
 public:
  using Clock = std::chrono::steady_clock;

  Stepper(System<S>& sys, const ClothCollisionOptions<S>& opt, ClothStepStats& stats) : sys_(sys), opt_(opt), stats_(stats) {
    h_ = static_cast<double>(opt.thickness);
    prox_ = opt.proximity_distance > S(0) ? static_cast<double>(opt.proximity_distance) : 2 * h_;
    target_ = h_ * (1 + static_cast<double>(opt.separation_margin));
    ccd_ = opt.ccd;
    ccd_.min_separation = h_;
    ccd_.t_max = 1.0;
    band_ = 0.5 * static_cast<double>(opt.separation_margin) * h_;
  }

  void assemble(const Faces& F, const Eigen::Matrix<S, Eigen::Dynamic, 1>& wm, const Vertices<S>& x0, const Vertices<S>& x1,
                const ClothObstacles<S>& obs) {
    const auto t0 = Clock::now();
    Eigen::Index nv = x0.rows(), nf = F.rows();
    for (const auto& r : obs.rigid) nv += r.mesh->V.rows(), nf += r.mesh->F.rows();
    for (const auto& k : obs.kinematic) nv += k.x0->rows(), nf += k.faces->rows();
    sys_.n_cloth = static_cast<std::int32_t>(x0.rows());
    sys_.X0.resize(nv, 3);
    sys_.X1.resize(nv, 3);
    sys_.F.resize(nf, 3);
    sys_.w.assign(static_cast<std::size_t>(nv), 0.0);
    sys_.tri_obstacle.assign(static_cast<std::size_t>(nf), 1);
    sys_.X0.topRows(x0.rows()) = x0;
    sys_.X1.topRows(x0.rows()) = x1;
    sys_.F.topRows(F.rows()) = F;
    for (Eigen::Index i = 0; i < F.rows(); ++i) sys_.tri_obstacle[static_cast<std::size_t>(i)] = 0;
    for (Eigen::Index i = 0; i < x0.rows(); ++i) sys_.w[static_cast<std::size_t>(i)] = static_cast<double>(wm[i]);
    Eigen::Index vo = x0.rows(), fo = F.rows();
    for (const auto& r : obs.rigid) {
      for (Eigen::Index i = 0; i < r.mesh->V.rows(); ++i) {
        const Vec3<S> p = r.mesh->V.row(i).transpose();
        sys_.X0.row(vo + i) = r.pose0.apply(p).transpose();
        sys_.X1.row(vo + i) = r.pose1.apply(p).transpose();
      }
      sys_.F.middleRows(fo, r.mesh->F.rows()) = r.mesh->F.array() + static_cast<int>(vo);
      vo += r.mesh->V.rows();
      fo += r.mesh->F.rows();
    }
    for (const auto& k : obs.kinematic) {
      sys_.X0.middleRows(vo, k.x0->rows()) = *k.x0;
      sys_.X1.middleRows(vo, k.x0->rows()) = *k.x1;
      sys_.F.middleRows(fo, k.faces->rows()) = k.faces->array() + static_cast<int>(vo);
      vo += k.x0->rows();
      fo += k.faces->rows();
    }
    check_coords(sys_.X0, "cloth_collision_step: rigid obstacle at pose0");
    check_coords(sys_.X1, "cloth_collision_step: rigid obstacle at pose1");
    changed_.assign(static_cast<std::size_t>(nv), 1);
    path_.assign(static_cast<std::size_t>(nv), 0.0);
    x1_seen_ = sys_.X1;
    moves_noted_ = 0;
    // Coordinate scale, for the rounding margin of distances computed in double.
    scale_ = std::max(sys_.X0.cwiseAbs().maxCoeff(), sys_.X1.cwiseAbs().maxCoeff());
    // Conservative rounding margin of the distance bound that lets a candidate skip its CCD
    // (distances computed in double from coordinates of magnitude <= scale_).
    bound_margin_ = 512 * std::numeric_limits<double>::epsilon() * scale_ + 1e-9 * h_;
    // The envelope's slack: how far a movable vertex's end position may move during the step
    // without a new gathering (a heuristic: only the cost of re-gathering depends on it). At
    // h / 2 a resting vertex's envelope grown for the CCD reaches no farther than its start
    // grown for the proximity pairs (h / 2 + h / 2 = prox / 2 at the default prox = 2 h).
    slack_ = static_cast<S>(h_ / 2);
    near_inflate_ = half_up(prox_);
    ccd_inflate_ = half_up(h_);
    const S inflate_needed = static_cast<S>(prox_ / 2);
    if (!(sys_.has_tree && sys_.tree_faces.rows() == sys_.F.rows() && sys_.tree_faces == sys_.F && sys_.tree_inflate >= inflate_needed)) {
      sys_.tree = SweptMeshBvh<S>::build(motion(), prox_);
      sys_.has_tree = true;
      sys_.tree_faces = sys_.F;
      sys_.tree_inflate = sys_.tree.inflate;
    }
    stats_.broad.ms += ms_since(t0);
  }

  /// Gathers the candidates of the current motion, classifies the start and throws on violations.
  void check_start() {
    gather();
    stats_.candidates_vf = stats_.candidates_ee = 0;
    for (const auto& p : cand_) (p.ee ? stats_.candidates_ee : stats_.candidates_vf)++;
    // Distances at x0 (double); the pairs near h get the exact-enough static CCD. Pairs whose
    // start boxes are farther apart than both thresholds need no closest points.
    // (the CCD tolerance is relative to a query's extent, at most twice the coordinate scale)
    const auto t0 = Clock::now();
    const double margin = 4 * ccd_.tolerance * scale_ + 1e-4 * h_ + 64 * std::numeric_limits<double>::epsilon() * scale_;
    const double reach = std::max(prox_, h_ + margin);
    std::vector<Prim> bad;
    for (std::size_t i = 0; i < cand_.size(); ++i) {
      const Prim& p = cand_[i];
      const double lb = start_box_distance(p);
      d0_[i] = lb;
      if (lb >= reach) continue;
      Contact c = closest(p, /*start=*/true);
      d0_[i] = c.dist;
      d0_exact_[i] = 1;
      if (c.dist < prox_) near_.push_back({p, c});
      if (c.dist < h_ + margin) {
        const auto r = ccd(p, /*static_start=*/true);
        if (r.hit) bad.push_back(p);
      }
    }
    if (!bad.empty()) {
      if (opt_.on_start_violation == StartViolation::Throw) {
        std::string msg = "cloth_collision_step: x0 has " + std::to_string(bad.size()) + " pair(s) closer than the thickness: ";
        for (std::size_t i = 0; i < std::min<std::size_t>(bad.size(), 8); ++i) msg += (i ? ", " : "") + pair_name(bad[i]);
        if (bad.size() > 8) msg += ", ...";
        throw InvalidInput(msg);
      }
      excluded_ = bad;
      std::sort(excluded_.begin(), excluded_.end());
      for (const auto& p : bad) stats_.start_violations.push_back(to_pair(p));
      near_.erase(std::remove_if(near_.begin(), near_.end(), [&](const Near& q) { return is_excluded(q.p); }), near_.end());
    }
    stats_.proximity.ms += ms_since(t0);
    broad_acc_ = 0;  // the start's gathering is counted in stats_.broad; no stage subtracts it
  }

  /// Stage 1: pairs within the proximity distance at x0 stop approaching (inelastic) with
  /// friction: each pair's gap along its normal at x0 (closest points' weights at x0) may not
  /// fall below its distance at x0. Relaxed in rounds (relax_contacts) until every pair meets
  /// that to proximity_tolerance h, or proximity_rounds run out (the CCD stages take the rest).
  void proximity_stage() {
    const auto t0 = Clock::now();
    contacts_.reserve(near_.size());
    for (const auto& q : near_)
      if (q.c.dist > 0) contacts_.push_back(constraint_of(q.p, q.c.a, q.c.n, q.c.dist));
    std::vector<std::uint8_t> acted(contacts_.size(), 0);
    const RelaxStats r = relax(opt_.proximity_rounds, &acted);
    stats_.proximity.passes += r.rounds;
    stats_.proximity_impulses += r.impulses;
    stats_.proximity_converged = r.converged;
    for (auto a : acted) stats_.proximity.collisions += a;
    stats_.proximity.ms += ms_since(t0);
  }

  /// Stage 2: passes of CCD impulses, earliest first.
  void impulse_stage() {
    const auto t0 = Clock::now();
    precise_ = false;
    for (int pass = 0; pass < opt_.impulse_passes; ++pass) {
      const auto hits = detect();
      ++stats_.impulses.passes;
      if (hits.empty()) break;
      for (const auto& hit : hits) {
        ZoneConstraint k = constraint_at_hit(hit);
        if (apply_impulse(k)) ++stats_.impulses.collisions;
        if (opt_.impulse_relax_rounds > 0) contacts_.push_back(k);
      }
      // The hits join the contact set and it is relaxed again: an impulse that stops a landing
      // sheet pushes the sheet below it into the resting stack, which the proximity pairs carry
      // down to the floor (without it, those pairs are the next pass's and the zones' hits).
      if (opt_.impulse_relax_rounds > 0) stats_.impulse_relax_impulses += relax(opt_.impulse_relax_rounds, nullptr).impulses;
    }
    stats_.impulses.ms += ms_since(t0) - broad_ms_in_stage();
  }

  /// Stage 3: impact zones (Harmon 2008 or rigid).
  void zone_stage() {
    const auto t0 = Clock::now();
    precise_ = true;
    const std::size_t nv = sys_.w.size();
    // The positions each zone's resolution in a round starts from and stays closest to: the end
    // positions before that round (before the stage in round 0). A zone found again in a later
    // round (new hits, or merged with another zone) keeps every constraint it had and is
    // projected from where the last round left it, which already meets them: the solver meets
    // mostly the new constraints, where a projection from the positions before the stage would
    // solve the whole, grown zone again from scratch (at 10^5 vertices, a zone of 5,500
    // constraints three times over in one step). Every change is still W A^T lambda with
    // lambda >= 0 per round, so the zone's momentum is kept.
    Vertices<S> xhat;
    std::vector<std::int32_t> parent(nv);
    std::iota(parent.begin(), parent.end(), 0);
    auto find = [&](std::int32_t v) {
      while (parent[static_cast<std::size_t>(v)] != v) {
        parent[static_cast<std::size_t>(v)] = parent[static_cast<std::size_t>(parent[static_cast<std::size_t>(v)])];
        v = parent[static_cast<std::size_t>(v)];
      }
      return v;
    };
    std::vector<ZoneConstraint> all;
    std::vector<std::int32_t> anchor;  // one movable vertex of each constraint (-1: none)
    for (int round = 0; round < opt_.max_zone_iterations; ++round) {
      const auto hits = detect();
      ++stats_.zones.passes;
      if (hits.empty()) break;
      xhat = sys_.X1;
      std::vector<std::int32_t> touched;
      for (const auto& hit : hits) {
        ZoneConstraint k = constraint_at_hit(hit);
        std::int32_t first = -1;
        for (int j = 0; j < k.count; ++j) {
          if (!(sys_.w[static_cast<std::size_t>(k.v[j])] > 0)) continue;
          if (first < 0) first = k.v[j];
          else parent[static_cast<std::size_t>(find(k.v[j]))] = find(first);
        }
        all.push_back(k);
        anchor.push_back(first);
        if (first >= 0) touched.push_back(first);
        ++stats_.zones.collisions;
      }
      // Zones touched in this round: every constraint of the zone, solved together.
      std::vector<std::int32_t> roots;
      for (auto v : touched) roots.push_back(find(v));
      std::sort(roots.begin(), roots.end());
      roots.erase(std::unique(roots.begin(), roots.end()), roots.end());
      std::vector<std::vector<std::size_t>> members(roots.size());
      for (std::size_t c = 0; c < all.size(); ++c) {
        if (anchor[c] < 0) continue;
        const auto it = std::lower_bound(roots.begin(), roots.end(), find(anchor[c]));
        if (it != roots.end() && *it == find(anchor[c])) members[static_cast<std::size_t>(it - roots.begin())].push_back(c);
      }
      for (std::size_t z = 0; z < roots.size(); ++z) resolve_zone(all, members[z], roots[z], xhat, parent, find);
    }
    stats_.zones.ms += ms_since(t0) - broad_ms_in_stage();
  }

  /// Stage 4: the fail-safe. Colliding pairs' movable vertices go back to x0 until the CCD finds
  /// nothing (boxes only shrink, so the candidates of one gathering stay a superset).
  void failsafe_stage() {
    const auto t0 = Clock::now();
    precise_ = true;
    auto hits = detect();
    ++stats_.failsafe.passes;
    while (!hits.empty()) {
      bool froze = false;
      for (const auto& hit : hits) {
        bool any = false;
        for (int j = 0; j < 4; ++j) {
          const std::int32_t v = hit.p.v[j];
          if (sys_.w[static_cast<std::size_t>(v)] > 0 && sys_.X1.row(v) != sys_.X0.row(v)) {
            sys_.X1.row(v) = sys_.X0.row(v);
            changed_[static_cast<std::size_t>(v)] = 1;
            ++stats_.frozen_vertices;
            froze = any = true;
          }
        }
        if (any) ++stats_.failsafe.collisions;
      }
      if (!froze) break;
      stats_.failsafe_used = true;
      hits = test_changed();
      ++stats_.failsafe.passes;
    }
    if (!hits.empty()) {
      stats_.collision_free = false;
      for (const auto& hit : hits) stats_.unresolved.push_back(to_pair(hit.p));
    }
    stats_.failsafe.ms += ms_since(t0) - broad_ms_in_stage();
  }

  void write_back(Vertices<S>& x1) const { x1 = sys_.X1.topRows(sys_.n_cloth); }

 private:
  struct Contact {
    double dist = 0;
    double a[4] = {0, 0, 0, 0};
    Vec3<double> n = Vec3<double>::Zero();
  };
  struct Near {
    Prim p;
    Contact c;
  };
  struct Hit {
    Prim p;
    CcdResult<S> r;
    std::uint32_t c = 0;  // candidate index
  };

  static double ms_since(Clock::time_point t) { return std::chrono::duration<double, std::milli>(Clock::now() - t).count(); }
  double broad_ms_in_stage() {
    const double b = broad_acc_;
    broad_acc_ = 0;
    return b;
  }

  MeshMotion<S> motion() const { return {&sys_.X0, &sys_.X1, &sys_.F}; }
  Vec3<double> p0(std::int32_t v) const { return sys_.X0.row(v).transpose().template cast<double>(); }
  Vec3<double> p1(std::int32_t v) const { return sys_.X1.row(v).transpose().template cast<double>(); }

  bool is_excluded(const Prim& p) const { return !excluded_.empty() && std::binary_search(excluded_.begin(), excluded_.end(), p); }

  /// Ownership of vertices and edges by one of their triangles, so that each primitive pair is
  /// generated by exactly one triangle pair (no sorting or deduplication): a vertex or edge is
  /// owned by the first triangle that contains it. Built when the faces change.
  void build_ownership() {
    const Faces& F = sys_.F;
    own_.assign(static_cast<std::size_t>(F.rows()), 0);
    std::vector<std::uint8_t> seen(sys_.w.size(), 0);
    std::vector<std::pair<std::int32_t, std::int32_t>> edges;
    edges.reserve(static_cast<std::size_t>(F.rows()) * 3);
    for (Eigen::Index f = 0; f < F.rows(); ++f)
      for (int k = 0; k < 3; ++k) {
        const std::int32_t v = F(f, k);
        if (!seen[static_cast<std::size_t>(v)]) seen[static_cast<std::size_t>(v)] = 1, own_[static_cast<std::size_t>(f)] |= std::uint8_t(1u << k);
        std::int32_t a = F(f, k), c = F(f, (k + 1) % 3);
        if (a > c) std::swap(a, c);
        edges.push_back({a, c});
      }
    // First triangle of each edge: sort edge occurrences by (edge, triangle).
    std::vector<std::int64_t> order(edges.size());
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(), [&](std::int64_t x, std::int64_t y) { return edges[std::size_t(x)] < edges[std::size_t(y)]; });
    for (std::size_t i = 0; i < order.size(); ++i) {
      if (i > 0 && edges[std::size_t(order[i])] == edges[std::size_t(order[i - 1])]) continue;
      const auto occ = order[i];
      own_[std::size_t(occ / 3)] |= std::uint8_t(8u << (occ % 3));
    }
    // Vertex -> incident triangles (CSR), for the re-gathering of the triangles of escaped vertices.
    vtri_off_.assign(sys_.w.size() + 1, 0);
    for (Eigen::Index f = 0; f < F.rows(); ++f)
      for (int k = 0; k < 3; ++k) ++vtri_off_[std::size_t(F(f, k)) + 1];
    for (std::size_t v = 0; v + 1 < vtri_off_.size(); ++v) vtri_off_[v + 1] += vtri_off_[v];
    vtri_.resize(vtri_off_.back());
    std::vector<std::uint32_t> fill(vtri_off_.begin(), vtri_off_.end() - 1);
    for (Eigen::Index f = 0; f < F.rows(); ++f)
      for (int k = 0; k < 3; ++k) vtri_[fill[std::size_t(F(f, k))]++] = static_cast<std::int32_t>(f);
    own_faces_ = sys_.F;
  }

  /// d / 2 in S, rounded up so that twice it is at least d.
  static S half_up(double d) {
    S g = static_cast<S>(d / 2);
    while (2 * static_cast<double>(g) < d) g = std::nextafter(g, std::numeric_limits<S>::infinity());
    return g;
  }

  /// The box grown by g > 0, rounded outwards: the rounding error of b -/+ g is at most half an
  /// ulp of |b| + g, and the extra 2 eps (|b| + g) covers it and the rounding of the margin's own
  /// subtraction (g > 0, so the margin is never zero).
  static Aabb<S> grow(Aabb<S> b, S g) {
    const S e = 2 * std::numeric_limits<S>::epsilon();
    for (int i = 0; i < 3; ++i) {
      b.min[i] = (b.min[i] - g) - e * (std::abs(b.min[i]) + g);
      b.max[i] = (b.max[i] + g) + e * (std::abs(b.max[i]) + g);
    }
    return b;
  }

  /// The grown envelope of vertex v (envelope box e): its start grown by half the proximity
  /// distance and e grown by h / 2. Two primitives closer than the proximity distance at x0 have
  /// overlapping start boxes grown by its half, and two that come within h during the step have
  /// overlapping swept boxes grown by h / 2 (their points' offset is under h on every axis), so
  /// the grown envelopes of every such pair overlap; nothing else needs them.
  Aabb<S> grown_envelope(std::size_t v, const Aabb<S>& e) const {
    Aabb<S> b;
    b.extend(sys_.X0.row(Eigen::Index(v)).transpose());
    return merge(grow(b, near_inflate_), grow(e, ccd_inflate_));
  }

  /// The candidates of the whole step, gathered once. Each vertex gets an envelope box: its swept
  /// box x0 -> x1 and, if it can move, a slack of h / 2 around it. Every later end position of the
  /// step that stays inside the envelope has its swept box inside it too, so the pairs gathered
  /// for the grown envelopes (grown_envelope) are a superset of the pairs closer than the
  /// proximity distance at x0 and of those that come within h in any such state: no pair is ever
  /// missed, and each CCD pass only re-tests candidates with a moved vertex (detect()). The tree is refitted to the envelopes (its
  /// topology comes from the first step); overlapping triangle pairs (not both obstacle) give the
  /// vertices and edges each owns (pairs_of), kept only when the primitives' own grown envelopes
  /// overlap; adjacent primitives (sharing a vertex) are skipped. When a vertex leaves its
  /// envelope later in the step, regather() grows only the envelopes that were left and adds the
  /// pairs they bring.
  void gather() {
    const auto t0 = Clock::now();
    ++stats_.broad.passes;
    if (own_faces_.rows() != sys_.F.rows() || own_faces_ != sys_.F) build_ownership();
    const Faces& F = sys_.F;
    const std::size_t nv = sys_.w.size(), nf = static_cast<std::size_t>(F.rows());
    ebox_.resize(nv);
    gbox_.resize(nv);
    for (std::size_t v = 0; v < nv; ++v) {
      ebox_[v] = envelope(v);
      gbox_[v] = grown_envelope(v, ebox_[v]);
    }
    tbox_.resize(nf);
    for (std::size_t f = 0; f < nf; ++f) tbox_[f] = triangle_envelope(f);
    old_gbox_ = gbox_;
    old_tbox_ = tbox_;
    refit_tree();
    cand_.clear();
    traverse_self(
        sys_.tree.tree, [](const Aabb<S>& x, const Aabb<S>& y) { return overlap(x, y); },
        [&](std::int32_t fa, std::int32_t fb) {
          pairs_of(fa, fb, cand_);
          return true;
        });
    // Per candidate: a lower bound on its distance at x0 (NaN: not known yet), the pass stamp;
    // the vertex -> candidate index is built when first needed.
    d0_.assign(cand_.size(), std::numeric_limits<double>::quiet_NaN());
    d0_exact_.assign(cand_.size(), 0);
    key_.assign(cand_.size(), -1.0);
    stamp_.assign(cand_.size(), 0);
    stamp_now_ = 0;
    inc_off_.clear();
    inc_.clear();
    inc_n_ = 0;
    last_hits_.clear();  // their candidates are re-tested anyway: every vertex counts as moved
    std::fill(changed_.begin(), changed_.end(), 1);
    const double ms = ms_since(t0);
    stats_.broad.ms += ms;
    broad_acc_ += ms;
  }

  /// A gathering again within the step, after moved vertices left their envelopes: those
  /// envelopes grow to hold the new end positions (envelopes only grow, so every candidate kept
  /// stays one), the tree is refitted, and the triangles of the grown vertices are queried against
  /// it. A pair that can newly overlap has a grown vertex among its four (all other boxes are
  /// unchanged), so its generating triangle pair (the owners of its two primitives) has a grown
  /// triangle: these queries find every new candidate. New candidates are appended (their caches
  /// start empty); the known ones keep their index, caches and hits.
  void regather() {
    const auto t0 = Clock::now();
    ++stats_.broad.passes;
    const Faces& F = sys_.F;
    const std::size_t nv = sys_.w.size(), nf = static_cast<std::size_t>(F.rows());
    std::vector<std::uint8_t> grown_tri(nf, 0);
    std::vector<std::int32_t> tris, verts;
    // old_gbox_, old_tbox_ hold the boxes before this gathering (copies of gbox_ and tbox_ from
    // gather(), brought up to date for the grown entries at the end).
    for (std::size_t v = 0; v < nv; ++v) {
      if (!changed_[v] || ebox_[v].contains(sys_.X1.row(Eigen::Index(v)).transpose())) continue;
      verts.push_back(static_cast<std::int32_t>(v));
      Aabb<S> b = envelope(v);
      b.extend(ebox_[v]);
      ebox_[v] = b;
      gbox_[v] = grown_envelope(v, b);
      for (std::uint32_t k = vtri_off_[v]; k < vtri_off_[v + 1]; ++k)
        if (!grown_tri[std::size_t(vtri_[k])]) grown_tri[std::size_t(vtri_[k])] = 1, tris.push_back(vtri_[k]);
    }
    for (auto f : tris) tbox_[std::size_t(f)] = triangle_envelope(std::size_t(f));
    refit_tree();
    std::vector<Prim> found;
    for (auto fa : tris) {
      const Aabb<S> box = tbox_[std::size_t(fa)];
      traverse(
          sys_.tree.tree, [&](const Aabb<S>& n) { return overlap(n, box); },
          [&](std::int32_t fb) {
            // each triangle pair once: a pair of two grown triangles from the smaller one
            if (fb == fa || (grown_tri[std::size_t(fb)] && fb < fa)) return true;
            if (overlap(box, tbox_[std::size_t(fb)])) pairs_of(fa, fb, found, /*only_new=*/true);
            return true;
          });
    }
    // pairs_of kept only the pairs not known yet: every candidate is generated by the one
    // triangle pair that owns its primitives, kept iff pairs_of's box tests hold, and boxes only
    // grow, so a pair is among the candidates iff those tests held for the boxes before this
    // gathering (old_gbox_, old_tbox_). Each triangle pair is visited once, so no pair twice;
    // sorted, so that the candidates' order (and the hits' order among equal times) is the one
    // of a sorted, deduplicated search.
    std::sort(found.begin(), found.end());
    const std::size_t added = found.size();
    cand_.insert(cand_.end(), found.begin(), found.end());
    for (auto v : verts) old_gbox_[std::size_t(v)] = gbox_[std::size_t(v)];
    for (auto f : tris) old_tbox_[std::size_t(f)] = tbox_[std::size_t(f)];
    if (added) {
      d0_.resize(cand_.size(), std::numeric_limits<double>::quiet_NaN());
      d0_exact_.resize(cand_.size(), 0);
      key_.resize(cand_.size(), -1.0);
      stamp_.resize(cand_.size(), 0);
      // the vertex -> candidate index keeps covering the first inc_n_ candidates; the new ones
      // are scanned (test_changed) until it is rebuilt
    }
    // The new candidates each have a grown vertex, which is marked as moved: the next pass tests them.
    const double ms = ms_since(t0);
    stats_.broad.ms += ms;
    broad_acc_ += ms;
  }

  /// The envelope of vertex v for the current end position: its swept box, with the slack if it
  /// can move.
  Aabb<S> envelope(std::size_t v) const {
    Aabb<S> b;
    b.extend(sys_.X0.row(Eigen::Index(v)).transpose());
    b.extend(sys_.X1.row(Eigen::Index(v)).transpose());
    if (sys_.w[v] > 0) b.min.array() -= slack_, b.max.array() += slack_;
    return b;
  }

  Aabb<S> triangle_envelope(std::size_t f) const {
    const Faces& F = sys_.F;
    return merge(merge(gbox_[std::size_t(F(Eigen::Index(f), 0))], gbox_[std::size_t(F(Eigen::Index(f), 1))]), gbox_[std::size_t(F(Eigen::Index(f), 2))]);
  }

  void refit_tree() {
    impact::refit(sys_.tree.tree, [&](const std::int32_t* ids, std::size_t n) {
      Aabb<S> box;
      for (std::size_t k = 0; k < n; ++k) box.extend(tbox_[std::size_t(ids[k])]);
      return box;
    });
  }

  /// The candidate primitive pairs of the triangle pair (fa, fb) (not both obstacle): the
  /// vertices and edges each owns against the other's face and edges, kept when their grown
  /// envelopes overlap and they share no vertex.
  /// With only_new, only the pairs whose tests fail for the boxes before the current
  /// re-gathering (old_gbox_, old_tbox_), i.e. those not among the candidates yet (regather).
  void pairs_of(std::int32_t fa, std::int32_t fb, std::vector<Prim>& out, bool only_new = false) const {
    if (sys_.tri_obstacle[std::size_t(fa)] && sys_.tri_obstacle[std::size_t(fb)]) return;
    const Faces& F = sys_.F;
    auto incident = [&](std::int32_t v, std::int32_t f) { return F(f, 0) == v || F(f, 1) == v || F(f, 2) == v; };
    auto vf = [&](std::int32_t ta, std::int32_t tb) {  // owned vertices of ta against face tb
      const std::uint8_t o = own_[std::size_t(ta)];
      for (int k = 0; k < 3; ++k) {
        if (!(o & (1u << k))) continue;
        const std::int32_t v = F(ta, k);
        if (incident(v, tb) || !overlap(gbox_[std::size_t(v)], tbox_[std::size_t(tb)])) continue;  // both grown
        if (only_new && overlap(old_gbox_[std::size_t(v)], old_tbox_[std::size_t(tb)])) continue;
        Prim p;
        p.ee = 0;
        p.v[0] = v, p.v[1] = F(tb, 0), p.v[2] = F(tb, 1), p.v[3] = F(tb, 2);
        out.push_back(p);
      }
    };
    vf(fa, fb);
    vf(fb, fa);
    const std::uint8_t oa = own_[std::size_t(fa)], ob = own_[std::size_t(fb)];
    if (!(oa & 0x38) || !(ob & 0x38)) return;
    for (int i = 0; i < 3; ++i) {
      if (!(oa & (8u << i))) continue;
      std::int32_t a0 = F(fa, i), a1 = F(fa, (i + 1) % 3);
      if (a0 > a1) std::swap(a0, a1);
      const Aabb<S> ea = merge(gbox_[std::size_t(a0)], gbox_[std::size_t(a1)]);
      if (!overlap(ea, tbox_[std::size_t(fb)])) continue;
      const bool was_a = only_new && overlap(merge(old_gbox_[std::size_t(a0)], old_gbox_[std::size_t(a1)]), old_tbox_[std::size_t(fb)]);
      for (int j = 0; j < 3; ++j) {
        if (!(ob & (8u << j))) continue;
        std::int32_t b0 = F(fb, j), b1 = F(fb, (j + 1) % 3);
        if (b0 > b1) std::swap(b0, b1);
        if (a0 == b0 || a0 == b1 || a1 == b0 || a1 == b1) continue;
        if (!overlap(ea, merge(gbox_[std::size_t(b0)], gbox_[std::size_t(b1)]))) continue;  // both grown
        if (was_a && overlap(merge(old_gbox_[std::size_t(a0)], old_gbox_[std::size_t(a1)]), merge(old_gbox_[std::size_t(b0)], old_gbox_[std::size_t(b1)])))
          continue;
        Prim p;
        p.ee = 1;
        const bool first = std::make_pair(a0, a1) < std::make_pair(b0, b1);
        p.v[0] = first ? a0 : b0, p.v[1] = first ? a1 : b1, p.v[2] = first ? b0 : a0, p.v[3] = first ? b1 : a1;
        out.push_back(p);
      }
    }
  }

  /// Whether some vertex moved since the last CCD pass left its envelope.
  bool escaped() const {
    for (std::size_t v = 0; v < changed_.size(); ++v)
      if (changed_[v] && !ebox_[v].contains(sys_.X1.row(Eigen::Index(v)).transpose())) return true;
    return false;
  }

  /// Lower bound on the distance of the pair's primitives at x0: the gap between their start
  /// boxes (in double).
  double start_box_distance(const Prim& p) const {
    Vec3<double> lo[2], hi[2];
    const int split = p.ee ? 2 : 1;
    for (int s = 0; s < 2; ++s) lo[s] = Vec3<double>::Constant(std::numeric_limits<double>::infinity()), hi[s] = -lo[s];
    for (int k = 0; k < 4; ++k) {
      const int s = k < split ? 0 : 1;
      const Vec3<double> x = p0(p.v[k]);
      lo[s] = lo[s].cwiseMin(x), hi[s] = hi[s].cwiseMax(x);
    }
    const Vec3<double> gap = (lo[1] - hi[0]).cwiseMax(lo[0] - hi[1]).cwiseMax(0.0);
    return gap.norm();
  }

  /// The largest relative displacement over the step between a point of one primitive and a point
  /// of the other: every point of a primitive moves by a convex combination of its vertices'
  /// displacements, so the difference of the two is at most the largest vertex-pair difference.
  double relative_motion(const Prim& p) const {
    const int split = p.ee ? 2 : 1;
    Vec3<double> d[4];
    for (int k = 0; k < 4; ++k) d[k] = p1(p.v[k]) - p0(p.v[k]);
    double m = 0;
    for (int i = 0; i < split; ++i)
      for (int j = split; j < 4; ++j) m = std::max(m, (d[i] - d[j]).norm());
    return m;
  }

  /// A lower bound on the pair's distance over the whole step, returned when it exceeds
  /// need = h + bound_margin_ (the pair provably stays farther apart than h, so its CCD can be
  /// skipped); -infinity when no bound proves that. With m the pair's relative motion
  /// (relative_motion: for fixed barycentric weights the points' offset changes by t times a
  /// convex combination of vertex-pair displacement differences, at most m long), the distance at
  /// time t is at least d(0) - t m and at least d(1) - (1 - t) m, so at least their mean
  /// (d(0) + d(1) - m) / 2 over the whole step. First the start bound alone (d(0) - m, the start
  /// distance cached per candidate: a box bound, then the exact one), then both ends. A margin
  /// covers rounding. Thread-safe per index.
  double separation_bound(std::size_t i) {
    const Prim& p = cand_[i];
    const double m = relative_motion(p), need = h_ + bound_margin_, none = -std::numeric_limits<double>::infinity();
    if (std::isnan(d0_[i])) d0_[i] = start_box_distance(p);
    if (d0_[i] > need + m) return d0_[i] - m;
    if (!d0_exact_[i]) {
      d0_[i] = closest(p, /*start=*/true).dist;
      d0_exact_[i] = 1;
      if (d0_[i] > need + m) return d0_[i] - m;
    }
    if (d0_[i] <= need) return none;  // nothing below can help: each bound is <= d(0)
    const Contact c1 = closest(p, /*start=*/false);
    const double both = 0.5 * (d0_[i] + c1.dist - m);
    if (both > need) return both;
    // Sliding pairs (a large relative motion along the contact, as in resting contact) fail the
    // bounds above; a separating direction fixed over the step proves them (hull_bound).
    return hull_bound(p, need);
  }

  /// Whether the convex hull of the pair's vertex offsets x_i - x_j (i of the first primitive,
  /// j of the second) at the start and at the end of the step stays farther than `need` from the
  /// origin. Every offset between a point of the first primitive and a point of the second at any
  /// time t is a convex combination of those (positions are linear in t, points are convex
  /// combinations of vertices), so the pair's distance stays above `need` over the whole step.
  /// The hull's distance from the origin is approached from both sides by Gilbert's algorithm
  /// (a point x of the hull: |x| bounds it from above; for n = x / |x|, min_k n . o_k from
  /// below): it stops with that lower bound (a lower bound on the pair's distance over the step)
  /// once it exceeds `need`, with -infinity once |x| does not (no fixed direction can separate by
  /// `need` then) or after a bounded number of steps. Rounding (|n| = 1 up to an ulp, the dot
  /// products) is covered by the margin in `need`.
  double hull_bound(const Prim& p, double need) const {
    const double none = -std::numeric_limits<double>::infinity();
    const int split = p.ee ? 2 : 1;
    Vec3<double> o[8];
    int k = 0;
    for (int i = 0; i < split; ++i)
      for (int j = split; j < 4; ++j) {
        o[k++] = p0(p.v[i]) - p0(p.v[j]);
        o[k++] = p1(p.v[i]) - p1(p.v[j]);
      }
    Vec3<double> x = o[0];
    for (int q = 1; q < k; ++q)
      if (o[q].squaredNorm() < x.squaredNorm()) x = o[q];
    for (int it = 0; it < 24; ++it) {
      const double len = x.norm();
      if (!(len > need)) return none;
      const Vec3<double> n = x / len;
      int best = 0;
      double lb = n.dot(o[0]);
      for (int q = 1; q < k; ++q) {
        const double d = n.dot(o[q]);
        if (d < lb) lb = d, best = q;
      }
      if (lb > need) return lb;
      // the hull's point nearest the origin on the segment from x to the offset found
      const Vec3<double> d = o[best] - x;
      const double dd = d.squaredNorm();
      if (!(dd > 0)) return none;
      x += std::clamp(-x.dot(d) / dd, 0.0, 1.0) * d;
    }
    return none;
  }

  /// What sample_pair found.
  enum class Sampled { hit, miss, unknown };

  /// Clear hits and clear misses without the CCD's search, in every stage. A hit only gives a
  /// constraint (the step's guarantee rests on the misses); a miss is proved. With m the pair's
  /// relative motion (relative_motion: the distance changes by at most (t' - t) m between times t
  /// and t'), the distance is sampled (exact closest points, in double) at n + 1 evenly spaced
  /// times, n = ceil(4 m / h) (so it changes by at most h / 4 between samples; pairs with
  /// m > 32 h are left to the search).
  /// Hit: at the first sample closer than h (a contact, up to the rounding margin), the time just
  /// before the distance falls to h + band_ / 2 is bisected between it and the sample before; the
  /// pair was farther than 3 h / 4 before it (the samples are h / 4 apart in distance), so it had
  /// not crossed, and the closest points there give the normal, as at the search's time of impact.
  /// Miss: between two samples at t < t' with distances d, d' the distance is at least
  /// max(d - (s - t) m, d' - (t' - s) m) >= (d + d' - (t' - t) m) / 2 at every time s; when that
  /// exceeds need = h + bound_margin_ on every interval (an interval that fails it is halved, up
  /// to three times, at a new sample), the smallest such bound (a lower bound on the distance over
  /// the step) is `bound`. The margin covers the rounding of the samples' positions and distances
  /// (computed in double from coordinates of magnitude <= scale_, as the other bounds').
  /// Unknown (the search decides): everything else, and pairs closer than h at the start.
  /// Thread-safe.
  Sampled sample_pair(const Prim& p, CcdResult<S>& r, double& bound) const {
    const double m = relative_motion(p);
    if (!(m <= 32 * h_)) return Sampled::unknown;
    const int n = std::max(2, static_cast<int>(std::ceil(4 * m / h_)));
    auto dist = [&](double t) {
      auto X = [&](int j) { return Vec3<double>((1 - t) * p0(p.v[j]) + t * p1(p.v[j])); };
      return closest_at(p, X).dist;
    };
    const double inside = h_ - bound_margin_, aim = h_ + 0.5 * band_, need = h_ + bound_margin_;
    double lb = std::numeric_limits<double>::infinity();
    // whether the distance stays above need on [a, b] (distances da, db there), halving up to depth times
    auto prove = [&](auto& self, double a, double b, double da, double db, int depth) -> bool {
      const double l = 0.5 * (da + db - (b - a) * m);
      if (l > need) {
        lb = std::min(lb, l);
        return true;
      }
      if (depth == 0) return false;
      const double mid = 0.5 * (a + b), dm = dist(mid);
      if (!(dm > need)) return false;
      return self(self, a, mid, da, dm, depth - 1) && self(self, mid, b, dm, db, depth - 1);
    };
    double prev = dist(0.0);
    if (prev < inside) return Sampled::unknown;  // closer than h at the start: the search decides
    bool proved = true;
    for (int k = 1; k <= n; ++k) {
      const double t = double(k) / n, d = dist(t);
      if (d < inside) {
        double lo = double(k - 1) / n, hi = t;
        if (prev > aim)
          for (int it = 0; it < 12; ++it) {
            const double mid = 0.5 * (lo + hi);
            (dist(mid) > aim ? lo : hi) = mid;
          }
        r = CcdResult<S>();
        r.hit = true;
        r.toi = static_cast<decltype(r.toi)>(lo);
        return Sampled::hit;
      }
      proved = proved && prove(prove, double(k - 1) / n, t, prev, d, 3);
      prev = d;
    }
    if (!proved) return Sampled::unknown;
    bound = lb;
    return Sampled::miss;
  }

  CcdResult<S> ccd(const Prim& p, bool static_start) {
    ++stats_.ccd_tests;
    return ccd_at(p, static_start, /*coarse=*/false);
  }
  /// The primitive CCD of a pair (thread-safe: reads only). The start check, the zones and the
  /// fail-safe use the options as given (coarse == false). The impulse passes only need a hit's time and
  /// contact to within a fraction of h: each pushes its hit to (1 + separation_margin) h, so a
  /// pair reported at h + band_ (band_ = separation_margin h / 2) is pushed as it should be, and a
  /// false positive closer than that costs one harmless impulse. There each query gets the
  /// tolerance that reports hits within h + band_ (tolerance = band_ / (2 L), L the query's
  /// extent, at most 1e-2 and never below the given one) and no re-check. The zones do not take
  /// it: a zone is detected again after each projection, and near misses within the band kept
  /// zones growing and merging until the rounds ran out (a 2,000-step twisting run then needed
  /// the fail-safe in 298 steps and ended one closer than h). Neither changes the CCD's
  /// guarantee: hit == false still proves the pair stays farther apart than h.
  CcdResult<S> ccd_at(const Prim& p, bool static_start, bool coarse) const {
    auto a = [&](int k) { return Vec3<S>(sys_.X0.row(p.v[k]).transpose()); };
    auto b = [&](int k) { return static_start ? Vec3<S>(sys_.X0.row(p.v[k]).transpose()) : Vec3<S>(sys_.X1.row(p.v[k]).transpose()); };
    CcdOptions o = ccd_;
    if (coarse && !static_start && band_ > 0) {
      Vec3<double> lo = p0(p.v[0]), hi = lo;
      for (int k = 0; k < 4; ++k) {
        lo = lo.cwiseMin(p0(p.v[k])).cwiseMin(p1(p.v[k]));
        hi = hi.cwiseMax(p0(p.v[k])).cwiseMax(p1(p.v[k]));
      }
      const double L = (hi - lo).maxCoeff();
      o.tolerance = std::max(o.tolerance, L > 0 ? std::min(band_ / (2 * L), 1e-2) : 1e-2);
      o.recheck_iterations = 0;
    }
    if (p.ee) return edge_edge_ccd(a(0), a(1), a(2), a(3), b(0), b(1), b(2), b(3), o);
    return vertex_face_ccd(a(0), a(1), a(2), a(3), b(0), b(1), b(2), b(3), o);
  }

  /// CCD over the pairs that may have changed: gathers again only when a moved vertex left its
  /// envelope, then tests the candidates with a vertex moved since the last pass and the previous
  /// hits.
  std::vector<Hit> detect() {
    note_moves();
    if (escaped()) regather();
    return test_changed();
  }

  /// The vertex -> candidate index (CSR) over the first inc_n_ candidates, built when a pass
  /// needs it: once per gathering, and again after re-gatherings only once the candidates they
  /// appended (scanned by test_changed meanwhile) exceed a quarter of those it covers.
  void build_incidence() {
    const std::size_t nv = sys_.w.size();
    inc_off_.assign(nv + 1, 0);
    for (const auto& p : cand_)
      for (int k = 0; k < 4; ++k) ++inc_off_[std::size_t(p.v[k]) + 1];
    for (std::size_t v = 0; v < nv; ++v) inc_off_[v + 1] += inc_off_[v];
    inc_.resize(inc_off_[nv]);
    inc_fill_.assign(inc_off_.begin(), inc_off_.end() - 1);
    for (std::size_t c = 0; c < cand_.size(); ++c)
      for (int k = 0; k < 4; ++k) inc_[inc_fill_[std::size_t(cand_[c].v[k])]++] = static_cast<std::uint32_t>(c);
    inc_n_ = cand_.size();
  }

  /// Notes the end positions' moves since the last call: a vertex whose end position changed
  /// counts as moved (changed_) and its path length grows by the distance moved. Every write to
  /// the end positions is seen here, whichever stage made it.
  void note_moves() {
    ++moves_noted_;
    const std::size_t nv = sys_.w.size();
    for (std::size_t v = 0; v < nv; ++v) {
      const Eigen::Index r = Eigen::Index(v);
      if (sys_.X1.row(r) == x1_seen_.row(r)) continue;
      path_[v] += (sys_.X1.row(r).template cast<double>() - x1_seen_.row(r).template cast<double>()).norm();
      x1_seen_.row(r) = sys_.X1.row(r);
      changed_[v] = 1;
    }
  }

  /// The sum of the path lengths of the pair's vertices (note_moves).
  double path_sum(const Prim& p) const {
    return path_[std::size_t(p.v[0])] + path_[std::size_t(p.v[1])] + path_[std::size_t(p.v[2])] + path_[std::size_t(p.v[3])];
  }

  /// The key of a candidate just proved farther than need = h + bound_margin_ over the step by a
  /// lower bound L on its distance (separation_bound): while the end positions of its vertices
  /// move by e_k in all since, a point of either primitive moves by at most t times a convex
  /// combination of the e_k at time t, so the pair's distance stays above L - sum e_k over the
  /// whole step, and the proof holds while sum e_k <= L - need. Each e_k is at most the growth of
  /// the vertex's path length (triangle inequality over the noted moves), so the proof holds while
  /// the sum of the four path lengths stays at most the key: that sum now plus L - need. The
  /// factors 1 -/+ 1e-12 cover the rounding of the path lengths (a sum of at most moves_cap_
  /// norms each, relative error under 1e-12; kept() stops keeping proofs beyond that).
  double key_of(const Prim& p, double bound) const { return path_sum(p) * (1 - 1e-12) + (bound - (h_ + bound_margin_)); }
  /// Whether candidate c's last proof still holds (key_of).
  bool kept(std::size_t c) const { return moves_noted_ <= moves_cap_ && path_sum(cand_[c]) * (1 + 1e-12) <= key_[c]; }

  std::vector<Hit> test_changed() {
    note_moves();
    // The candidates to test, in increasing index order: those with a moved vertex (by a scan
    // when many vertices moved, through the incidence index otherwise) and the last hits, less
    // those whose proof from an earlier pass still holds (kept).
    std::vector<std::uint32_t>& todo = todo_;
    todo.clear();
    std::size_t moved = 0;
    for (auto c : changed_) moved += c;
    if (++stamp_now_ == 0) std::fill(stamp_.begin(), stamp_.end(), 0), stamp_now_ = 1;
    if (moved * 8 >= changed_.size()) {
      for (std::size_t c = 0; c < cand_.size(); ++c) {
        const Prim& p = cand_[c];
        if (changed_[std::size_t(p.v[0])] || changed_[std::size_t(p.v[1])] || changed_[std::size_t(p.v[2])] || changed_[std::size_t(p.v[3])])
          todo.push_back(static_cast<std::uint32_t>(c)), stamp_[c] = stamp_now_;
      }
    } else if (moved > 0) {
      if (inc_off_.empty() || 4 * (cand_.size() - inc_n_) > inc_n_) build_incidence();
      for (std::size_t v = 0; v < changed_.size(); ++v) {
        if (!changed_[v]) continue;
        for (std::uint32_t k = inc_off_[v]; k < inc_off_[v + 1]; ++k)
          if (stamp_[inc_[k]] != stamp_now_) stamp_[inc_[k]] = stamp_now_, todo.push_back(inc_[k]);
      }
      for (std::size_t c = inc_n_; c < cand_.size(); ++c) {
        const Prim& p = cand_[c];
        if (stamp_[c] != stamp_now_ &&
            (changed_[std::size_t(p.v[0])] || changed_[std::size_t(p.v[1])] || changed_[std::size_t(p.v[2])] || changed_[std::size_t(p.v[3])]))
          todo.push_back(static_cast<std::uint32_t>(c)), stamp_[c] = stamp_now_;
      }
    }
    for (const auto& h : last_hits_)
      if (stamp_[h.c] != stamp_now_) stamp_[h.c] = stamp_now_, todo.push_back(h.c);
    // Increasing order: by a scan of the stamps when many are marked (cheaper than sorting them).
    if (todo.size() * 16 >= cand_.size()) {
      todo.clear();
      for (std::size_t c = 0; c < cand_.size(); ++c)
        if (stamp_[c] == stamp_now_) todo.push_back(static_cast<std::uint32_t>(c));
    } else {
      std::sort(todo.begin(), todo.end());
    }
    const std::size_t listed = todo.size();
    todo.erase(std::remove_if(todo.begin(), todo.end(), [&](std::uint32_t c) { return kept(c); }), todo.end());
    stats_.ccd_kept += listed - todo.size();
    // Results only for the pairs that ran a test (ran[i]); the buffer is kept between passes.
    if (res_.size() < todo.size()) res_.resize(todo.size());
    CcdResult<S>* res = res_.data();
    std::vector<std::uint8_t> ran(todo.size(), 0);
    parallel_for(todo.size(), opt_.threads, [&](std::size_t i) {
      const std::size_t c = todo[i];
      if (is_excluded(cand_[c])) return;
      const double bound = separation_bound(c);
      if (bound > -std::numeric_limits<double>::infinity()) {
        key_[c] = key_of(cand_[c], bound);
        return;
      }
      key_[c] = -1;
      // Clear hits and misses need no search (sample_pair); every other pair gets the CCD (coarse
      // in the impulse passes, as given in the zones and the fail-safe).
      double sampled_bound = 0;
      const Sampled sp = sample_pair(cand_[c], res[i], sampled_bound);
      if (sp == Sampled::miss) {
        key_[c] = key_of(cand_[c], sampled_bound);
        return;
      }
      if (sp == Sampled::unknown) res[i] = ccd_at(cand_[c], false, /*coarse=*/!precise_);
      ran[i] = 1;
    });
    std::size_t tested = 0;
    for (auto r : ran) tested += r;
    stats_.ccd_tests += tested;
    stats_.ccd_skipped += todo.size() - tested;
    std::vector<Hit> hits;
    for (std::size_t i = 0; i < todo.size(); ++i)
      if (ran[i] && res[i].hit) hits.push_back({cand_[todo[i]], res[i], todo[i]});
    std::fill(changed_.begin(), changed_.end(), 0);
    std::stable_sort(hits.begin(), hits.end(), [](const Hit& x, const Hit& y) { return x.r.toi < y.r.toi; });
    last_hits_ = hits;
    return hits;
  }

  /// Closest points of a pair at x0 (start) or x1, in double: distance, weights, unit normal.
  Contact closest(const Prim& p, bool start) const {
    return closest_at(p, [&](int k) { return start ? p0(p.v[k]) : p1(p.v[k]); });
  }

  template <class Pos>
  static Contact closest_at(const Prim& p, Pos&& X) {
    Contact c;
    if (p.ee) {
      const auto r = closest_points_segment_segment(Segment<double>(X(0), X(1)), Segment<double>(X(2), X(3)));
      c.a[0] = 1 - r.s, c.a[1] = r.s, c.a[2] = -(1 - r.t), c.a[3] = -r.t;
    } else {
      const auto r = closest_point_on_triangle(X(0), Triangle<double>(X(1), X(2), X(3)));
      c.a[0] = 1, c.a[1] = -r.barycentric[0], c.a[2] = -r.barycentric[1], c.a[3] = -r.barycentric[2];
    }
    Vec3<double> d = Vec3<double>::Zero();
    for (int k = 0; k < 4; ++k) d += c.a[k] * X(k);
    c.dist = d.norm();
    if (c.dist > 0) c.n = d / c.dist;
    return c;
  }

  ZoneConstraint constraint_of(const Prim& p, const double* a, const Vec3<double>& n, double b) const {
    ZoneConstraint k;
    k.count = 4;
    for (int j = 0; j < 4; ++j) k.v[j] = p.v[j], k.a[j] = a[j];
    k.n = n;
    k.b = b;
    return k;
  }

  /// The constraint of a CCD hit: the closest points of the pair at toi give the weights and the
  /// normal (their difference, about h long there); when they are too close to give a direction
  /// (a hit reported on an exhausted budget), the primitives' normal oriented by the start.
  ZoneConstraint constraint_at_hit(const Hit& hit) const {
    const Prim& p = hit.p;
    const double t = static_cast<double>(hit.r.toi);
    auto X = [&](int k) { return Vec3<double>((1 - t) * p0(p.v[k]) + t * p1(p.v[k])); };
    Contact c = closest_at(p, X);
    if (c.dist > 0.25 * h_) return constraint_of(p, c.a, c.n, target_);
    Vec3<double> d0 = Vec3<double>::Zero();
    for (int k = 0; k < 4; ++k) d0 += c.a[k] * p0(p.v[k]);
    Vec3<double> n = p.ee ? Vec3<double>((X(1) - X(0)).cross(X(3) - X(2))) : Vec3<double>((X(2) - X(1)).cross(X(3) - X(1)));
    if (n.norm() > 0) {
      n.normalize();
      if (n.dot(d0) < 0) n = -n;
    } else {
      n = d0.norm() > 0 ? Vec3<double>(d0.normalized()) : Vec3<double>(0, 0, 1);
    }
    return constraint_of(p, c.a, n, target_);
  }

  /// Relaxes the contact set contacts_ (relax_contacts: one-sided Gauss-Seidel) with the
  /// proximity tolerance.
  RelaxStats relax(int rounds, std::vector<std::uint8_t>* acted) {
    return relax_contacts(
        contacts_, sys_.w, static_cast<double>(opt_.proximity_tolerance) * h_, rounds, [&](const ZoneConstraint& k) { return gap(k); },
        [&](const ZoneConstraint& k, double dl, double dn) { return push(k, dl, dn); }, acted);
  }

  double gap(const ZoneConstraint& k) const {
    double g = 0;
    for (int j = 0; j < k.count; ++j) g += k.a[j] * k.n.dot(p1(k.v[j]));
    return g;
  }

  /// One inelastic impulse with Coulomb friction on end positions: after it the constraint's gap
  /// reaches k.b (if some vertex is movable), and the tangential relative displacement over the
  /// step shrinks by at most friction times the normal change. Returns whether it acted.
  bool apply_impulse(const ZoneConstraint& k) {
    const double g = gap(k);
    if (g >= k.b) return false;
    double denom = 0;
    for (int j = 0; j < k.count; ++j) denom += k.a[j] * k.a[j] * sys_.w[static_cast<std::size_t>(k.v[j])];
    if (!(denom > 0)) return false;
    const double dn = k.b - g;
    return push(k, dn / denom, dn);
  }

  /// Moves the constraint's movable vertices by w_j a_j dl n, which changes its gap by dn = dl
  /// sum_j a_j^2 w_j, and, when dn > 0, applies Coulomb friction: the tangential relative
  /// displacement over the step shrinks by at most friction times dn. The caller has checked
  /// that some vertex is movable (sum_j a_j^2 w_j > 0).
  bool push(const ZoneConstraint& k, double dl, double dn) {
    double denom = 0;
    for (int j = 0; j < k.count; ++j) denom += k.a[j] * k.a[j] * sys_.w[static_cast<std::size_t>(k.v[j])];
    Vec3<double> rel = Vec3<double>::Zero();
    for (int j = 0; j < k.count; ++j) rel += k.a[j] * (p1(k.v[j]) - p0(k.v[j]));
    Vec3<double> tang = rel - k.n.dot(rel) * k.n;
    const double tl = tang.norm();
    const double mu = static_cast<double>(opt_.friction);
    Vec3<double> push = dl * k.n;
    if (dn > 0 && tl > 0 && mu > 0) push -= (std::min(tl, mu * dn) / denom) * (tang / tl);
    for (int j = 0; j < k.count; ++j) {
      const double w = sys_.w[static_cast<std::size_t>(k.v[j])];
      if (!(w > 0)) continue;
      const Vec3<double> x = p1(k.v[j]) + (w * k.a[j]) * push;
      sys_.X1.row(k.v[j]) = x.cast<S>().transpose();
      changed_[static_cast<std::size_t>(k.v[j])] = 1;
    }
    return true;
  }

  template <class Find>
  void resolve_zone(const std::vector<ZoneConstraint>& all, const std::vector<std::size_t>& idx, std::int32_t root, const Vertices<S>& xhat,
                    const std::vector<std::int32_t>& parent, Find& find) {
    (void)parent;
    std::vector<ZoneConstraint> cons;
    cons.reserve(idx.size());
    bool immovable = false;
    for (auto c : idx) {
      cons.push_back(all[c]);
      for (int j = 0; j < all[c].count; ++j) immovable = immovable || !(sys_.w[static_cast<std::size_t>(all[c].v[j])] > 0);
    }
    // The zone's movable vertices: those of its constraints (only they are ever joined).
    std::vector<std::int32_t> verts;
    for (const auto& k : cons)
      for (int j = 0; j < k.count; ++j)
        if (sys_.w[static_cast<std::size_t>(k.v[j])] > 0) verts.push_back(k.v[j]);
    std::sort(verts.begin(), verts.end());
    verts.erase(std::unique(verts.begin(), verts.end()), verts.end());
    (void)root;
    (void)find;
    ++stats_.zone_count;
    stats_.largest_zone = std::max(stats_.largest_zone, verts.size());
    // The zone as a whole (every constraint it gathered so far) is solved from xhat, the
    // positions before this round.
    bool done = false;
    if (opt_.zone_method == ZoneMethod::Rigid && immovable) {
      // A rigid zone held by infinite-mass vertices that stay still is at rest with them (Provot,
      // Bridson: the zone's mass is infinite); held by moving ones it is projected like Harmon's.
      bool still = true;
      for (const auto& k : cons)
        for (int j = 0; j < k.count; ++j)
          if (!(sys_.w[static_cast<std::size_t>(k.v[j])] > 0)) still = still && sys_.X1.row(k.v[j]) == sys_.X0.row(k.v[j]);
      if (still) {
        for (auto v : verts) sys_.X1.row(v) = sys_.X0.row(v);
        ++stats_.rigid_zones;
        done = true;
      }
    }
    if (!done && (opt_.zone_method == ZoneMethod::Harmon || immovable)) {
      ZoneProjectionOptions po;
      po.max_iterations = opt_.max_projection_iterations;
      po.tolerance = static_cast<double>(opt_.projection_tolerance) * h_;
      // Reads every position from xhat (movable vertices outside this zone are not in its
      // constraints; immovable ones never change), writes only this zone's vertices.
      const auto r = project_zone(cons, sys_.w, xhat, sys_.X1, po);
      done = r.converged;
    }
    if (!done && !immovable) {
      for (auto v : verts) sys_.X1.row(v) = xhat.row(v);
      rigid_zone_motion(verts, sys_.w, sys_.X0, sys_.X1);
      ++stats_.rigid_zones;
      done = true;
    }
    if (done && !immovable) zone_momentum(verts, xhat);
    if (done)
      for (auto v : verts) changed_[static_cast<std::size_t>(v)] = 1;
    // A zone that could not be resolved stays as it is: the fail-safe takes it.
  }

  /// The momentum error of a resolved zone of finite-mass vertices only (nothing outside it pushes
  /// it): the change of its linear momentum by the resolution, sum m (x1' - xhat), relative to
  /// sum m |xhat - x0|; and of its angular momentum about its centre of mass at x0, sum m
  /// (x0 - c) x (x1' - xhat), relative to sum m |x0 - c| |xhat - x0|. Kept as the step's largest.
  void zone_momentum(const std::vector<std::int32_t>& verts, const Vertices<S>& xhat) {
    double mass = 0;
    Vec3<double> c = Vec3<double>::Zero();
    for (auto v : verts) {
      const double m = 1 / sys_.w[std::size_t(v)];
      mass += m;
      c += m * p0(v);
    }
    c /= mass;
    Vec3<double> dp = Vec3<double>::Zero(), dl = Vec3<double>::Zero();
    double ps = 0, ls = 0;
    for (auto v : verts) {
      const double m = 1 / sys_.w[std::size_t(v)];
      const Vec3<double> before = xhat.row(v).transpose().template cast<double>(), change = p1(v) - before, r = p0(v) - c;
      dp += m * change;
      dl += m * r.cross(change);
      ps += m * (before - p0(v)).norm();
      ls += m * r.norm() * (before - p0(v)).norm();
    }
    if (ps > 0) stats_.zone_momentum_error = std::max(stats_.zone_momentum_error, dp.norm() / ps);
    if (ls > 0) stats_.zone_angular_momentum_error = std::max(stats_.zone_angular_momentum_error, dl.norm() / ls);
  }

  System<S>& sys_;
  const ClothCollisionOptions<S>& opt_;
  ClothStepStats& stats_;
  double h_ = 0, prox_ = 0, target_ = 0, scale_ = 0;
  CcdOptions ccd_;
  double band_ = 0;      // the impulses' and zones' CCD locates hits within h + band_ (ccd_at)
  bool precise_ = true;  // the CCD with the options as given (start check, zones, fail-safe)
  double bound_margin_ = 0;
  S slack_ = S(0);
  S near_inflate_ = S(0), ccd_inflate_ = S(0);  // half the proximity distance, h / 2 (rounded up)
  double broad_acc_ = 0;
  std::vector<Prim> cand_, excluded_;
  std::vector<std::uint8_t> own_;
  std::vector<std::uint32_t> vtri_off_;  // vertex -> incident triangles (CSR)
  std::vector<std::int32_t> vtri_;
  Faces own_faces_;
  std::vector<Aabb<S>> ebox_, gbox_, tbox_;  // per vertex: envelope, grown envelope; per triangle
  std::vector<Aabb<S>> old_gbox_, old_tbox_;  // gbox_, tbox_ before the current re-gathering
  std::vector<double> d0_;                   // per candidate: a lower bound on its distance at x0
  std::vector<std::uint8_t> d0_exact_;       // ... which is the exact distance (in double)
  std::vector<std::uint32_t> stamp_, inc_off_, inc_, inc_fill_;
  std::size_t inc_n_ = 0;  // candidates covered by the vertex -> candidate index
  std::uint32_t stamp_now_ = 0;
  std::vector<Near> near_;
  // The contact set: the proximity pairs' constraints (stage 1), then the CCD impulses' hits.
  std::vector<ZoneConstraint> contacts_;
  std::vector<Hit> last_hits_;
  std::vector<CcdResult<S>> res_;  // test_changed's buffers, kept between passes
  std::vector<std::uint32_t> todo_;
  std::vector<std::uint8_t> changed_;
  // Proofs kept across the passes of a step (note_moves, kept): per vertex, the path length of its
  // end position over the step's passes and the end positions at the last pass; per candidate,
  // the key below which the sum of its vertices' path lengths keeps its last proof valid (< 0:
  // none).
  std::vector<double> path_;
  Vertices<S> x1_seen_;
  std::vector<double> key_;
  int moves_noted_ = 0;
  static constexpr int moves_cap_ = 1000;
};

}  // namespace impact::detail::cloth
