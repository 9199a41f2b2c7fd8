// SPDX-License-Identifier: MIT
// Consumer of an installed (or add_subdirectory'd) impact: builds a sphere tree over a generated
// mesh, runs a sphere-overlap traversal and checks it against brute force. Exit code 0 = pass.
#include <impact/bvh/mesh_bvh.hpp>
#include <impact/bvh/traverse.hpp>
#include <impact/geometry/mesh_generators.hpp>
#include <impact/geometry/sphere.hpp>

#include <cstdio>
#include <set>

int main() {
  const auto mesh = impact::make_icosphere<double>(1.0, 3);
  const impact::MeshBvh<impact::Sphere<double>> bvh(mesh);
  const impact::Sphere<double> query(Eigen::Vector3d(1.0, 0.0, 0.0), 0.3);

  std::set<int> visited;  // rows of F reached through overlapping nodes
  impact::traverse(
      bvh.tree(), [&](const impact::Sphere<double>& bv) { return impact::overlap(bv, query); },
      [&](std::int32_t leaf) {
        visited.insert(bvh.triangle_id(leaf));
        return true;
      });
  // conservative: every triangle with a corner inside the query sphere was reached
  int expected = 0;
  for (int t = 0; t < mesh.num_triangles(); ++t) {
    const auto tri = mesh.triangle(t);
    if (query.contains(tri.a) || query.contains(tri.b) || query.contains(tri.c)) {
      ++expected;
      if (!visited.count(t)) {
        std::printf("FAIL: triangle %d inside the query was not reached\n", t);
        return 1;
      }
    }
  }
  if (expected == 0 || visited.size() >= static_cast<std::size_t>(mesh.num_triangles())) {
    std::printf("FAIL: %d expected, %zu visited of %d\n", expected, visited.size(), mesh.num_triangles());
    return 1;
  }
  std::printf("impact consumer ok: %d triangles, %zu nodes, %zu visited, %d with a corner inside\n", mesh.num_triangles(),
              bvh.tree().nodes.size(), visited.size(), expected);
  return 0;
}
