// SPDX-License-Identifier: MIT
/// \file
/// validate_step: the checks of cloth_collision_step's input (sizes, indices, finite coordinates
/// and masses, obstacles, options), each failure an InvalidInput naming what is wrong, before
/// anything is modified. Not part of the interface.
#pragma once

#include "impact/cloth/step_options.hpp"
#include "impact/core/error.hpp"
#include "impact/core/types.hpp"
#include "impact/geometry/triangle_mesh.hpp"

#include <cmath>
#include <cstddef>
#include <string>

namespace impact::detail::cloth {

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

}  // namespace impact::detail::cloth
