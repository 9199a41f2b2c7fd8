// SPDX-License-Identifier: MIT
/// \file
/// TriangleMesh (owning vertex and face arrays) and validate_mesh, the check every entry point that
/// takes user arrays runs once: non-empty, finite coordinates within CoordinateRange, indices in range. Zero-area
/// triangles are valid. After validation the hot paths trust the data.
#pragma once

#include "impact/core/error.hpp"
#include "impact/core/types.hpp"
#include "impact/core/validate.hpp"
#include "impact/geometry/triangle.hpp"

#include <algorithm>
#include <sstream>
#include <string>

namespace impact {

/// A triangle mesh: V is n x 3 positions, F is m x 3 indices into V (counter-clockwise seen from
/// outside for closed meshes, though nothing in the collision core depends on orientation).
template <class S> struct TriangleMesh {
  Vertices<S> V;
  Faces F;

  TriangleMesh() = default;
  TriangleMesh(Vertices<S> v, Faces f) : V(std::move(v)), F(std::move(f)) {}

  int num_vertices() const { return static_cast<int>(V.rows()); }
  int num_triangles() const { return static_cast<int>(F.rows()); }
  Vec3<S> vertex(int i) const { return V.row(i).transpose(); }
  Triangle<S> triangle(int t) const { return {vertex(F(t, 0)), vertex(F(t, 1)), vertex(F(t, 2))}; }
  template <class T> TriangleMesh<T> cast() const { return {V.template cast<T>(), F}; }
};

/// Throws InvalidInput unless V and F describe a usable triangle mesh: at least one triangle,
/// at least one vertex, every coordinate finite and at most CoordinateRange<S>::max in magnitude,
/// the largest coordinate magnitude 0 or at least CoordinateRange<S>::min_scale (core/validate.hpp:
/// the range where the constructions keep their accuracy), every index in [0, V.rows()). `what`
/// names the mesh in the message.
template <class DerivedV, class DerivedF>
void validate_mesh(const Eigen::MatrixBase<DerivedV>& V, const Eigen::MatrixBase<DerivedF>& F, const std::string& what = "mesh") {
  using S = typename DerivedV::Scalar;
  if (V.cols() != 3) throw InvalidInput(what + ": vertex array must have 3 columns, has " + std::to_string(V.cols()));
  if (F.cols() != 3) throw InvalidInput(what + ": face array must have 3 columns, has " + std::to_string(F.cols()));
  if (F.rows() == 0) throw InvalidInput(what + ": empty mesh (no triangles)");
  if (V.rows() == 0) throw InvalidInput(what + ": empty mesh (no vertices)");
  S scale = S(0);
  for (Eigen::Index i = 0; i < V.rows(); ++i) {
    if (!all_finite(V.row(i)))
      throw InvalidInput(what + ": vertex " + std::to_string(i) + " has a NaN or infinite coordinate");
    const S m = V.row(i).cwiseAbs().maxCoeff();
    if (m > CoordinateRange<S>::max)
      throw InvalidInput(what + ": vertex " + std::to_string(i) + " has a coordinate beyond " + detail::to_text(CoordinateRange<S>::max) +
                         " in magnitude (CoordinateRange, core/validate.hpp)");
    scale = std::max(scale, m);
  }
  if (scale != S(0) && scale < CoordinateRange<S>::min_scale) {
    std::ostringstream s;
    s << what << ": every coordinate is below " << CoordinateRange<S>::min_scale << " in magnitude (the largest is " << scale
      << "): too small for accurate constructions (CoordinateRange, core/validate.hpp)";
    throw InvalidInput(s.str());
  }
  const auto n = V.rows();
  for (Eigen::Index t = 0; t < F.rows(); ++t) {
    for (int k = 0; k < 3; ++k) {
      const auto idx = F(t, k);
      if (idx < 0 || idx >= n)
        throw InvalidInput(what + ": triangle " + std::to_string(t) + " has vertex index " + std::to_string(idx) +
                           " outside [0, " + std::to_string(n) + ")");
    }
  }
}

template <class S> void validate_mesh(const TriangleMesh<S>& m, const std::string& what = "mesh") { validate_mesh(m.V, m.F, what); }

}  // namespace impact
