// SPDX-License-Identifier: MIT
// impact-fit-bench: run time against tightness of the four bounding-sphere methods.
//
//   impact-fit-bench [MESH...] [--repeat R] [--json FILE]
//
// For each mesh (built-in generated meshes without arguments) and each method (aabb-center,
// centroid, ritter, exact), two measurements:
//  - whole mesh: time to fit all vertices, and the radius excess over the exact minimal sphere;
//  - tree: time to build a sphere tree whose nodes are fitted by that method, and the sum of all
//    node radii as excess over the same tree fitted exactly (the topology does not depend on the
//    fit, so node by node the exact sphere is the lower bound).
#include "bench_util.hpp"
#include "impact/bvh/mesh_bvh.hpp"
#include "impact/geometry/mesh_generators.hpp"

#include <cstdio>
#include <cstdlib>

using namespace impact;
using impact::bench::Clock;
using impact::bench::seconds_since;

namespace {
const std::pair<SphereFit, const char*> kMethods[] = {
    {SphereFit::AabbCenter, "aabb-center"}, {SphereFit::Centroid, "centroid"}, {SphereFit::Ritter, "ritter"}, {SphereFit::Exact, "exact"}};

double sum_radii(const MeshBvh<Sphere<double>>& m) {
  double s = 0;
  for (const auto& n : m.tree().nodes) s += n.bv.radius;
  return s;
}
}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> paths;
  std::string json;
  int repeat = 5;
  const char* usage = "usage: impact-fit-bench [MESH...] [--repeat R] [--json FILE]\n";
  for (int i = 1; i < argc; ++i) {
    const std::string s = argv[i];
    if (s == "--json") json = bench::option_value(argc, argv, i, usage);
    else if (s == "--repeat") repeat = int(bench::parse_integer(s, bench::option_value(argc, argv, i, usage), 1, 1000, usage));
    else if (!s.empty() && s[0] == '-') bench::reject_option(s, usage);
    else paths.push_back(s);
  }
  bench::check_writable(json, usage);
  std::vector<std::pair<std::string, TriangleMesh<double>>> meshes;
  try {
    if (paths.empty()) {
      meshes.emplace_back("generated:torus", make_torus<double>(1.0, 0.35, 160, 64));
      meshes.emplace_back("generated:icosphere", make_icosphere<double>(1.0, 5));
      meshes.emplace_back("generated:soup", make_random_soup<double>(20000, 7));
    }
    for (const auto& p : paths) {
#ifdef IMPACT_HAVE_IO
      meshes.emplace_back(p, load_mesh<double>(p, bench::bench_load_options()));
#else
      std::fprintf(stderr, "impact-fit-bench: built without assimp, cannot load %s\n", p.c_str());
      return 1;
#endif
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "impact-fit-bench: %s\n", e.what());
    return 1;
  }

  std::vector<std::string> items;
  std::printf("%-28s %-12s %8s %14s %12s %14s %16s\n", "mesh", "method", "tris", "whole_us", "whole_excess", "tree_build_ms",
              "tree_sum_excess");
  for (const auto& [name, mesh] : meshes) {
    std::vector<Vec3<double>> pts(static_cast<std::size_t>(mesh.V.rows()));
    for (Eigen::Index i = 0; i < mesh.V.rows(); ++i) pts[static_cast<std::size_t>(i)] = mesh.V.row(i).transpose();
    const double exact_r = bounding_sphere(pts, SphereFit::Exact).radius;
    MeshBvhConfig exact_cfg;
    exact_cfg.fit.sphere = SphereFit::Exact;
    const double exact_sum = sum_radii(MeshBvh<Sphere<double>>(mesh, exact_cfg));
    for (const auto& [method, mname] : kMethods) {
      double whole_s = 1e300, r = 0;
      for (int k = 0; k < repeat; ++k) {
        auto t0 = Clock::now();
        r = bounding_sphere(pts, method).radius;
        whole_s = std::min(whole_s, seconds_since(t0));
      }
      MeshBvhConfig cfg;
      cfg.fit.sphere = method;
      double build_s = 1e300, sum = 0;
      for (int k = 0; k < repeat; ++k) {
        auto t0 = Clock::now();
        MeshBvh<Sphere<double>> m(mesh, cfg);
        build_s = std::min(build_s, seconds_since(t0));
        sum = sum_radii(m);
      }
      const double whole_excess = r / exact_r - 1, tree_excess = sum / exact_sum - 1;
      std::printf("%-28s %-12s %8d %14.1f %11.2f%% %14.2f %15.2f%%\n", name.c_str(), mname, mesh.num_triangles(), whole_s * 1e6,
                  100 * whole_excess, build_s * 1e3, 100 * tree_excess);
      bench::JsonObject o;
      o.add("mesh", name).add("method", mname).add("triangles", mesh.num_triangles()).add("whole_us", whole_s * 1e6);
      o.add("whole_radius_excess", whole_excess).add("tree_build_ms", build_s * 1e3).add("tree_radius_sum_excess", tree_excess);
      items.push_back(o.str());
    }
  }
  std::printf("\nexcess: radius over the exact minimal sphere (whole mesh), or sum of node radii over the same tree fitted exactly.\n"
              "times: best of %d runs.\n", repeat);
  if (!json.empty()) {
    bench::JsonObject top;
    top.add("repeat", repeat).raw("results", bench::JsonObject::array(items));
    if (!bench::write_file(json, top.str())) return 1;
  }
  return 0;
}
