// SPDX-License-Identifier: MIT
// impact-hierarchy-bench: every hierarchy of the library on the same work, to choose one.
//
//   impact-hierarchy-bench [MESH...] [--poses N] [--rays N] [--seed S] [--json FILE]
//
// A MESH given as A,B (two paths and a comma) runs the mesh–mesh queries of A against B; every
// other query runs on A.
// For each mesh (default: a generated torus) and each structure (bounding volume sphere, AABB or
// oriented box, times builder: top-down middle, median or SAH split, bottom-up clustering,
// incremental insertion; and the kd-tree over triangles): build time of one tree, its memory
// beyond the mesh (bytes per triangle), refit time after a deformation, and per query the median
// and mean time and the BV and primitive tests: boolean and all-pairs mesh–mesh (the mesh against
// itself under N random poses, tests/support/poses.hpp), self-collision (all pairs), ray first
// hit for short segments from near the surface and long rays from outside (N of each), closest
// point from N points around the mesh. The kd-tree answers no collision query and gets no row
// for them. Every answer is checked: the colliding poses, pair sets, hit parameters and
// distances must be identical across structures (the first structure to answer is the
// reference), and the first 32 rays and points are also checked against brute force over all
// triangles; any mismatch is printed and the bench exits with status 3.
// --copies N adds the mesh "copies-N": N copies of one tilted triangle, in three vertex orders
// (coincident copies, README "Nearest-first queries"): the middle-split tree of each BV and the
// kd-tree, build time, ray casts through the triangle and closest points near it (--rays of each,
// the first 8 checked against brute force), with their triangle tests.
// --json FILE writes one row per structure and query (structure, bv, builder, query, build_ms,
// bytes_per_triangle, median_us, mean_us, tests, bv_tests, primitive_tests, refit_ms, mismatches).
#include "bench_util.hpp"
#include "impact/query/kd_tree.hpp"
#include "impact/bvh/mesh_bvh.hpp"
#include "impact/geometry/mesh_generators.hpp"
#include "impact/query/closest_point_mesh.hpp"
#include "impact/query/mesh_collide.hpp"
#include "impact/query/ray_mesh.hpp"
#include "support/poses.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <map>
#include <optional>

using namespace impact;
using impact::bench::Clock;
using impact::bench::seconds_since;

namespace {

struct Args {
  std::vector<std::string> meshes;
  std::string json;
  int poses = 100, rays = 1000, threads = 0, copies = 0;
  std::uint64_t seed = 1;
};

constexpr const char* kUsage =
    "usage: impact-hierarchy-bench [MESH...] [--poses N] [--rays N] [--seed S] [--threads T] [--copies N] [--json FILE]\n";


Args parse(int argc, char** argv) {
  Args a;
  for (int i = 1; i < argc; ++i) {
    const std::string s = argv[i];
    auto next = [&] { return bench::option_value(argc, argv, i, kUsage); };
    if (s == "--poses") a.poses = int(bench::parse_integer(s, next(), 1, 10000000, kUsage));
    else if (s == "--rays") a.rays = int(bench::parse_integer(s, next(), 1, 10000000, kUsage));
    else if (s == "--seed") a.seed = bench::parse_seed(s, next(), kUsage);
    else if (s == "--json") a.json = next();
    else if (s == "--threads") a.threads = int(bench::parse_integer(s, next(), 0, 1024, kUsage));
    else if (s == "--copies") a.copies = int(bench::parse_integer(s, next(), 0, 10000000, kUsage));
    else if (!s.empty() && s[0] == '-') bench::reject_option(s, kUsage);
    else a.meshes.push_back(s);
  }
  bench::check_writable(a.json, kUsage);
  return a;
}

TriangleMesh<double> load(const std::string& path) { return bench::load_mesh_or_exit(path, kUsage); }

struct Row {
  std::string mesh, structure, bv, builder, query;
  double build_ms = 0, bytes_per_triangle = 0, refit_ms = -1;
  bench::Summary us;
  double bv_tests = -1, primitive_tests = -1;
  int mismatches = 0;
};

/// The work of one mesh: poses, rays, points, and the reference answers.
struct Work {
  std::string mesh;
  TriangleMesh<double> m;
  TriangleMesh<double> other;  // B of the mesh-mesh queries (m itself unless given as A,B)
  std::vector<RigidTransform<double>> poses;
  std::vector<Ray<double>> short_rays, long_rays;
  std::vector<Vec3<double>> points;
  Vertices<double> deformed;  // for refit
  // reference answers (empty until a structure answers)
  std::vector<char> boolean;
  std::vector<std::vector<std::pair<std::int32_t, std::int32_t>>> pairs;
  std::vector<std::pair<std::int32_t, std::int32_t>> self_pairs;
  bool have_self = false;
  std::map<std::string, std::vector<double>> ray_t;  // "ray_short" / "ray_long"
  std::vector<double> distance;
  std::string reference[7];

  /// The rays of query "ray_short" or "ray_long".
  const std::vector<Ray<double>>& rays(const char* query) const {
    return std::strcmp(query, "ray_short") == 0 ? short_rays : long_rays;
  }
};

bool same(double a, double b) { return (std::isnan(a) && std::isnan(b)) || a == b; }

/// Brute force over all triangles: the narrow phase's watertight test with the library's tie rule.
double brute_ray(const TriangleMesh<double>& m, const Ray<double>& r) {
  const PreparedRay<double> pr(r);
  double best = std::numeric_limits<double>::quiet_NaN();
  for (int t = 0; t < m.num_triangles(); ++t) {
    const auto h = detail::ray_mesh_triangle_hit(pr, m.triangle(t));
    if (h && (std::isnan(best) || h->t < best)) best = h->t;
  }
  return best;
}
double brute_distance(const TriangleMesh<double>& m, const Vec3<double>& p) {
  double best = std::numeric_limits<double>::infinity();
  for (int t = 0; t < m.num_triangles(); ++t) {  // the library's per-triangle rule (query/closest_point_mesh.hpp)
    const Triangle<double> tri = m.triangle(t);
    best = std::min(best, detail::triangle_squared_distance(p, tri, detail::closest_on_triangle(p, tri)));
  }
  return std::sqrt(best);
}

Work make_work(const std::string& name, TriangleMesh<double> m, std::optional<TriangleMesh<double>> other, const Args& args) {
  Work w;
  w.mesh = name;
  w.m = std::move(m);
  if (!other) w.other = w.m;
  else w.other = std::move(*other);
  w.poses = impact::test::random_poses_around(w.m, w.other, args.poses, args.seed);
  const Aabb<double> box = impact::test::bounds(w.m);
  const double diag = (box.max - box.min).norm();
  impact::test::Rng rng(args.seed + 17);
  for (int k = 0; k < args.rays; ++k) {
    // short: from near a random point of a random triangle, 2 % of the diagonal long
    const Triangle<double> t = w.m.triangle(static_cast<int>(rng.index(static_cast<std::uint64_t>(w.m.num_triangles()))));
    double u = rng.uniform(), v = rng.uniform();
    if (u + v > 1) u = 1 - u, v = 1 - v;
    const Vec3<double> on = t.a + u * (t.b - t.a) + v * (t.c - t.a);
    const Vec3<double> o = on + rng.vec(-0.005, 0.005) * diag;
    Vec3<double> d = rng.vec(-1, 1);
    if (d.norm() < 1e-3) d = Vec3<double>(1, 0, 0);
    d.normalize();
    w.short_rays.emplace_back(o, d, 0.02 * diag);
    // long: from a sphere around the mesh towards a random point of its box, unbounded
    Vec3<double> s = rng.vec(-1, 1);
    if (s.norm() < 1e-3) s = Vec3<double>(0, 0, 1);
    const Vec3<double> lo = box.center() + s.normalized() * diag;
    const Vec3<double> target = rng.in_box(box.min, box.max);
    w.long_rays.emplace_back(lo, (target - lo).normalized(), std::numeric_limits<double>::infinity());
    w.points.push_back(rng.in_box(box.min.array() - 0.1 * diag, box.max.array() + 0.1 * diag));
  }
  // a deformation for refit: every vertex moved by up to 1 % of the diagonal
  w.deformed = w.m.V;
  for (Eigen::Index i = 0; i < w.deformed.rows(); ++i) w.deformed.row(i) += (rng.vec(-0.01, 0.01) * diag).transpose();
  return w;
}

struct Checker {
  int mismatches = 0;
  void report(const Work& w, const std::string& structure, const std::string& query, std::size_t k, const std::string& what) {
    if (++mismatches <= 20)
      std::fprintf(stderr, "MISMATCH %s %s %s query %zu: %s\n", w.mesh.c_str(), structure.c_str(), query.c_str(), k, what.c_str());
  }
};

template <class F> bench::Summary time_each(std::size_t n, F&& f, std::vector<double>* us_out = nullptr) {
  std::vector<double> us(n);
  for (std::size_t k = 0; k < n; ++k) {
    const auto t0 = Clock::now();
    f(k);
    us[k] = seconds_since(t0) * 1e6;
  }
  if (us_out) *us_out = us;
  return bench::summarize(us);
}

/// Checks per-query answers against the reference (brute force for the first ones, then the
/// first structure's answers), extending the reference with answers it does not have yet.
void check_values(Work& w, Checker& ck, Row& row, std::vector<double>& ref, const std::vector<double>& got) {
  const std::size_t known = std::min(ref.size(), got.size());
  if (ref.size() < got.size()) ref.insert(ref.end(), got.begin() + static_cast<std::ptrdiff_t>(ref.size()), got.end());
  for (std::size_t k = 0; k < known; ++k)
    if (!same(ref[k], got[k])) {
      ++row.mismatches;
      char buf[128];
      std::snprintf(buf, sizeof buf, "%.17g, reference %.17g", got[k], ref[k]);
      ck.report(w, row.structure, row.query, k, buf);
    }
}

/// The ray_short and ray_long rows of one structure: `cast(ray, Stats*)` returns its first hit (an
/// optional with `t`), `counts(stats)` the node and triangle tests it counted.
template <class Stats, class MakeRow, class Cast, class Counts>
void ray_rows(Work& w, Checker& ck, std::vector<Row>& rows, MakeRow&& row, Cast&& cast, Counts&& counts) {
  for (const char* q : {"ray_short", "ray_long"}) {
    const auto& rays = w.rays(q);
    Row r = row(q);
    std::vector<double> t(rays.size());
    Stats st;
    r.us = time_each(rays.size(), [&](std::size_t k) {
      const auto h = cast(rays[k], &st);
      t[k] = h ? h->t : std::numeric_limits<double>::quiet_NaN();
    });
    const auto [bv_tests, triangle_tests] = counts(st);
    r.bv_tests = double(bv_tests) / double(rays.size()), r.primitive_tests = double(triangle_tests) / double(rays.size());
    check_values(w, ck, r, w.ray_t[q], t);
    rows.push_back(r);
  }
}

/// The top-down build (middle split) on one thread and on `threads`: the best of three builds
/// each, and whether the trees agree node for node (a mismatch otherwise). Rows: builder
/// "middle-1t" and "middle-<T>t", query "build".
template <class BV>
void build_threads_rows(const Work& w, int threads, std::vector<Row>& rows, Checker& ck) {
  const std::string bv = BvTraits<BV>::name;
  Bvh<BV> trees[2];
  for (int k = 0; k < 2; ++k) {
    MeshBvhConfig cfg;
    cfg.build.threads = k == 0 ? 1 : threads;
    double best = std::numeric_limits<double>::infinity();
    std::size_t tree_bytes = 0;
    for (int rep = 0; rep < 3; ++rep) {
      const auto t0 = Clock::now();
      const MeshBvh<BV> tree(w.m, cfg);
      best = std::min(best, seconds_since(t0) * 1e3);
      if (rep == 0) trees[k] = tree.tree(), tree_bytes = tree.tree_bytes();
    }
    Row r;
    r.mesh = w.mesh, r.bv = bv, r.builder = "middle-" + std::to_string(cfg.build.threads) + "t";
    r.structure = bv + "/" + r.builder, r.query = "build", r.build_ms = best;
    r.bytes_per_triangle = double(tree_bytes) / double(w.m.num_triangles());  // as run_bvh's rows count it
    if (k == 1) {
      bool same = trees[0].nodes.size() == trees[1].nodes.size() && trees[0].primitives == trees[1].primitives;
      for (std::size_t i = 0; same && i < trees[0].nodes.size(); ++i)
        same = trees[0].nodes[i].first == trees[1].nodes[i].first && trees[0].nodes[i].count == trees[1].nodes[i].count &&
               std::memcmp(&trees[0].nodes[i].bv, &trees[1].nodes[i].bv, sizeof(BV)) == 0;
      r.mismatches = same ? 0 : 1;
      ck.mismatches += r.mismatches;
    }
    rows.push_back(r);
  }
}

template <class BV>
void run_bvh(Work& w, const std::string& builder, const MeshBvhConfig& cfg, std::vector<Row>& rows, Checker& ck) {
  const std::string bv = BvTraits<BV>::name;
  const std::string structure = bv + "/" + builder;
  auto t0 = Clock::now();
  MeshBvh<BV> tree(w.m, cfg);
  const double build_ms = seconds_since(t0) * 1e3;
  const double bpt = double(tree.tree_bytes()) / double(tree.num_triangles());
  const MeshBvh<BV> tree_b_own(w.other, cfg);  // B of the mesh-mesh queries (a copy of A's tree for one mesh)
  const MeshBvh<BV>& tree_b = tree_b_own;
  auto row = [&](const char* query) {
    Row r;
    r.mesh = w.mesh, r.structure = structure, r.bv = bv, r.builder = builder, r.query = query;
    r.build_ms = build_ms, r.bytes_per_triangle = bpt;
    return r;
  };
  const RigidTransform<double> id;
  const std::size_t np = w.poses.size();

  {  // boolean
    Row r = row("boolean");
    std::vector<char> ans(np);
    QueryStats total;
    r.us = time_each(np, [&](std::size_t k) {
      QueryStats st;
      ans[k] = collides(tree, id, tree_b, w.poses[k], &st);
      total.bv_tests += st.bv_tests, total.primitive_tests += st.primitive_tests;
    });
    r.bv_tests = double(total.bv_tests) / double(np), r.primitive_tests = double(total.primitive_tests) / double(np);
    if (w.boolean.empty()) w.boolean = ans;
    for (std::size_t k = 0; k < np; ++k)
      if (ans[k] != w.boolean[k]) ++r.mismatches, ck.report(w, structure, "boolean", k, ans[k] ? "colliding, reference not" : "apart, reference colliding");
    rows.push_back(r);
  }
  {  // all pairs
    Row r = row("all_pairs");
    std::vector<std::vector<std::pair<std::int32_t, std::int32_t>>> ans(np);
    QueryStats total;
    CollideOptions opt;
    opt.all_pairs = true;
    r.us = time_each(np, [&](std::size_t k) {
      auto res = collide(tree, id, tree_b, w.poses[k], opt);
      total.bv_tests += res.stats.bv_tests, total.primitive_tests += res.stats.primitive_tests;
      ans[k] = std::move(res.pairs);
    });
    for (auto& a : ans) std::sort(a.begin(), a.end());
    r.bv_tests = double(total.bv_tests) / double(np), r.primitive_tests = double(total.primitive_tests) / double(np);
    if (w.pairs.empty()) w.pairs = ans;
    for (std::size_t k = 0; k < np; ++k)
      if (ans[k] != w.pairs[k])
        ++r.mismatches, ck.report(w, structure, "all_pairs", k, std::to_string(ans[k].size()) + " pairs, reference " + std::to_string(w.pairs[k].size()));
    rows.push_back(r);
  }
  {  // self-collision
    Row r = row("self");
    CollideOptions opt;
    opt.all_pairs = true;
    const std::size_t repeat = std::size_t(std::clamp(200000 / std::max(1, w.m.num_triangles()), 1, 5));
    std::vector<std::pair<std::int32_t, std::int32_t>> ans;
    QueryStats st;
    r.us = time_each(repeat, [&](std::size_t) {
      auto res = self_collide(tree, opt);
      st = res.stats;
      ans = std::move(res.pairs);
    });
    std::sort(ans.begin(), ans.end());
    r.bv_tests = double(st.bv_tests), r.primitive_tests = double(st.primitive_tests);
    if (!w.have_self) w.self_pairs = ans, w.have_self = true;
    if (ans != w.self_pairs)
      ++r.mismatches, ck.report(w, structure, "self", 0, std::to_string(ans.size()) + " pairs, reference " + std::to_string(w.self_pairs.size()));
    rows.push_back(r);
  }
  {
    ray_rows<RayMeshStats>(
        w, ck, rows, row, [&](const Ray<double>& ray, RayMeshStats* st) { return ray_mesh_first_hit(tree, ray, id, st); },
        [](const RayMeshStats& st) { return std::make_pair(st.node_tests, st.triangle_tests); });
    Row r = row("closest_point");
    std::vector<double> d(w.points.size());
    ClosestPointStats st;
    r.us = time_each(w.points.size(), [&](std::size_t k) { d[k] = closest_point_on_mesh(tree, w.points[k], id, {}, &st)->distance; });
    r.bv_tests = double(st.node_tests) / double(w.points.size()), r.primitive_tests = double(st.triangle_tests) / double(w.points.size());
    check_values(w, ck, r, w.distance, d);
    rows.push_back(r);
  }
  // refit last (it changes the tree): median of three refits to the deformed and back
  std::vector<double> ms;
  for (int k = 0; k < 3; ++k) {
    auto r0 = Clock::now();
    tree.set_vertices(k % 2 == 0 ? w.deformed : w.m.V);
    ms.push_back(seconds_since(r0) * 1e3);
  }
  const double refit = bench::summarize(ms).median;
  for (auto& r : rows)
    if (r.structure == structure && r.mesh == w.mesh) r.refit_ms = refit;
}

void run_kd(Work& w, std::vector<Row>& rows, Checker& ck) {
  const std::string structure = "kd-tree/sah";
  auto t0 = Clock::now();
  KdTree<double> kd(w.m);
  const double build_ms = seconds_since(t0) * 1e3;
  const double bpt = double(kd.memory_bytes()) / double(w.m.num_triangles());
  auto row = [&](const char* query) {
    Row r;
    r.mesh = w.mesh, r.structure = structure, r.bv = "none", r.builder = "kd-sah", r.query = query;
    r.build_ms = build_ms, r.bytes_per_triangle = bpt;
    return r;
  };
  ray_rows<KdTreeStats>(
      w, ck, rows, row, [&](const Ray<double>& ray, KdTreeStats* st) { return kd.first_hit(ray, st); },
      [](const KdTreeStats& st) { return std::make_pair(st.node_visits, st.triangle_tests); });
  Row r = row("closest_point");
  std::vector<double> d(w.points.size());
  KdTreeStats st;
  r.us = time_each(w.points.size(), [&](std::size_t k) { d[k] = kd.closest_point(w.points[k], &st)->distance; });
  r.bv_tests = double(st.node_visits) / double(w.points.size()), r.primitive_tests = double(st.triangle_tests) / double(w.points.size());
  check_values(w, ck, r, w.distance, d);
  rows.push_back(r);
}

}  // namespace

/// N copies of one tilted triangle, a third each in the vertex orders (a, b, c), (b, c, a), (a, c, b).
TriangleMesh<double> tilted_copies(int n) {
  TriangleMesh<double> m;
  m.V.resize(3, 3);
  m.V << 0, 0, 0, 1, 0, 0.4, 0, 1, 0.7;
  m.F.resize(n, 3);
  for (int k = 0; k < n; ++k) {
    if (k % 3 == 0) m.F.row(k) << 0, 1, 2;
    if (k % 3 == 1) m.F.row(k) << 1, 2, 0;
    if (k % 3 == 2) m.F.row(k) << 0, 2, 1;
  }
  return m;
}

/// The "copies-N" rows (--copies): build, ray casts through the copied triangle and closest points
/// near it, per structure; the first 8 answers of each against brute force.
void copies_rows(const Args& args, std::vector<Row>& rows, Checker& ck) {
  Work w;
  w.mesh = "copies-" + std::to_string(args.copies);
  w.m = tilted_copies(args.copies);
  impact::test::Rng rng(args.seed + 29);
  std::vector<Ray<double>> rays;
  std::vector<Vec3<double>> points;
  for (int k = 0; k < args.rays; ++k) {
    const double u = rng.uniform(0.05, 0.9), v = rng.uniform(0.05, 0.95) * (1 - u);
    const Vec3<double> target(u, v, 0.4 * u + 0.7 * v);
    const Vec3<double> o = target + Vec3<double>(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(0.2, 1));
    rays.emplace_back(o, target - o, 2.0);
    points.push_back(target + 0.05 * Vec3<double>(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)));
  }
  const std::size_t nb = std::min<std::size_t>(8, rays.size());
  std::vector<double> ref_t(nb), ref_d(nb);
  for (std::size_t k = 0; k < nb; ++k) ref_t[k] = brute_ray(w.m, rays[k]), ref_d[k] = brute_distance(w.m, points[k]);
  auto add = [&](const std::string& structure, const std::string& bv, const std::string& builder, double build_ms, double bpt, auto&& ray,
                 auto&& closest) {
    for (const char* query : {"copies_ray", "copies_closest"}) {
      Row r;
      r.mesh = w.mesh, r.structure = structure, r.bv = bv, r.builder = builder, r.query = query;
      r.build_ms = build_ms, r.bytes_per_triangle = bpt;
      std::size_t tests = 0;
      const bool is_ray = std::strcmp(query, "copies_ray") == 0;
      r.us = time_each(rays.size(), [&](std::size_t k) {
        const double got = is_ray ? ray(rays[k], tests) : closest(points[k], tests);
        if (k < nb && !same(got, is_ray ? ref_t[k] : ref_d[k])) ++r.mismatches, ck.report(w, structure, query, k, "differs from brute force");
      });
      r.primitive_tests = double(tests) / double(rays.size());
      rows.push_back(r);
    }
  };
  auto tree = [&](auto tag) {
    using BV = decltype(tag);
    const auto t0 = Clock::now();
    MeshBvhConfig one;
    one.build.threads = 1;
    const MeshBvh<BV> bvh(w.m, one);
    const double ms = seconds_since(t0) * 1e3;
    add(std::string(BvTraits<BV>::name) + "/middle", BvTraits<BV>::name, "middle", ms, double(bvh.tree_bytes()) / double(args.copies),
        [&](const Ray<double>& r, std::size_t& tests) {
          RayMeshStats st;
          const auto h = ray_mesh_first_hit(bvh, r, {}, &st);
          tests += st.triangle_tests;
          return h ? h->t : std::numeric_limits<double>::quiet_NaN();
        },
        [&](const Vec3<double>& p, std::size_t& tests) {
          ClosestPointStats st;
          const auto c = closest_point_on_mesh(bvh, p, {}, {}, &st);
          tests += st.triangle_tests;
          return c ? c->distance : std::numeric_limits<double>::infinity();
        });
  };
  tree(Sphere<double>());
  tree(Aabb<double>());
  tree(Obb<double>());
  const auto t0 = Clock::now();
  const KdTree<double> kd(w.m);
  const double ms = seconds_since(t0) * 1e3;
  add("kd-tree/sah", "none", "kd-sah", ms, double(kd.memory_bytes()) / double(args.copies),
      [&](const Ray<double>& r, std::size_t& tests) {
        KdTreeStats st;
        const auto h = kd.first_hit(r, &st);
        tests += st.triangle_tests;
        return h ? h->t : std::numeric_limits<double>::quiet_NaN();
      },
      [&](const Vec3<double>& p, std::size_t& tests) {
        KdTreeStats st;
        const auto c = kd.closest_point(p, &st);
        tests += st.triangle_tests;
        return c ? c->distance : std::numeric_limits<double>::infinity();
      });
}

int main(int argc, char** argv) {
  const Args args = parse(argc, argv);
  struct Input {
    std::string name;
    TriangleMesh<double> m;
    std::optional<TriangleMesh<double>> other;
  };
  std::vector<Input> meshes;
  try {
    if (args.meshes.empty()) meshes.push_back({"generated:torus", make_torus<double>(1.0, 0.35, 48, 24), std::nullopt});
    for (const auto& p : args.meshes) {
      const auto comma = p.find(',');
      if (comma == std::string::npos) {
        meshes.push_back({p, load(p), std::nullopt});
      } else {
        meshes.push_back({p, load(p.substr(0, comma)), load(p.substr(comma + 1))});
        validate_mesh(*meshes.back().other, p);
        bench::require_extent(*meshes.back().other, p);
      }
    }
    for (auto& mm : meshes) validate_mesh(mm.m, mm.name), bench::require_extent(mm.m, mm.name);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "impact-hierarchy-bench: %s\n", e.what());
    return 1;
  }
  std::vector<Row> rows;
  Checker ck;
  if (args.copies > 0) {
    copies_rows(args, rows, ck);
    std::printf("impact-hierarchy-bench: %s, %d rays and points (prim_tests: triangle tests per query)\n", rows.front().mesh.c_str(), args.rays);
    for (const Row& r : rows)
      std::printf("%-20s %-14s build %9.2f ms  median %11.3f us  mean %11.3f us  prim_tests %10.1f  mism %d\n", r.structure.c_str(),
                  r.query.c_str(), r.build_ms, r.us.median, r.us.mean, r.primitive_tests, r.mismatches);
  }
  for (auto& input : meshes) {
    const std::string& name = input.name;
    Work w = make_work(name, std::move(input.m), std::move(input.other), args);
    std::printf("impact-hierarchy-bench: %s (%d triangles), %d poses, %d rays of each kind and points, seed %llu\n", name.c_str(),
                w.m.num_triangles(), args.poses, args.rays, static_cast<unsigned long long>(args.seed));
    // brute-force answers for the first rays and points become the reference
    const std::size_t nb = std::min<std::size_t>(32, w.points.size());
    for (const char* q : {"ray_short", "ray_long"}) {
      const auto& rays = w.rays(q);
      std::vector<double> t(nb);
      for (std::size_t k = 0; k < nb; ++k) t[k] = brute_ray(w.m, rays[k]);
      w.ray_t[q] = t;
    }
    w.distance.resize(nb);
    for (std::size_t k = 0; k < nb; ++k) w.distance[k] = brute_distance(w.m, w.points[k]);
    // (the rest of the reference comes from the first structure that answers: check_values)
    const std::size_t first_row = rows.size();
    // one thread: the builders compare with each other (the parallel build has rows of its own)
    const auto one = [](MeshBvhConfig c) { c.build.threads = 1; return c; };
    const std::pair<const char*, MeshBvhConfig> builders[] = {
        {"middle", [&] { MeshBvhConfig c; c.build.split = SplitRule::SpatialMiddle; return one(c); }()},
        {"median", [&] { MeshBvhConfig c; c.build.split = SplitRule::CentroidMedian; return one(c); }()},
        {"sah", [&] { MeshBvhConfig c; c.build.split = SplitRule::Sah; return one(c); }()},
        {"bottom-up", [&] { MeshBvhConfig c; c.build.method = BuildMethod::BottomUp; return one(c); }()},
        {"incremental", [&] { MeshBvhConfig c; c.build.method = BuildMethod::Incremental; return one(c); }()},
    };
    for (const auto& [builder, cfg] : builders) run_bvh<Sphere<double>>(w, builder, cfg, rows, ck);
    for (const auto& [builder, cfg] : builders) run_bvh<Aabb<double>>(w, builder, cfg, rows, ck);
    for (const auto& [builder, cfg] : builders) run_bvh<Obb<double>>(w, builder, cfg, rows, ck);
    run_kd(w, rows, ck);
    const int threads = resolve_threads(args.threads);
    if (threads > 1) {
      build_threads_rows<Sphere<double>>(w, threads, rows, ck);
      build_threads_rows<Aabb<double>>(w, threads, rows, ck);
      build_threads_rows<Obb<double>>(w, threads, rows, ck);
    }

    std::printf("%-20s %-14s %9s %7s %9s %11s %11s %10s %10s %5s\n", "structure", "query", "build_ms", "B/tri", "refit_ms", "median_us",
                "mean_us", "bv_tests", "prim_tests", "mism");
    for (std::size_t i = first_row; i < rows.size(); ++i) {
      const Row& r = rows[i];
      std::printf("%-20s %-14s %9.2f %7.1f %9.3f %11.3f %11.3f %10.1f %10.1f %5d\n", r.structure.c_str(), r.query.c_str(), r.build_ms,
                  r.bytes_per_triangle, r.refit_ms, r.us.median, r.us.mean, r.bv_tests, r.primitive_tests, r.mismatches);
    }
  }
  if (!args.json.empty()) {
    std::vector<std::string> items;
    for (const Row& r : rows) {
      bench::JsonObject o;
      o.add("mesh", r.mesh).add("structure", r.structure).add("bv", r.bv).add("builder", r.builder).add("query", r.query);
      o.add("build_ms", r.build_ms).add("bytes_per_triangle", r.bytes_per_triangle).add("refit_ms", r.refit_ms);
      o.add("median_us", r.us.median).add("mean_us", r.us.mean).add("p99_us", r.us.p99).add("max_us", r.us.max);
      o.add("tests", r.bv_tests < 0 ? -1.0 : r.bv_tests + r.primitive_tests).add("bv_tests", r.bv_tests).add("primitive_tests", r.primitive_tests);
      o.add("mismatches", r.mismatches);
      items.push_back(o.str());
    }
    bench::JsonObject top;
    top.add("bench", "impact-hierarchy-bench").add("poses", args.poses).add("rays", args.rays).add("seed", static_cast<long long>(args.seed));
    top.raw("results", bench::JsonObject::array(items));
    if (!bench::write_file(args.json, top.str())) {
      std::fprintf(stderr, "impact-hierarchy-bench: cannot write %s\n", args.json.c_str());
      return 1;
    }
  }
  if (ck.mismatches > 0) {
    std::fprintf(stderr, "impact-hierarchy-bench: %d mismatches\n", ck.mismatches);
    return 3;
  }
  return 0;
}
