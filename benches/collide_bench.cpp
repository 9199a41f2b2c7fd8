// SPDX-License-Identifier: MIT
// impact-collide-bench: mesh–mesh collision of impact's sphere and AABB trees against FCL's
// OBBRSS and OBB trees, in one run, on the same meshes and the same random poses.
//
//   impact-collide-bench [MESH_A [MESH_B]] [--poses N] [--seed S] [--bv sphere|aabb|obb|all]
//                        [--split middle|median|sah|bottom-up|incremental] [--leaf N] [--repeat K] [--rounds K]
//                        [--json FILE]
//
// Mesh B defaults to mesh A; without meshes a built-in generated scene is used (a torus against an
// icosphere). impact's trees are built with the SAH split unless --split says otherwise (the
// SAH-built OBB tree is the best impact structure on every scene measured, docs/collide.md). Poses come from tests/support/poses.hpp: A stays at the origin, B gets a uniformly
// random rotation and a translation uniform in A's bounding box grown by B's bounding radius. For each method it prints build time, median and mean query time,
// colliding poses, mismatches against FCL OBBRSS (boolean answers, or pair sets in all-pairs mode),
// mean BV and triangle tests, and the speed ratio FCL OBBRSS / method. Timed per query: impact's
// collides / collide (poses as arguments); FCL's fcl::collide on the two geometries with their
// transforms (converted to fcl::Transform3d before timing). With --repeat K each query runs K
// times on its pose and the least time is kept (the same for both libraries); with --rounds K
// the whole pass over the poses runs K times and each pose keeps its least time (each query
// still cold, but a query preempted in one round is timed again in the next). Exits with status 3 when any answer
// differs from FCL OBBRSS.
#include "bench_util.hpp"
#include "impact/bvh/mesh_bvh.hpp"
#include "impact/geometry/mesh_generators.hpp"
#include "impact/query/mesh_collide.hpp"
#include "support/fcl_oracle.hpp"
#include "support/poses.hpp"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <set>
#include <vector>

using namespace impact;
using impact::bench::Clock;
using impact::bench::seconds_since;

namespace {

struct Args {
  std::string mesh_a, mesh_b, json, bv = "all", split = "sah";
  int poses = 1000, leaf = 1, repeat = 1, rounds = 1;
  std::uint64_t seed = 1;
};

constexpr const char* kUsage =
    "usage: impact-collide-bench [MESH_A [MESH_B]] [--poses N] [--seed S] [--bv sphere|aabb|obb|all]\n"
    "                            [--split middle|median|sah|bottom-up|incremental] [--leaf N] [--repeat K] [--rounds K] [--json FILE]\n"
    "  --split R   how impact's trees are built (default sah: the best impact structure, the SAH-built OBB tree, in the\n"
    "              default run; middle is the default split of sphere and AABB trees, SAH that of OBB trees)\n"
    "  --repeat K  time each query K times on its pose and keep the least (default 1: one cold query per pose)\n"
    "  --rounds K  pass over all the poses K times and keep each pose's least time (cold queries, preemption filtered)\n";

[[noreturn]] void usage(const char* msg) { bench::exit_usage(msg, kUsage); }

Args parse(int argc, char** argv) {
  Args a;
  std::vector<std::string> pos;
  for (int i = 1; i < argc; ++i) {
    const std::string s = argv[i];
    auto next = [&] { return bench::option_value(argc, argv, i, kUsage); };
    if (s == "--poses") a.poses = int(bench::parse_integer(s, next(), 1, 10000000, kUsage));
    else if (s == "--seed") a.seed = bench::parse_seed(s, next(), kUsage);
    else if (s == "--bv") a.bv = next();
    else if (s == "--json") a.json = next();
    else if (s == "--split") a.split = next();
    else if (s == "--leaf") a.leaf = int(bench::parse_integer(s, next(), 1, 1024, kUsage));
    else if (s == "--repeat") a.repeat = int(bench::parse_integer(s, next(), 1, 1000, kUsage));
    else if (s == "--rounds") a.rounds = int(bench::parse_integer(s, next(), 1, 1000, kUsage));
    else if (!s.empty() && s[0] == '-') bench::reject_option(s, kUsage);
    else pos.push_back(s);
  }
  if (pos.size() > 2) usage("at most two meshes");
  if (a.bv != "sphere" && a.bv != "aabb" && a.bv != "obb" && a.bv != "all") usage("--bv must be sphere, aabb, obb or all");
  if (a.split != "middle" && a.split != "median" && a.split != "sah" && a.split != "bottom-up" && a.split != "incremental")
    usage("--split must be middle, median, sah, bottom-up or incremental");
  bench::check_writable(a.json, kUsage);
  if (!pos.empty()) a.mesh_a = pos[0];
  a.mesh_b = pos.size() > 1 ? pos[1] : a.mesh_a;
  return a;
}

TriangleMesh<double> load(const std::string& path) { return bench::load_mesh_or_exit(path, kUsage); }

/// A query's time on its pose, in µs: `query()` run `repeat` times, the least kept. One sub-µs query
/// timed once is mostly what the machine did meanwhile; the least of K is its own cost (warm: the
/// second run finds the first one's nodes in cache). Both libraries are timed the same way.
template <class Query> double least_us(int repeat, Query&& query) {
  double best = 0;
  for (int r = 0; r < repeat; ++r) {
    const auto q0 = Clock::now();
    query();
    const double us = seconds_since(q0) * 1e6;
    best = r == 0 ? us : std::min(best, us);
  }
  return best;
}

/// Records one pose's boolean and all-pairs times for round `round` of --rounds: the first round
/// appends them (and returns true: the pose's answers are counted then), later rounds only lower
/// them. Both libraries go through it.
bool record_times(int round, std::size_t pose, double us_boolean, double us_all, std::vector<double>& tb, std::vector<double>& ta) {
  if (round > 0) {
    tb[pose] = std::min(tb[pose], us_boolean);
    ta[pose] = std::min(ta[pose], us_all);
    return false;
  }
  tb.push_back(us_boolean);
  ta.push_back(us_all);
  return true;
}

struct Row {
  std::string library, bv, query;
  double build_ms = 0;
  bench::Summary us;
  int colliding = 0, mismatches = 0;
  double bv_tests = -1, tri_tests = -1;
  double ratio = 0;  // FCL OBBRSS median / this median
  double tree_bytes_per_tri = -1;  // impact: MeshBvh::tree_bytes() per triangle, beyond the mesh's V and F
};

}  // namespace

int main(int argc, char** argv) {
  const Args args = parse(argc, argv);
  TriangleMesh<double> A, B;
  std::string name_a = args.mesh_a.empty() ? "generated:torus" : args.mesh_a;
  std::string name_b = args.mesh_a.empty() ? "generated:icosphere" : args.mesh_b;
  try {
    if (args.mesh_a.empty()) {
      A = make_torus<double>(1.0, 0.35, 160, 64);
      B = make_icosphere<double>(0.6, 5);
    } else {
      A = load(args.mesh_a);
      B = args.mesh_b == args.mesh_a ? A : load(args.mesh_b);
    }
    validate_mesh(A, name_a);
    validate_mesh(B, name_b);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "impact-collide-bench: %s\n", e.what());
    return 1;
  }

  const std::vector<RigidTransform<double>> poses = impact::test::random_poses_around(A, B, args.poses, args.seed);
  const RigidTransform<double> id;
  std::printf("impact-collide-bench: A=%s (%d tris), B=%s (%d tris), %d poses, seed %llu, %s\n", name_a.c_str(), A.num_triangles(),
              name_b.c_str(), B.num_triangles(), args.poses, static_cast<unsigned long long>(args.seed),
              (args.repeat == 1 ? std::string("one cold query per pose") : "the least of " + std::to_string(args.repeat) + " runs per pose")
                  .append(args.rounds == 1 ? "" : ", the least over " + std::to_string(args.rounds) + " rounds over all poses")
                  .c_str());

  std::vector<Row> rows;
  std::vector<char> ref_bool(poses.size());
  std::vector<std::set<std::pair<int, int>>> ref_pairs(poses.size());
  double ref_bool_median = 0, ref_all_median = 0;

  // FCL: OBBRSS is the reference, OBB a second peer.
  auto run_fcl = [&](auto tag, const char* bvname, bool reference) {
    using FBV = decltype(tag);
    auto t0 = Clock::now();
    auto fa = impact::test::make_fcl_model<FBV>(A);
    auto fb = impact::test::make_fcl_model<FBV>(B);
    const double build_ms = seconds_since(t0) * 1e3;
    Row rb_{"fcl", bvname, "boolean", build_ms, {}, 0, 0, -1, -1, 0};
    Row ra_{"fcl", bvname, "all_pairs", build_ms, {}, 0, 0, -1, -1, 0};
    std::vector<double> tb, ta;
    // As FCL's own tests call it for a mesh pair whose poses change: fcl::collide on the two
    // geometries with their transforms (the CollisionObject overload only adds a wrapper; its world
    // AABB, set by computeAABB, is read by FCL's broad phase, never by collide). The transforms are
    // converted before timing, as impact's poses are; the request is made once.
    std::vector<fcl::Transform3d> tf(poses.size());
    for (std::size_t k = 0; k < poses.size(); ++k) tf[k] = impact::test::to_fcl(poses[k]);
    const fcl::Transform3d tf_id = fcl::Transform3d::Identity();
    const fcl::CollisionRequestd boolean_req;
    const fcl::CollisionRequestd all_req(100000000, false);
    for (int round = 0; round < args.rounds; ++round)
    for (std::size_t k = 0; k < poses.size(); ++k) {
      // a fresh result for every run, made outside the timed call
      std::vector<fcl::CollisionResultd> res_b(std::size_t(args.repeat)), res_a(std::size_t(args.repeat));
      int run = 0;
      const double us_b = least_us(args.repeat, [&] { fcl::collide(fa.get(), tf_id, fb.get(), tf[k], boolean_req, res_b[std::size_t(run++)]); });
      const bool hit = res_b[0].isCollision();
      run = 0;
      const double us_a = least_us(args.repeat, [&] { fcl::collide(fa.get(), tf_id, fb.get(), tf[k], all_req, res_a[std::size_t(run++)]); });
      if (!record_times(round, k, us_b, us_a, tb, ta)) continue;  // later rounds only lower the times
      std::set<std::pair<int, int>> ps;
      for (std::size_t c = 0; c < res_a[0].numContacts(); ++c) ps.emplace(res_a[0].getContact(c).b1, res_a[0].getContact(c).b2);
      rb_.colliding += hit;
      ra_.colliding += !ps.empty();
      if (reference) {
        ref_bool[k] = hit;
        ref_pairs[k] = ps;
      } else {
        rb_.mismatches += hit != bool(ref_bool[k]);
        ra_.mismatches += ps != ref_pairs[k];
      }
    }
    rb_.us = bench::summarize(tb);
    ra_.us = bench::summarize(ta);
    if (reference) ref_bool_median = rb_.us.median, ref_all_median = ra_.us.median;
    rows.push_back(rb_);
    rows.push_back(ra_);
  };
  run_fcl(fcl::OBBRSS<double>{}, "obbrss", true);
  run_fcl(fcl::OBB<double>{}, "obb", false);

  auto run_impact = [&](auto tag, const char* bvname) {
    using BV = decltype(tag);
    MeshBvhConfig cfg;
    cfg.build.threads = 1;  // FCL builds on one thread: the build times compare like for like
    cfg.build.leaf_size = args.leaf;
    cfg.build.split = args.split == "median" ? SplitRule::CentroidMedian : args.split == "sah" ? SplitRule::Sah : SplitRule::SpatialMiddle;
    if (args.split == "bottom-up") cfg.build.method = BuildMethod::BottomUp;
    if (args.split == "incremental") cfg.build.method = BuildMethod::Incremental;
    auto t0 = Clock::now();
    MeshBvh<BV> ma(A, cfg);
    MeshBvh<BV> mb(B, cfg);
    const double build_ms = seconds_since(t0) * 1e3;
    Row rb_{"impact", bvname, "boolean", build_ms, {}, 0, 0, 0, 0, 0};
    Row ra_{"impact", bvname, "all_pairs", build_ms, {}, 0, 0, 0, 0, 0};
    rb_.tree_bytes_per_tri = ra_.tree_bytes_per_tri =
        double(ma.tree_bytes() + mb.tree_bytes()) / double(ma.num_triangles() + mb.num_triangles());
    std::vector<double> tb, ta;
    CollideOptions all;
    all.all_pairs = true;
    for (int round = 0; round < args.rounds; ++round)
    for (std::size_t k = 0; k < poses.size(); ++k) {
      QueryStats st;
      bool hit = false;
      const double us_b = least_us(args.repeat, [&] { hit = collides(ma, id, mb, poses[k], &st); });
      CollideResult<double> res;
      const double us_a = least_us(args.repeat, [&] { res = collide(ma, id, mb, poses[k], all); });
      if (!record_times(round, k, us_b, us_a, tb, ta)) continue;  // later rounds only lower the times
      rb_.bv_tests += double(st.bv_tests);
      rb_.tri_tests += double(st.primitive_tests);
      ra_.bv_tests += double(res.stats.bv_tests);
      ra_.tri_tests += double(res.stats.primitive_tests);
      std::set<std::pair<int, int>> ps(res.pairs.begin(), res.pairs.end());
      rb_.colliding += hit;
      ra_.colliding += !ps.empty();
      rb_.mismatches += hit != bool(ref_bool[k]);
      ra_.mismatches += ps != ref_pairs[k];
    }
    for (Row* r : {&rb_, &ra_}) {
      r->bv_tests /= double(poses.size());
      r->tri_tests /= double(poses.size());
    }
    rb_.us = bench::summarize(tb);
    ra_.us = bench::summarize(ta);
    rows.push_back(rb_);
    rows.push_back(ra_);
  };
  if (args.bv == "sphere" || args.bv == "all") run_impact(Sphere<double>{}, "sphere");
  if (args.bv == "aabb" || args.bv == "all") run_impact(Aabb<double>{}, "aabb");
  if (args.bv == "obb" || args.bv == "all") run_impact(Obb<double>{}, "obb");

  for (Row& r : rows) r.ratio = (r.query == "boolean" ? ref_bool_median : ref_all_median) / std::max(r.us.median, 1e-9);

  std::printf("\n%-7s %-7s %-10s %10s %11s %11s %9s %10s %12s %12s %13s\n", "library", "bv", "query", "build_ms", "median_us",
              "mean_us", "colliding", "mismatch", "bv_tests", "tri_tests", "fcl/this(med)");
  for (const Row& r : rows) {
    char bvt[32] = "-", trt[32] = "-";
    if (r.bv_tests >= 0) std::snprintf(bvt, sizeof bvt, "%.1f", r.bv_tests);
    if (r.tri_tests >= 0) std::snprintf(trt, sizeof trt, "%.1f", r.tri_tests);
    std::printf("%-7s %-7s %-10s %10.2f %11.2f %11.2f %9d %10d %12s %12s %13.2f\n", r.library.c_str(), r.bv.c_str(), r.query.c_str(),
                r.build_ms, r.us.median, r.us.mean, r.colliding, r.mismatches, bvt, trt, r.ratio);
  }
  for (const Row& r : rows)
    if (r.tree_bytes_per_tri >= 0 && r.query == "boolean")
      std::printf("memory: impact %s tree %.1f bytes per triangle beyond the mesh (nodes, permutation, triangle ids)\n", r.bv.c_str(),
                  r.tree_bytes_per_tri);
  std::printf("\nmismatches: boolean answers (or all-pairs pair sets) that differ from FCL OBBRSS on the same pose.\n");

  // impact's answers against FCL OBBRSS (FCL's OBB row is printed, as a check of the peer, but is
  // not impact's answer).
  int total_mismatch = 0;
  for (const Row& r : rows)
    if (r.library == "impact") total_mismatch += r.mismatches;

  if (!args.json.empty()) {
    std::vector<std::string> items;
    for (const Row& r : rows) {
      bench::JsonObject o;
      o.add("library", r.library).add("bv", r.bv).add("query", r.query).add("build_ms", r.build_ms).add("median_us", r.us.median);
      o.add("mean_us", r.us.mean).add("p99_us", r.us.p99).add("max_us", r.us.max).add("colliding", r.colliding).add("mismatches", r.mismatches);
      if (r.bv_tests >= 0) o.add("bv_tests_mean", r.bv_tests).add("tri_tests_mean", r.tri_tests);
      if (r.tree_bytes_per_tri >= 0) o.add("tree_bytes_per_triangle", r.tree_bytes_per_tri);
      o.add("speedup_vs_fcl_obbrss", r.ratio);
      items.push_back(o.str());
    }
    bench::JsonObject top;
    top.add("mesh_a", name_a).add("mesh_b", name_b).add("poses", args.poses).add("seed", static_cast<long long>(args.seed));
    top.add("split", args.split).add("leaf_size", args.leaf).add("repeat", args.repeat).add("rounds", args.rounds).raw("results", bench::JsonObject::array(items));
    if (!bench::write_file(args.json, top.str())) {
      std::fprintf(stderr, "impact-collide-bench: cannot write %s\n", args.json.c_str());
      return 1;
    }
  }
  if (total_mismatch) {
    std::fprintf(stderr, "impact-collide-bench: %d impact answers differ from FCL OBBRSS (see the mismatch column)\n", total_mismatch);
    return 3;
  }
  return 0;
}
