// SPDX-License-Identifier: MIT
/// \file
/// Stepper's contact impulses: the constraint of a proximity pair or a CCD hit, the relaxation of
/// the contact set (relax_contacts) with its warm start from the last step, and the inelastic
/// impulse with Coulomb friction that each contact applies to the end positions.
/// Part of cloth_collision_step's internals (stepper.hpp); not part of the interface.
#pragma once

#include "impact/cloth/detail/stepper.hpp"

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace impact::detail::cloth {

template <class S>
ZoneConstraint Stepper<S>::constraint_of(const Prim& p, const double* a, const Vec3<double>& n, double b) const {
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
template <class S>
ZoneConstraint Stepper<S>::constraint_at_hit(const Hit& hit) const {
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
template <class S>
RelaxStats Stepper<S>::relax(int rounds, std::vector<std::uint8_t>* acted) {
  return relax_contacts(
      contacts_, sys_.w, static_cast<double>(opt_.proximity_tolerance) * h_, rounds, [&](const ZoneConstraint& k) { return gap(k); },
      [&](const ZoneConstraint& k, double dl, double dn) { return push(k, dl, dn); }, acted);
}

template <class S>
double Stepper<S>::gap(const ZoneConstraint& k) const {
  double g = 0;
  for (int j = 0; j < k.count; ++j) g += k.a[j] * k.n.dot(p1(k.v[j]));
  return g;
}

/// One inelastic impulse with Coulomb friction on end positions: after it the constraint's gap
/// reaches k.b (if some vertex is movable), and the tangential relative displacement over the
/// step shrinks by at most friction times the normal change. Returns whether it acted.
template <class S>
bool Stepper<S>::apply_impulse(const ZoneConstraint& k) {
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
template <class S>
bool Stepper<S>::push(const ZoneConstraint& k, double dl, double dn) {
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

}  // namespace impact::detail::cloth
