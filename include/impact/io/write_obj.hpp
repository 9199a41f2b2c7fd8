// SPDX-License-Identifier: MIT
/// \file
/// write_obj: saves a TriangleMesh as a Wavefront OBJ file (positions and triangles only), for
/// examples, debugging and round trips through load_mesh. Needs no third-party library.
#pragma once

#include "impact/core/error.hpp"
#include "impact/geometry/triangle_mesh.hpp"

#include <fstream>
#include <limits>
#include <string>

namespace impact {

/// Writes `v x y z` lines (with max_digits10 significant digits, so the text parses back to the
/// same values of S) and one-based `f a b c` lines, in the order of V and F. Validates the mesh
/// first. Throws InvalidInput when the mesh is invalid or the file cannot be created or written.
/// Note that load_mesh reads coordinates through assimp's single-precision ai_real.
template <class S> void write_obj(const std::string& path, const TriangleMesh<S>& mesh) {
  validate_mesh(mesh, "write_obj: '" + path + "'");
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) throw InvalidInput("write_obj: '" + path + "': cannot create the file");
  out.precision(std::numeric_limits<S>::max_digits10);
  for (int i = 0; i < mesh.num_vertices(); ++i) out << "v " << mesh.V(i, 0) << ' ' << mesh.V(i, 1) << ' ' << mesh.V(i, 2) << '\n';
  for (int t = 0; t < mesh.num_triangles(); ++t)
    out << "f " << mesh.F(t, 0) + 1 << ' ' << mesh.F(t, 1) + 1 << ' ' << mesh.F(t, 2) + 1 << '\n';
  out.flush();
  if (!out) throw InvalidInput("write_obj: '" + path + "': write failed");
}

}  // namespace impact
