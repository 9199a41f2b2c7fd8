// SPDX-License-Identifier: MIT
// impact-convex-bench: per shape pair, boolean / distance / penetration queries per second for
// impact's convex layer (convex/query.hpp) and FCL 0.7 on the same shapes and poses, with the error
// of each against an oracle independent of both (tests/support/convex_oracle.hpp):
//   distance     the certified bracket of the ellipsoid method (width < 1e-11), error |d - mid|
//   penetration  the exact least overlap over the candidate axes for box/hull pairs; for curved
//                shapes the least overlap found by a grid search over directions (an upper bound
//                of the true depth: only a depth above it counts as error)
//   boolean      mismatches against the oracle's sign where |signed distance| > 1e-6 of the size
// Errors are relative to the larger shape's size (shape_size). FCL is set up as its users do:
// fcl::Sphere / Capsule / Cylinder / Cone / Box / Convex, fcl::collide and fcl::distance on
// CollisionGeometry + Transform3 with default requests (its default narrow-phase solver, the libccd
// one: GST_LIBCCD), contacts requested for penetration (CollisionRequest(1, true)) and nearest
// points for distance (DistanceRequest(true)), since impact returns both.
//
//   impact-convex-bench [--pairs N] [--json FILE] [--min-time SECONDS]
#include "bench_util.hpp"
#include "impact/convex/query.hpp"
#include "support/convex_oracle.hpp"
#ifdef IMPACT_HAVE_FCL
#include "support/convex_fcl.hpp"
#endif

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <string>
#include <vector>

namespace {

using namespace impact;
using impact::bench::Clock;
using impact::bench::JsonObject;
using impact::bench::seconds_since;
using V3 = Eigen::Vector3d;
using Pose = RigidTransform<double>;

struct Row {
  std::string pair, query, library;
  double qps = 0, mean_error = 0, max_error = 0;
  int mismatches = 0, samples = 0;
};

struct Reference {
  double signed_distance = 0;  // > 0 separated (bracket midpoint), < 0 minus the depth reference
  bool separated = false, intersecting = false;
  bool exact_depth = false;  // polytope pairs: the depth reference is exact, else an upper bound
};

template <class A, class B>
Reference reference(const A& a, const Pose& pa, const B& b, const Pose& pb, double scale) {
  Reference r;
  r.exact_depth = false;
  const auto br = test::distance_bracket(a, pa, b, pb);
  if (br.lower > 1e-6 * scale) {
    r.separated = true;
    r.signed_distance = (br.lower + br.upper) / 2;
    return r;
  }
  const auto o = test::signed_distance_oracle(a, pa, b, pb);
  double depth = -o.value;
  constexpr bool polytopes = (std::is_same_v<A, Box<double>> || std::is_same_v<A, ConvexHull<double>>)&&(
      std::is_same_v<B, Box<double>> || std::is_same_v<B, ConvexHull<double>>);
  if constexpr (polytopes) {
    std::vector<V3> normals, ea, eb;
    test::polytope_features(a, pa, normals, ea);
    test::polytope_features(b, pb, normals, eb);
    depth = test::polytope_depth(normals, ea, eb, [&](const V3& m) { return test::overlap_along(a, pa, b, pb, m); });
    r.exact_depth = true;
  }
  if (br.upper < 1e-9 * scale && depth > 1e-6 * scale) {
    r.intersecting = true;
    r.signed_distance = -depth;
  }
  return r;
}

/// Depth error against the reference: |depth - exact| for polytopes; for curved shapes the
/// reference is an upper bound of the true depth, so only the excess above it counts (a depth below
/// it may still be exact).
double depth_error(double depth, const Reference& r) {
  const double ref = -r.signed_distance;
  return r.exact_depth ? std::abs(depth - ref) : std::max(depth - ref, 0.0);
}

/// Runs body(i) over the poses repeatedly for at least min_time seconds; queries per second.
double rate(std::size_t n, double min_time, const std::function<void(std::size_t)>& body) {
  std::size_t count = 0;
  const auto t0 = Clock::now();
  double t = 0;
  do {
    for (std::size_t i = 0; i < n; ++i) body(i);
    count += n;
    t = seconds_since(t0);
  } while (t < min_time);
  return double(count) / t;
}

struct Errors {
  double sum = 0, max = 0;
  int n = 0, mismatches = 0;
  void add(double e) {
    sum += e;
    max = std::max(max, e);
    ++n;
  }
};

volatile double g_sink = 0;

template <class A, class B>
void run_pair(const std::string& name, const A& a, const B& b, int n_poses, double min_time, std::vector<Row>& rows) {
  const double scale = std::max(shape_size(a), shape_size(b));
  const auto poses = test::convex_poses(n_poses, 0.9 * (shape_size(a) + shape_size(b)), std::hash<std::string>{}(name) & 0xffff);
  std::vector<Reference> ref;
  for (const auto& [pa, pb] : poses) ref.push_back(reference(a, pa, b, pb, scale));
  const std::size_t n = poses.size();

  const auto add = [&](const char* query, const char* lib, double qps, const Errors& e) {
    Row r;
    r.pair = name;
    r.query = query;
    r.library = lib;
    r.qps = qps;
    r.mean_error = e.n ? e.sum / e.n / scale : 0;
    r.max_error = e.max / scale;
    r.mismatches = e.mismatches;
    r.samples = e.n;
    rows.push_back(r);
  };

  // impact
  {
    Errors eb, ed, ep;
    for (std::size_t i = 0; i < n; ++i) {
      const auto& [pa, pb] = poses[i];
      const bool hit = convex_intersect(a, pa, b, pb);
      const auto d = convex_distance(a, pa, b, pb);
      const auto c = convex_penetration(a, pa, b, pb);
      if (ref[i].separated || ref[i].intersecting) {
        ++eb.n;
        eb.mismatches += hit != ref[i].intersecting;
        ed.mismatches += d.intersecting != ref[i].intersecting;
        ep.mismatches += c.intersecting != ref[i].intersecting;
      }
      if (ref[i].separated && !d.intersecting) ed.add(std::abs(d.distance - ref[i].signed_distance));
      if (ref[i].intersecting && c.intersecting) ep.add(depth_error(c.depth, ref[i]));
    }
    const double qb = rate(n, min_time, [&](std::size_t i) { g_sink = g_sink + convex_intersect(a, poses[i].first, b, poses[i].second); });
    const double qd = rate(n, min_time, [&](std::size_t i) { g_sink = g_sink + convex_distance(a, poses[i].first, b, poses[i].second).distance; });
    const double qp =
        rate(n, min_time, [&](std::size_t i) { g_sink = g_sink + convex_penetration(a, poses[i].first, b, poses[i].second).depth; });
    add("boolean", "impact", qb, eb);
    add("distance", "impact", qd, ed);
    add("penetration", "impact", qp, ep);
  }
#ifdef IMPACT_HAVE_FCL
  {
    const test::FclShapePair fcl{test::to_fcl_shape(a), test::to_fcl_shape(b)};
    Errors eb, ed, ep;
    for (std::size_t i = 0; i < n; ++i) {
      const auto& [pa, pb] = poses[i];
      const bool hit = fcl.collide(pa, pb);
      V3 wa, wb;
      const double d = fcl.distance(pa, pb, &wa, &wb);
      double depth = 0;
      V3 normal, point;
      const bool pen = fcl.penetration(pa, pb, depth, normal, point);
      if (ref[i].separated || ref[i].intersecting) {
        ++eb.n;
        eb.mismatches += hit != ref[i].intersecting;
        ed.mismatches += (d <= 0) != ref[i].intersecting;
        ep.mismatches += pen != ref[i].intersecting;
      }
      if (ref[i].separated && d > 0) ed.add(std::abs(d - ref[i].signed_distance));
      if (ref[i].intersecting && pen) ep.add(depth_error(depth, ref[i]));
    }
    V3 wa, wb;
    double depth;
    V3 normal, point;
    const double qb = rate(n, min_time, [&](std::size_t i) { g_sink = g_sink + fcl.collide(poses[i].first, poses[i].second); });
    const double qd = rate(n, min_time, [&](std::size_t i) { g_sink = g_sink + fcl.distance(poses[i].first, poses[i].second, &wa, &wb); });
    const double qp =
        rate(n, min_time, [&](std::size_t i) { g_sink = g_sink + fcl.penetration(poses[i].first, poses[i].second, depth, normal, point); });
    add("boolean", "fcl", qb, eb);
    add("distance", "fcl", qd, ed);
    add("penetration", "fcl", qp, ep);
  }
#endif
}

}  // namespace

int main(int argc, char** argv) {
  int n_poses = 1000;
  double min_time = 0.2;
  std::string json;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--pairs" && i + 1 < argc) {
      n_poses = std::atoi(argv[++i]);
    } else if (arg == "--json" && i + 1 < argc) {
      json = argv[++i];
    } else if (arg == "--min-time" && i + 1 < argc) {
      min_time = std::atof(argv[++i]);
    } else {
      std::fprintf(stderr, "usage: impact-convex-bench [--pairs N] [--json FILE] [--min-time SECONDS]\n");
      return 2;
    }
  }
  if (n_poses < 1 || !(min_time >= 0)) {
    std::fprintf(stderr, "impact-convex-bench: --pairs must be >= 1 and --min-time >= 0\n");
    return 2;
  }
  const test::ConvexZoo z;
  std::vector<Row> rows;
  std::printf("impact-convex-bench: %d poses per pair, each query timed for >= %.2f s; errors relative to the larger shape's size\n",
              n_poses, min_time);
  run_pair("sphere-sphere", z.sphere, z.sphere, n_poses, min_time, rows);
  run_pair("sphere-capsule", z.sphere, z.capsule, n_poses, min_time, rows);
  run_pair("capsule-capsule", z.capsule, z.capsule, n_poses, min_time, rows);
  run_pair("sphere-box", z.sphere, z.box, n_poses, min_time, rows);
  run_pair("box-box", z.box, z.box, n_poses, min_time, rows);
  run_pair("capsule-box", z.capsule, z.box, n_poses, min_time, rows);
  run_pair("sphere-cylinder", z.sphere, z.cylinder, n_poses, min_time, rows);
  run_pair("capsule-cylinder", z.capsule, z.cylinder, n_poses, min_time, rows);
  run_pair("cylinder-cylinder", z.cylinder, z.cylinder, n_poses, min_time, rows);
  run_pair("cylinder-cone", z.cylinder, z.cone, n_poses, min_time, rows);
  run_pair("cone-box", z.cone, z.box, n_poses, min_time, rows);
  run_pair("sphere-hull", z.sphere, z.hull, n_poses, min_time, rows);
  run_pair("capsule-hull", z.capsule, z.hull, n_poses, min_time, rows);
  run_pair("box-hull", z.box, z.hull, n_poses, min_time, rows);
  run_pair("hull-hull", z.hull, z.hull, n_poses, min_time, rows);

  std::printf("%-18s %-12s %-7s %12s %10s %10s %5s %7s %14s\n", "pair", "query", "library", "queries/s", "mean err", "max err", "mism",
              "samples", "impact/FCL");
  std::vector<std::string> items;
  for (const Row& r : rows) {
    double ratio = 0;
    if (r.library == "impact")
      for (const Row& o : rows)
        if (o.library == "fcl" && o.pair == r.pair && o.query == r.query) ratio = r.qps / o.qps;
    char ratio_text[32] = "";
    if (ratio > 0) std::snprintf(ratio_text, sizeof ratio_text, "%.2fx", ratio);
    std::printf("%-18s %-12s %-7s %12.0f %10.2e %10.2e %5d %7d %14s\n", r.pair.c_str(), r.query.c_str(), r.library.c_str(), r.qps,
                r.mean_error, r.max_error, r.mismatches, r.samples, ratio_text);
    JsonObject o;
    o.add("pair", r.pair).add("query", r.query).add("library", r.library).add("queries_per_s", r.qps).add("mean_error", r.mean_error);
    o.add("max_error", r.max_error).add("mismatches", r.mismatches).add("samples", r.samples);
    items.push_back(o.str());
  }
  if (!json.empty()) {
    JsonObject top;
    top.add("bench", "impact-convex-bench").add("poses_per_pair", n_poses).add("min_time_s", min_time);
#ifdef IMPACT_HAVE_FCL
    top.add("peer", "FCL 0.7, fcl::collide / fcl::distance on shape primitives, default requests (GST_LIBCCD)");
#else
    top.add("peer", "none (built without FCL)");
#endif
    top.raw("rows", JsonObject::array(items));
    if (!impact::bench::write_file(json, top.str())) {
      std::fprintf(stderr, "impact-convex-bench: cannot write %s\n", json.c_str());
      return 1;
    }
  }
  return 0;
}
