// SPDX-License-Identifier: MIT
// Qhull (Debian libqhull-dev: libqhull_r, the reentrant C API), the peer of impact-convex-bench's
// hull rows (built with IMPACT_HAVE_QHULL). Set up as qhull's own docs show for a 3-d convex hull
// (user_r.h, the qh_new_qhull example): one qhT zeroed with qh_zero, qh_new_qhull on the points
// with "qhull Qt" (Qt: triangulated output, since impact returns triangles), the hull read with
// FORALLvertices / FORALLfacets, then qh_freeqhull and qh_memfreeshort.
#pragma once

#include <libqhull_r/qhull_ra.h>

#include <array>
#include <cstdio>
#include <string>
#include <vector>

namespace impact::bench {

/// A hull as qhull returns it: the input indices of its vertices, its facets' vertex indices and
/// planes (unit outward normal n and offset o, n . x + o = 0 on the facet), or the first line of
/// qhull's error message when it refused the input.
struct QhullHull {
  bool ok = false;
  std::string error;
  std::vector<int> vertices;
  std::vector<std::array<int, 3>> triangles;
  std::vector<std::array<double, 4>> planes;
};

/// The qhull options used (also written into the bench's JSON).
inline const char* qhull_options() { return "qhull Qt"; }

/// The convex hull of `n` points (x, y, z consecutive in `xyz`) by qhull. `err` receives qhull's
/// messages (qhull writes them there instead of stderr); it is rewound and read back on failure.
inline QhullHull qhull_hull(std::vector<double>& xyz, int n, FILE* err) {
  QhullHull out;
  qhT qh_storage;
  qhT* qh = &qh_storage;
  if (err) std::rewind(err);  // the error message of this call starts the file
  qh_zero(qh, err);
  char options[32];
  std::snprintf(options, sizeof options, "%s", qhull_options());
  const int code = qh_new_qhull(qh, 3, n, xyz.data(), False, options, nullptr, err);
  if (code == 0) {
    out.ok = true;
    vertexT* vertex;
    FORALLvertices out.vertices.push_back(qh_pointid(qh, vertex->point));
    facetT* facet;
    FORALLfacets {
      std::array<int, 3> t{-1, -1, -1};
      int k = 0;
      vertexT** vertexp;
      FOREACHvertex_(facet->vertices) {
        if (k < 3) t[static_cast<std::size_t>(k)] = qh_pointid(qh, vertex->point);
        ++k;
      }
      out.triangles.push_back(t);
      out.planes.push_back({facet->normal[0], facet->normal[1], facet->normal[2], facet->offset});
    }
  } else if (err) {
    std::fflush(err);
    std::rewind(err);
    char line[256] = "";
    if (std::fgets(line, sizeof line, err)) out.error = line;
    while (!out.error.empty() && (out.error.back() == '\n' || out.error.back() == '\r')) out.error.pop_back();
    std::rewind(err);
  }
  qh_freeqhull(qh, !qh_ALL);
  int curlong = 0, totlong = 0;
  qh_memfreeshort(qh, &curlong, &totlong);
  return out;
}

}  // namespace impact::bench
