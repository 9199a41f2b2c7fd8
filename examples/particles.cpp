// SPDX-License-Identifier: MIT
// Example: particles poured into a bowl (a generated open hemisphere), or onto a mesh given on the
// command line, with backtracking collision response (restitution 0.3, friction 0.4, radius 0.01);
// every K steps the particle positions are written as CSV (x,y,z per line) or PLY point clouds
// into an output folder, ready for ParaView, MeshLab or a spreadsheet.
//
//   example-particles [OUT_DIR] [--mesh FILE] [--steps S] [--every K] [--ply]
//
// OUT_DIR defaults to the current directory and is created (with its parents) when it does not
// exist; the default run (600 steps) takes well under a second and writes 10 files
// particles_0000.csv ... particles_0009.csv.
#include "impact/geometry/mesh_generators.hpp"
#include "impact/response/particle_step.hpp"
#ifdef IMPACT_HAVE_IO
#include "impact/io/load_mesh.hpp"
#endif

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

using namespace impact;

namespace {

// The lower half of a UV sphere of radius 1: an open bowl, normals pointing outwards.
TriangleMesh<double> make_bowl() {
  const TriangleMesh<double> s = make_uv_sphere<double>(1.0, 48, 24);
  std::vector<int> keep;
  for (int t = 0; t < s.num_triangles(); ++t)
    if (s.triangle(t).centroid().z() < 0) keep.push_back(t);
  TriangleMesh<double> b;
  b.V = s.V;
  b.F.resize(static_cast<Eigen::Index>(keep.size()), 3);
  for (std::size_t i = 0; i < keep.size(); ++i) b.F.row(static_cast<Eigen::Index>(i)) = s.F.row(keep[i]);
  return b;
}

/// A whole-number option in [1, max]: the whole text digits, else 0 (the caller prints the usage).
/// std::atoi would take "12x" for 12 and "abc" for 0 without a word.
int count_arg(const char* text, long max) {
  char* end = nullptr;
  errno = 0;
  const long v = std::strtol(text, &end, 10);
  return errno == 0 && end != text && *end == '\0' && v >= 1 && v <= max ? int(v) : 0;
}

bool write_frame(const std::string& path, const std::vector<Particle<double>>& ps, bool ply) {
  std::ofstream f(path);
  if (ply) {
    f << "ply\nformat ascii 1.0\nelement vertex " << ps.size() << "\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
  } else {
    f << "x,y,z\n";
  }
  for (const auto& p : ps) f << p.position.x() << (ply ? ' ' : ',') << p.position.y() << (ply ? ' ' : ',') << p.position.z() << '\n';
  return bool(f);
}

}  // namespace

int main(int argc, char** argv) {
  std::string out = ".", mesh_path;
  int steps = 600, every = 60;
  bool ply = false;
  for (int i = 1; i < argc; ++i) {
    const std::string s = argv[i];
    if (s == "--steps" && i + 1 < argc && (steps = count_arg(argv[++i], 1000000)) > 0) continue;
    if (s == "--every" && i + 1 < argc && (every = count_arg(argv[++i], 1000000)) > 0) continue;
    if (s == "--mesh" && i + 1 < argc) mesh_path = argv[++i];
    else if (s == "--ply") ply = true;
    else if (!s.empty() && s[0] != '-') out = s;
    else {
      std::fprintf(stderr,
                   "usage: example-particles [OUT_DIR] [--mesh FILE] [--steps S] [--every K] [--ply]\n"
                   "  OUT_DIR  folder for the frames (default: the current one; created if missing)\n");
      return 2;
    }
  }

  std::error_code ec;
  std::filesystem::create_directories(out, ec);  // no-op when it exists
  if (ec) {
    std::fprintf(stderr, "cannot create the output folder %s: %s\n", out.c_str(), ec.message().c_str());
    return 1;
  }

  TriangleMesh<double> mesh;
  try {
    if (mesh_path.empty()) {
      mesh = make_bowl();
    } else {
#ifdef IMPACT_HAVE_IO
      mesh = load_mesh<double>(mesh_path);
#else
      std::fprintf(stderr, "built without assimp: run without --mesh\n");
      return 1;
#endif
    }
  } catch (const InvalidInput& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 1;
  }
  // Scale the scene to the mesh: pour from above the centre of its box.
  Aabb<double> box;
  for (int i = 0; i < mesh.num_vertices(); ++i) box.extend(mesh.vertex(i));
  const double size = 2 * box.half_diagonal();
  const MeshBvh<Aabb<double>> bvh(mesh);

  ColliderSet<double> colliders;
  colliders.meshes.emplace_back(bvh, ColliderSide::TwoSided, Material<double>{0.3, 0.4});
  // a floor below everything catches what falls off
  colliders.planes.emplace_back(Plane<double>(Vec3<double>::UnitZ(), box.min.z() - 0.05 * size), Material<double>{0.3, 0.4});

  StepOptions<double> opt;  // backtracking, the default
  opt.gravity = Vec3<double>(0, 0, -9.81 * size / 2);
  const double dt = 1.0 / 240;

  std::vector<Particle<double>> particles;
  detail::SplitMix64 rng(7);
  const Vec3<double> spout(box.center().x(), box.center().y(), box.max.z() + 0.2 * size);
  int frame = 0;
  for (int step = 0; step < steps; ++step) {
    if (step < steps / 2) {  // pour 4 particles per step during the first half
      for (int k = 0; k < 4; ++k) {
        Particle<double> p;
        p.radius = 0.01 * size;
        p.position = spout + 0.05 * size * Vec3<double>(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
        p.velocity = 0.2 * size * Vec3<double>(rng.uniform(-1, 1), rng.uniform(-1, 1), 0);
        particles.push_back(p);
      }
    }
    step_particles(particles, colliders, dt, opt);
    if ((step + 1) % every == 0) {
      char name[64];
      std::snprintf(name, sizeof name, "/particles_%04d.%s", frame++, ply ? "ply" : "csv");
      if (!write_frame(out + name, particles, ply)) {
        std::fprintf(stderr, "cannot write %s%s\n", out.c_str(), name);
        return 1;
      }
    }
  }
  std::printf("%zu particles, %d steps, %d frames written to %s\n", particles.size(), steps, frame, out.c_str());
  return 0;
}
