// SPDX-License-Identifier: MIT
// Consumer of impact::io: writes a generated mesh as OBJ, loads it back through assimp and checks
// the counts, and checks that a missing file throws impact::InvalidInput. Exit code 0 = pass.
#include <impact/geometry/mesh_generators.hpp>
#include <impact/io/load_mesh.hpp>
#include <impact/io/write_obj.hpp>

#include <cstdio>
#include <string>

int main(int argc, char** argv) {
  if (argc < 2) {
    std::printf("usage: impact-consumer-io SCRATCH_FILE.obj\n");
    return 2;
  }
  const std::string path = argv[1];
  const auto torus = impact::make_torus<double>(1.0, 0.3, 24, 12);
  impact::write_obj(path, torus);
  const auto back = impact::load_mesh<double>(path);
  if (back.num_triangles() != torus.num_triangles() || back.num_vertices() != torus.num_vertices()) {
    std::printf("FAIL: wrote %d/%d, read %d/%d vertices/triangles\n", torus.num_vertices(), torus.num_triangles(),
                back.num_vertices(), back.num_triangles());
    return 1;
  }
  try {
    impact::load_mesh<float>(path + ".missing");
    std::printf("FAIL: no exception for a missing file\n");
    return 1;
  } catch (const impact::InvalidInput&) {
  }
  std::printf("impact io consumer ok: %d vertices, %d triangles\n", back.num_vertices(), back.num_triangles());
  return 0;
}
