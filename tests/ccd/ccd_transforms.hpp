// SPDX-License-Identifier: MIT
// Metamorphic transforms of CCD queries that keep the exact answer: time reversal, re-ordering of
// the triangle's vertices or of the edges, axis permutation, mirroring, scaling by powers of two
// and exact translation. Each is exact in double (checked where it could round), so the ground
// truth of the query files holds for the transformed query. Shared by tests/ccd and
// impact-ccd-bench (--transform NAME and its metamorphic section).
#pragma once

#include "support/ccd_queries.hpp"

#include <cmath>
#include <string>
#include <utility>
#include <vector>

namespace impact::test {

/// The names of the transforms, in the order the bench and the tests run them.
inline const std::vector<std::string>& ccd_transform_names() {
  static const std::vector<std::string> names = {
      "reverse-time", "rotate-face", "reflect-face", "swap-edges", "reverse-edge", "permute-axes",
      "mirror",       "scale-up",    "scale-down",   "translate"};
  return names;
}

/// Whether the transform applies to this kind of query ("vertex-face" or "edge-edge").
inline bool ccd_transform_applies(const std::string& name, const std::string& kind) {
  if (name == "rotate-face" || name == "reflect-face") return kind == "vertex-face";
  if (name == "swap-edges" || name == "reverse-edge") return kind == "edge-edge";
  return true;
}

/// The largest translation c = 3 * 2^j (j <= 20) of one axis under which the 8 coordinates x stay
/// exact doubles (x + c rounds to no other value, checked by an exact TwoSum), or 0 when none.
inline double exact_translation(const double (&x)[8]) {
  for (int j = 20; j >= -1000; --j) {
    const double c = 3.0 * std::ldexp(1.0, j);
    bool exact = true;
    for (double v : x) {
      const double s = v + c, bb = s - v, e = (v - (s - bb)) + (c - bb);
      exact = exact && e == 0.0 && std::isfinite(s);
    }
    if (exact) return c;
  }
  return 0.0;
}

/// Applies the named transform to a query (points 0-3 at t = 0, 4-7 at t = 1). Returns false when
/// the transform does not apply to the kind, or cannot be applied exactly (scaling that would
/// underflow or overflow, which the query files never need).
inline bool apply_ccd_transform(const std::string& name, const std::string& kind, CcdQueryRecord& q) {
  if (!ccd_transform_applies(name, kind)) return false;
  auto& p = q.points;
  if (name == "reverse-time") {
    for (int k = 0; k < 4; ++k) std::swap(p[k], p[k + 4]);
  } else if (name == "rotate-face") {  // (p, f0, f1, f2) -> (p, f1, f2, f0)
    for (int s : {0, 4}) {
      const auto f0 = p[s + 1];
      p[s + 1] = p[s + 2];
      p[s + 2] = p[s + 3];
      p[s + 3] = f0;
    }
  } else if (name == "reflect-face") {  // (p, f0, f1, f2) -> (p, f0, f2, f1): the normal flips
    for (int s : {0, 4}) std::swap(p[s + 2], p[s + 3]);
  } else if (name == "swap-edges") {  // (a0, a1, b0, b1) -> (b0, b1, a0, a1)
    for (int s : {0, 4}) {
      std::swap(p[s + 0], p[s + 2]);
      std::swap(p[s + 1], p[s + 3]);
    }
  } else if (name == "reverse-edge") {  // (a0, a1) -> (a1, a0)
    for (int s : {0, 4}) std::swap(p[s + 0], p[s + 1]);
  } else if (name == "permute-axes") {  // (x, y, z) -> (y, z, x)
    for (auto& v : p) v = Eigen::Vector3d(v[1], v[2], v[0]);
  } else if (name == "mirror") {  // x -> -x
    for (auto& v : p) v[0] = -v[0];
  } else if (name == "scale-up" || name == "scale-down") {  // x 2^40, x 2^-40
    const int e = name == "scale-up" ? 40 : -40;
    for (auto& v : p)
      for (int i = 0; i < 3; ++i) {
        const double s = std::ldexp(v[i], e);
        if (!std::isfinite(s) || std::ldexp(s, -e) != v[i]) return false;
        v[i] = s;
      }
  } else if (name == "translate") {  // per axis by the largest exact 3 * 2^j, j <= 20
    for (int i = 0; i < 3; ++i) {
      double x[8];
      for (int k = 0; k < 8; ++k) x[k] = p[k][i];
      const double c = exact_translation(x);
      for (auto& v : p) v[i] += c;
    }
  } else {
    return false;
  }
  return true;
}

}  // namespace impact::test
