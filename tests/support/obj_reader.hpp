// SPDX-License-Identifier: MIT
// A tiny test-only Wavefront OBJ reader: `v x y z` lines and `f` lines with 1-based (or negative,
// relative) indices in the forms i, i/t, i//n, i/t/n; polygons are fan-triangulated. Everything
// else is ignored. Throws impact::InvalidInput when the file cannot be read. Not a general loader
// (that is impact/io); it exists so the tests need no optional dependency.
#pragma once

#include "impact/core/error.hpp"
#include "impact/geometry/triangle_mesh.hpp"

#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace impact::test {

template <class S> TriangleMesh<S> read_obj(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InvalidInput("read_obj: cannot open " + path);
  std::vector<Eigen::Vector3d> v;
  std::vector<Eigen::Vector3i> f;
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream ls(line);
    std::string tag;
    ls >> tag;
    if (tag == "v") {
      Eigen::Vector3d p;
      ls >> p.x() >> p.y() >> p.z();
      v.push_back(p);
    } else if (tag == "f") {
      std::vector<int> poly;
      std::string tok;
      while (ls >> tok) {
        const int i = std::stoi(tok.substr(0, tok.find('/')));
        poly.push_back(i > 0 ? i - 1 : static_cast<int>(v.size()) + i);
      }
      for (std::size_t k = 1; k + 1 < poly.size(); ++k) f.emplace_back(poly[0], poly[k], poly[k + 1]);
    }
  }
  TriangleMesh<S> m;
  m.V.resize(static_cast<Eigen::Index>(v.size()), 3);
  m.F.resize(static_cast<Eigen::Index>(f.size()), 3);
  for (std::size_t i = 0; i < v.size(); ++i) m.V.row(static_cast<Eigen::Index>(i)) = v[i].cast<S>().transpose();
  for (std::size_t i = 0; i < f.size(); ++i) m.F.row(static_cast<Eigen::Index>(i)) = f[i].transpose();
  validate_mesh(m, path);
  return m;
}

}  // namespace impact::test
