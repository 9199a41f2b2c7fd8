// SPDX-License-Identifier: MIT
/// \file
/// Stepper: the stages of one cloth_collision_step over the combined system (step_system.hpp).
/// The class is declared here with its state; its members are defined by concern in
/// step_assembly.hpp (the combined system, the start check), step_gathering.hpp (the broad phase
/// over the step), step_bounds.hpp (proofs that skip a CCD search), step_passes.hpp (the CCD
/// passes), step_contacts.hpp (impulses and their relaxation), step_stages.hpp (proximity, CCD
/// impulses, fail-safe) and step_zones.hpp (impact zones), which collision_step.hpp includes.
/// Not part of the interface.
#pragma once

#include "impact/bvh/traverse.hpp"
#include "impact/ccd/mesh_ccd.hpp"
#include "impact/cloth/detail/hull_proofs.hpp"
#include "impact/cloth/detail/kept_proofs.hpp"
#include "impact/cloth/detail/relax_contacts.hpp"
#include "impact/cloth/detail/start_intersections.hpp"
#include "impact/cloth/detail/step_system.hpp"
#include "impact/cloth/step_options.hpp"
#include "impact/cloth/zone_projection.hpp"
#include "impact/core/error.hpp"
#include "impact/core/parallel.hpp"
#include "impact/narrow/closest_point.hpp"

#include <algorithm>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

namespace impact::detail::cloth {

template <class T>
class Appender;  // step_gathering.hpp

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

  // The stages, in the order cloth_collision_step calls them.
  // step_assembly.hpp: the combined system; the start's candidates, proximity pairs and violations
  void assemble(const Faces& F, const Eigen::Matrix<S, Eigen::Dynamic, 1>& wm, const Vertices<S>& x0, const Vertices<S>& x1,
                const ClothObstacles<S>& obs);
  void check_start();
  // step_stages.hpp: stage 1 (proximity), stage 2 (CCD impulses), stage 4 (fail-safe)
  void proximity_stage();
  void impulse_stage();
  void failsafe_stage();
  // step_zones.hpp: stage 3 (impact zones)
  void zone_stage();

  void write_back(Vertices<S>& x1) const { x1 = sys_.X1.topRows(sys_.n_cloth); }
  // step_gathering.hpp: keeps the end state for the next step's start check when it is known
  // free of intersections
  void note_end();

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

  // step_gathering.hpp: the broad phase over the step
  void build_ownership();
  static S half_up(double d);
  static Aabb<S> grow(Aabb<S> b, S g);
  Aabb<S> grown_envelope(std::size_t v, const Aabb<S>& e) const;
  void gather();
  void regather();
  Aabb<S> envelope(std::size_t v) const;
  Aabb<S> triangle_envelope(std::size_t f) const;
  void refit_tree();
  void refit_grown(const std::vector<std::int32_t>& tris);
  template <class Visit>
  void self_pairs(Visit&& visit);
  template <class Visit>
  void grown_pairs(const std::vector<std::int32_t>& tris, Visit&& visit);
  template <bool OnlyNew = false>
  void pairs_of(std::int32_t fa, std::int32_t fb, Appender<Prim>& out) const;
  void start_planes();
  void check_pierce(std::int32_t fa, std::int32_t fb);
  bool escaped() const;
  void build_incidence();

  // step_bounds.hpp: proofs that a candidate stays farther than h, closest points
  /// What sample_pair found.
  enum class Sampled { hit, miss, unknown };
  double start_box_distance(const Prim& p) const;
  double relative_motion(const Prim& p) const;
  /// What separation_bound computed on the way, for sample_pair: the pair's relative motion and
  /// its exact distances at the start and at the end of the step (NaN where not computed).
  /// The directions of the closest points (second primitive to first) at t = 0 (where computed:
  /// has_n0) and t = 1 (where d1 is), for split_bound.
  struct Measured {
    double m = 0;
    double d0 = std::numeric_limits<double>::quiet_NaN();
    double d1 = std::numeric_limits<double>::quiet_NaN();
    Vec3<double> n0 = Vec3<double>::UnitZ(), n1 = Vec3<double>::UnitZ();
    bool has_n0 = false;
  };
  double separation_bound(std::size_t i, Measured& known);
  double split_bound(const Prim& p, const Measured& known) const;
  /// sample_pair's most intervals along the step (each h / 4 of relative motion): pairs moving
  /// relative to each other by more than max_samples_ / 4 h go to the search.
  static constexpr int max_samples_ = 128;
  Sampled sample_pair(const Prim& p, const Measured& known, CcdResult<S>& r, double& bound) const;
  Contact closest(const Prim& p, bool start) const;
  template <class Pos>
  static Contact closest_at(const Prim& p, Pos&& X);
  void note_moves();
  double path_sum(const Prim& p) const;
  /// The key of a candidate just proved farther than need = h + bound_margin_ over the step by a
  /// lower bound `bound` on its distance (separation_bound, sample_pair): kept_proofs.hpp.
  double key_of(const Prim& p, double bound) const { return proof_key(path_sum(p), bound - (h_ + bound_margin_)); }
  /// Whether candidate c's last proof still holds (kept_proofs.hpp; the path lengths' rounding
  /// bound assumes at most moves_cap_ noted moves, beyond which no proof is kept).
  /// (A candidate without a proof, key < 0, is not kept whatever its path lengths: tested first.)
  bool kept(std::size_t c) const { return key_[c] >= 0 && moves_noted_ <= moves_cap_ && proof_holds(path_sum(cand_[c]), key_[c]); }

  // step_passes.hpp: the CCD passes
  CcdResult<S> ccd(const Prim& p, bool static_start);
  CcdResult<S> ccd_at(const Prim& p, bool static_start, bool coarse) const;
  std::vector<Hit> detect();
  std::vector<Hit> test_changed();

  // step_contacts.hpp: constraints, impulses and their relaxation
  ZoneConstraint constraint_of(const Prim& p, const double* a, const Vec3<double>& n, double b) const;
  ZoneConstraint constraint_at_hit(const Hit& hit) const;
  RelaxStats relax(int rounds, std::vector<std::uint8_t>* acted);
  double gap(const ZoneConstraint& k) const;
  bool apply_impulse(const ZoneConstraint& k);
  bool push(const ZoneConstraint& k, double dl, double dn);

  // step_zones.hpp: a zone's resolution
  template <class Find>
  void resolve_zone(const std::vector<ZoneConstraint>& all, const std::vector<std::size_t>& idx, std::int32_t root, const Vertices<S>& xhat,
                    const std::vector<std::int32_t>& parent, Find& find);
  void zone_momentum(const std::vector<std::int32_t>& verts, const Vertices<S>& xhat);

  System<S>& sys_;
  const ClothCollisionOptions<S>& opt_;
  ClothStepStats& stats_;
  double h_ = 0, prox_ = 0, target_ = 0, scale_ = 0;
  CcdOptions ccd_;
  double band_ = 0;      // the impulses' and zones' CCD locates hits within h + band_ (ccd_at)
  bool precise_ = true;  // the CCD with the options as given (start check, zones, fail-safe)
  double bound_margin_ = 0;
  int split_depth_ = 5;  // split_bound's pieces: down to 2^-5 of the step
  S slack_ = S(0);
  S near_inflate_ = S(0), ccd_inflate_ = S(0);  // half the proximity distance, h / 2 (rounded up)
  double broad_acc_ = 0;
  // The large per-step arrays live in the workspace (StepBuffers), set up again in every step.
  StepBuffers<S>& buf_ = sys_.buf;
  std::vector<Prim>& cand_ = buf_.cand;
  std::vector<Prim> excluded_;
  std::vector<Aabb<S>>& ebox_ = buf_.ebox;  // per vertex: envelope, grown envelope; per triangle
  std::vector<Aabb<S>>& gbox_ = buf_.gbox;
  std::vector<Aabb<S>>& tbox_ = buf_.tbox;
  std::vector<Aabb<S>>& old_gbox_ = buf_.old_gbox;  // gbox_, tbox_ before the current re-gathering
  std::vector<Aabb<S>>& old_tbox_ = buf_.old_tbox;
  std::vector<std::uint8_t> grown_tri_;       // regather's triangles with a grown vertex (all 0 between calls)
  std::vector<std::uint8_t> grown_vert_;      // regather's grown vertices (all 0 between calls)
  std::vector<std::uint8_t> grown_node_;      // grown_pairs: tree nodes above such a triangle (all 0 between calls)
  std::vector<std::pair<std::int32_t, std::int32_t>>& pair_stack_ = buf_.pair_stack;  // the walks' stack
  std::vector<double>& d0_ = buf_.d0;              // per candidate: a lower bound on its distance at x0
  std::vector<std::uint8_t>& d0_exact_ = buf_.d0_exact;  // ... which is the exact distance (in double)
  std::vector<std::uint32_t>& stamp_ = buf_.stamp;
  std::vector<std::uint32_t>& inc_off_ = buf_.inc_off;
  std::vector<std::uint32_t>& inc_ = buf_.inc;
  std::vector<std::uint32_t>& inc_fill_ = buf_.inc_fill;
  std::size_t inc_n_ = 0;  // candidates covered by the vertex -> candidate index
  std::uint32_t stamp_now_ = 0;
  std::vector<Near> near_;
  // The start's intersecting triangle pairs that the filter of check_pierce let through (sorted
  // by check_start).
  std::vector<std::pair<std::int32_t, std::int32_t>> pierced_;
  std::vector<PiercePlane>& plane0_ = buf_.plane0;  // per triangle, at x0 (start_planes)
  // The contact set: the proximity pairs' constraints (stage 1), then the CCD impulses' hits.
  std::vector<ZoneConstraint> contacts_;
  std::vector<Hit> last_hits_;
  // test_changed's buffers: the candidates to test, each one's outcome, those that ran a test
  // and their results
  std::vector<std::uint32_t>& todo_ = buf_.todo;
  std::vector<std::uint8_t>& status_ = buf_.status;
  std::vector<std::uint32_t>& run_ = buf_.run;
  std::vector<double>& toi_ = buf_.toi;
  std::vector<CcdResult<S>>& res_ = buf_.res;
  std::vector<std::uint8_t>& changed_ = buf_.changed;
  // Proofs kept across the passes of a step (note_moves, kept): per vertex, the path length of its
  // end position over the step's passes and the end positions at the last pass; per candidate,
  // the key below which the sum of its vertices' path lengths keeps its last proof valid (< 0:
  // none).
  std::vector<double>& path_ = buf_.path;
  Vertices<S>& x1_seen_ = buf_.x1_seen;
  std::vector<double>& key_ = buf_.key;
  int moves_noted_ = 0;
  static constexpr int moves_cap_ = 1000;
};

}  // namespace impact::detail::cloth

