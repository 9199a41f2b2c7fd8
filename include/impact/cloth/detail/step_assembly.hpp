// SPDX-License-Identifier: MIT
/// \file
/// Stepper's assembly of the combined system (cloth vertices, then every obstacle's at its
/// start and end pose, with infinite mass; the swept tree built or kept) and the start check (the
/// candidates' distances at x0: the proximity pairs, and InvalidInput or a report for pairs
/// already closer than h).
/// Part of cloth_collision_step's internals (stepper.hpp); not part of the interface.
#pragma once

#include "impact/cloth/detail/stepper.hpp"
#include "impact/cloth/detail/validate_step.hpp"

#include <algorithm>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <utility>
#include <vector>

namespace impact::detail::cloth {

template <class S>
void Stepper<S>::assemble(const Faces& F, const Eigen::Matrix<S, Eigen::Dynamic, 1>& wm, const Vertices<S>& x0, const Vertices<S>& x1,
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
  refill(changed_, static_cast<std::size_t>(nv), std::uint8_t(1));
  refill(path_, static_cast<std::size_t>(nv), 0.0);
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
    const auto& nodes = sys_.tree.tree.nodes;
    sys_.tree_parent.assign(nodes.size(), -1);
    sys_.tri_leaf.assign(static_cast<std::size_t>(sys_.F.rows()), -1);
    for (std::size_t k = 0; k < nodes.size(); ++k) {
      if (nodes[k].is_leaf()) {
        for (std::int32_t q = nodes[k].first; q < nodes[k].first + nodes[k].count; ++q)
          sys_.tri_leaf[static_cast<std::size_t>(sys_.tree.tree.primitives[static_cast<std::size_t>(q)])] = static_cast<std::int32_t>(k);
      } else {
        sys_.tree_parent[static_cast<std::size_t>(nodes[k].left())] = sys_.tree_parent[static_cast<std::size_t>(nodes[k].right())] =
            static_cast<std::int32_t>(k);
      }
    }
    sys_.tree_count.assign(nodes.size(), 0);
    for (std::size_t k = 0; k < nodes.size(); ++k)
      if (nodes[k].is_leaf())
        for (std::int32_t a = static_cast<std::int32_t>(k); a >= 0; a = sys_.tree_parent[static_cast<std::size_t>(a)])
          sys_.tree_count[static_cast<std::size_t>(a)] += nodes[k].count;
    sys_.front.clear();
  }
  stats_.broad.ms += ms_since(t0);
}

/// Gathers the candidates of the current motion, classifies the start and throws on violations:
/// triangle pairs that intersect at x0 (the gathering's exact test, check_pierce), then pairs
/// closer than h.
template <class S>
void Stepper<S>::check_start() {
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
  // The proximity pairs in a fixed order of their vertices (Prim's), not in the order the tree's
  // walk found them: the relaxation is Gauss-Seidel, so its path (and the step's result) follows
  // this order, which must not depend on the tree (its shape comes from the first step's motion).
  std::sort(near_.begin(), near_.end(), [](const Near& x, const Near& y) { return x.p < y.p; });
  std::sort(bad.begin(), bad.end());
  std::sort(pierced_.begin(), pierced_.end());
  if (!pierced_.empty()) {
    if (opt_.on_start_violation == StartViolation::Throw) {
      std::string msg = "cloth_collision_step: x0 intersects itself or an obstacle (" + std::to_string(pierced_.size()) +
                        " triangle pair(s) with an edge of one through the other, with no vertex-face or edge-edge pair within h / 2): ";
      for (std::size_t i = 0; i < std::min<std::size_t>(pierced_.size(), 8); ++i) {
        const auto& t = pierced_[i];
        auto tri = [&](std::int32_t f) {
          return "triangle " + std::to_string(f) + " (" + std::to_string(sys_.F(f, 0)) + "," + std::to_string(sys_.F(f, 1)) + "," +
                 std::to_string(sys_.F(f, 2)) + ")";
        };
        msg += (i ? ", " : "") + tri(t.first) + " and " + tri(t.second);
      }
      if (pierced_.size() > 8) msg += ", ...";
      throw InvalidInput(msg);
    }
    stats_.start_intersections = pierced_;
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

}  // namespace impact::detail::cloth
