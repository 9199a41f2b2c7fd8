// SPDX-License-Identifier: MIT
// Example: a square cloth falls on a sphere resting on the ground. The reference mass-spring model
// (impact/cloth/cloth_model.hpp) proposes each step's end positions, cloth_collision_step
// (impact/cloth/collision_step.hpp) corrects them so that nothing comes closer than the
// thickness, and the velocities follow from the corrected positions. Every K steps the cloth and
// the sphere are written as an OBJ frame (objects "cloth", "sphere", "ground") into OUT_DIR,
// which is created if needed.
//
//   example-cloth [OUT_DIR] [--resolution N] [--steps S] [--every K]
//
// OUT_DIR defaults to "cloth_frames"; the default run (a 16 x 16 cloth, 120 steps of 1/120 s,
// a frame every 12 steps) writes cloth_0000.obj ... cloth_0009.obj in about ten seconds.
#include "impact/cloth/cloth_model.hpp"
#include "impact/cloth/collision_step.hpp"
#include "impact/geometry/mesh_generators.hpp"

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

using namespace impact;

namespace {

/// A whole-number option in [1, max]: the whole text digits, else 0 (the caller prints the usage).
/// std::atoi would take "12x" for 12 and "abc" for 0 without a word.
int count_arg(const char* text, long max) {
  char* end = nullptr;
  errno = 0;
  const long v = std::strtol(text, &end, 10);
  return errno == 0 && end != text && *end == '\0' && v >= 1 && v <= max ? int(v) : 0;
}

bool write_frame(const std::string& path, const Vertices<double>& cloth, const Faces& F, const TriangleMesh<double>& sphere,
                 const TriangleMesh<double>& ground) {
  std::ofstream f(path);
  int base = 1;
  auto object = [&](const char* name, const Vertices<double>& V, const Faces& T) {
    f << "o " << name << "\n";
    for (Eigen::Index i = 0; i < V.rows(); ++i) f << "v " << V(i, 0) << ' ' << V(i, 1) << ' ' << V(i, 2) << "\n";
    for (Eigen::Index k = 0; k < T.rows(); ++k) f << "f " << T(k, 0) + base << ' ' << T(k, 1) + base << ' ' << T(k, 2) + base << "\n";
    base += static_cast<int>(V.rows());
  };
  object("cloth", cloth, F);
  object("sphere", sphere.V, sphere.F);
  object("ground", ground.V, ground.F);
  return bool(f);
}

}  // namespace

int main(int argc, char** argv) {
  std::string out = "cloth_frames";
  int n = 16, steps = 120, every = 12;
  for (int i = 1; i < argc; ++i) {
    const std::string s = argv[i];
    if (s == "--resolution" && i + 1 < argc && (n = count_arg(argv[++i], 1000)) > 0) continue;
    if (s == "--steps" && i + 1 < argc && (steps = count_arg(argv[++i], 1000000)) > 0) continue;
    if (s == "--every" && i + 1 < argc && (every = count_arg(argv[++i], 1000000)) > 0) continue;
    if (!s.empty() && s[0] != '-') out = s;
    else {
      std::fprintf(stderr, "usage: example-cloth [OUT_DIR] [--resolution N (1-1000)] [--steps S] [--every K]\n");
      return 2;
    }
  }
  std::error_code ec;
  std::filesystem::create_directories(out, ec);
  if (ec) {
    std::fprintf(stderr, "cannot create %s: %s\n", out.c_str(), ec.message().c_str());
    return 1;
  }

  // The cloth: 1 m square, n x n cells, 5 cm above a sphere of radius 0.25 m standing on the ground.
  TriangleMesh<double> cloth = make_grid<double>(n, n, 1.0);
  cloth.V.col(2).array() += 0.55;
  MassSpringParams<double> material;  // light cotton-like defaults
  const MassSpringCloth<double> model = make_mass_spring_cloth(cloth, material);
  Eigen::VectorXd inverse_mass = model.mass.cwiseInverse();  // no pinned vertices here

  // Obstacles never move here: one pose for both ends of every step.
  TriangleMesh<double> sphere = make_icosphere<double>(0.25, 3);
  sphere.V.col(2).array() += 0.25;
  TriangleMesh<double> ground;
  ground.V.resize(4, 3);
  ground.V << -3, -3, 0, 3, -3, 0, 3, 3, 0, -3, 3, 0;
  ground.F.resize(2, 3);
  ground.F << 0, 1, 2, 0, 2, 3;
  ClothObstacles<double> obstacles;
  obstacles.rigid.push_back({&sphere, RigidTransform<double>(), RigidTransform<double>()});
  obstacles.rigid.push_back({&ground, RigidTransform<double>(), RigidTransform<double>()});

  ClothCollisionOptions<double> options;
  options.thickness = 0.004;  // 4 mm: no two primitives ever come closer
  options.friction = 0.3;
  ClothCollisionWorkspace<double> workspace;  // refits the swept tree between steps

  ImplicitStepOptions<double> dynamics;
  dynamics.dt = 1.0 / 120;
  Vertices<double> x = cloth.V, v = Vertices<double>::Zero(cloth.V.rows(), 3);
  int frame = 0, failsafe = 0;
  try {
    for (int step = 0; step < steps; ++step) {
      const ImplicitStepResult<double> proposal = implicit_euler_step(model, x, v, dynamics);
      Vertices<double> x1 = proposal.x1;
      const ClothStepStats stats = cloth_collision_step(cloth.F, inverse_mass, x, x1, obstacles, options, &workspace);
      failsafe += stats.failsafe_used;
      v = (x1 - x) / dynamics.dt;
      x = x1;
      if ((step + 1) % every == 0) {
        char name[64];
        std::snprintf(name, sizeof name, "cloth_%04d.obj", frame++);
        if (!write_frame((std::filesystem::path(out) / name).string(), x, cloth.F, sphere, ground)) {
          std::fprintf(stderr, "cannot write %s\n", name);
          return 1;
        }
      }
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "example-cloth: %s\n", e.what());
    return 1;
  }
  std::printf("%d steps, %d frames in %s, fail-safe used in %d step(s)\n", steps, frame, out.c_str(), failsafe);
  return 0;
}
