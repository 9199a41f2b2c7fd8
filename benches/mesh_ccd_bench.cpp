// SPDX-License-Identifier: MIT
// impact-mesh-ccd-bench: mesh-level CCD (mesh_ccd, mesh_self_ccd) over the steps of two moving
// scenes, on one thread and on T, checked against an independent oracle.
//
//   impact-mesh-ccd-bench [MESH] [--steps S] [--threads T] [--check-steps C] [--json FILE]
//
// Without MESH the mesh is a generated torus (20,480 triangles). Scenes, each S steps:
//   pair  a second copy of the mesh, turned, starts above the first and sinks into it (0.01 of the
//         diagonal and 0.02 rad a step): mesh_ccd of the two;
//   self  the mesh deforms by a travelling wave (16 waves across the diagonal, vertices displaced
//         up to 0.012 of it, about 0.005 more each step; the surface folds): mesh_self_ccd.
// Per step the swept trees are refitted (built once) and each query runs on one thread (the
// calling thread's CPU time) and on T threads (wall clock, CPU of the calling thread and of the
// process). The T-thread answer must equal the one-thread answer (contacts in the same order,
// toi, counters): "differing" counts the steps where it does not. The first C steps (default 1)
// are also checked against an oracle that shares nothing with the tree: a sweep along x over
// the swept boxes of every vertex, face and edge (grown by half the minimum separation), running
// the same primitive test on every primitive pair whose boxes overlap (self: skipping a vertex of
// the face and edges that share a vertex). "missed" counts oracle hits the query did not report;
// "extra" the query's hits on a pair whose boxes overlap that the oracle found no hit for (a hit
// on a pair with disjoint boxes can only be a near miss within the tolerance, and is not counted).
// Speed-ups by the wall clock and by the CPU times (bench_util.hpp, cpu_speedup), as the other
// benches give them on a shared machine. Exit status 3 when anything differs or is missed.
#include "bench_util.hpp"
#include "impact/ccd/mesh_ccd.hpp"
#include "impact/core/parallel.hpp"
#include "impact/geometry/mesh_generators.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <map>
#include <numeric>
#include <string>
#include <tuple>
#include <vector>

namespace {

using namespace impact;
using bench::Clock;

const char* kUsage =
    "usage: impact-mesh-ccd-bench [MESH] [--steps S] [--threads T] [--check-steps C] [--json FILE]\n"
    "  MESH             any file impact::io loads (default: a generated torus of 20,480 triangles)\n"
    "  --steps S        steps of each scene (default 20)\n"
    "  --threads T      threads of the parallel runs (default 0: the hardware concurrency)\n"
    "  --check-steps C  steps checked against the sweep oracle (default 1)\n";

struct Args {
  std::string mesh, json;
  int steps = 20, threads = 0, check_steps = 1;
};

Args parse(int argc, char** argv) {
  Args a;
  for (int i = 1; i < argc; ++i) {
    const std::string s = argv[i];
    if (s == "--steps")
      a.steps = int(bench::parse_integer(s, bench::option_value(argc, argv, i, kUsage), 1, 100000, kUsage));
    else if (s == "--threads")
      a.threads = int(bench::parse_integer(s, bench::option_value(argc, argv, i, kUsage), 0, 1024, kUsage));
    else if (s == "--check-steps")
      a.check_steps = int(bench::parse_integer(s, bench::option_value(argc, argv, i, kUsage), 0, 100000, kUsage));
    else if (s == "--json")
      a.json = bench::option_value(argc, argv, i, kUsage);
    else if (!s.empty() && s[0] == '-')
      bench::reject_option(s, kUsage);
    else if (a.mesh.empty())
      a.mesh = s;
    else
      bench::exit_usage("more than one mesh given", kUsage);
  }
  bench::check_writable(a.json, kUsage);
  return a;
}

// ---- the oracle: a sweep along x over primitive boxes ---------------------------------------

/// Calls f(i, j) for every i of `a` and j of `b` whose boxes overlap (closed boxes), each pair once.
template <class F>
void sweep_pairs(const std::vector<Aabb<double>>& a, const std::vector<Aabb<double>>& b, F&& f) {
  std::vector<int> ia(a.size()), ib(b.size());
  std::iota(ia.begin(), ia.end(), 0);
  std::iota(ib.begin(), ib.end(), 0);
  std::sort(ia.begin(), ia.end(), [&](int x, int y) { return a[std::size_t(x)].min.x() < a[std::size_t(y)].min.x(); });
  std::sort(ib.begin(), ib.end(), [&](int x, int y) { return b[std::size_t(x)].min.x() < b[std::size_t(y)].min.x(); });
  // pairs with a.min.x <= b.min.x: scan b from the first with min.x >= a.min.x; the others from a
  std::size_t start = 0;
  for (const int i : ia) {
    const Aabb<double>& x = a[std::size_t(i)];
    while (start < ib.size() && b[std::size_t(ib[start])].min.x() < x.min.x()) ++start;
    for (std::size_t k = start; k < ib.size() && b[std::size_t(ib[k])].min.x() <= x.max.x(); ++k)
      if (overlap(x, b[std::size_t(ib[k])])) f(i, ib[k]);
  }
  start = 0;
  for (const int j : ib) {
    const Aabb<double>& y = b[std::size_t(j)];
    while (start < ia.size() && a[std::size_t(ia[start])].min.x() <= y.min.x()) ++start;
    for (std::size_t k = start; k < ia.size() && a[std::size_t(ia[k])].min.x() <= y.max.x(); ++k)
      if (overlap(a[std::size_t(ia[k])], y)) f(ia[k], j);
  }
}

Aabb<double> swept_box(const MeshMotion<double>& m, std::initializer_list<int> verts, double grow) {
  Aabb<double> box;
  for (const int v : verts) {
    box.extend(m.p0(v));
    box.extend(m.p1(v));
  }
  return {box.min.array() - grow, box.max.array() + grow};
}

std::vector<std::array<int, 2>> edges_of(const Faces& F) {
  std::vector<std::array<int, 2>> e;
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      int a = F(f, k), b = F(f, (k + 1) % 3);
      if (a > b) std::swap(a, b);
      e.push_back({a, b});
    }
  std::sort(e.begin(), e.end());
  e.erase(std::unique(e.begin(), e.end()), e.end());
  return e;
}

/// A contact's identity: (kind, mesh, ids...).
using Key = std::array<std::int32_t, 5>;
Key key_of(const MeshCcdContact<double>& c) {
  if (c.kind == MeshCcdKind::VertexFace) return {0, c.vertex_mesh, c.vertex, c.face, -1};
  return {1, c.a0, c.a1, c.b0, c.b1};
}

struct OracleCheck {
  std::size_t missed = 0, extra = 0, hits = 0, tests = 0;
  OracleCheck& operator+=(const OracleCheck& o) {
    missed += o.missed, extra += o.extra, hits += o.hits, tests += o.tests;
    return *this;
  }
};

/// Compares a query's contacts with the sweep oracle's (see the file comment). `b` is null for
/// self CCD.
OracleCheck check_against_oracle(const MeshMotion<double>& a, const MeshMotion<double>* b, const CcdOptions& opt,
                                 const MeshCcdResult<double>& got) {
  const bool self = b == nullptr;
  const MeshMotion<double>& mb = self ? a : *b;
  const double g = opt.min_separation / 2;
  std::vector<Key> oracle;       // hits
  std::vector<Key> overlapping;  // every tested pair
  OracleCheck out;
  const auto vertex_boxes = [&](const MeshMotion<double>& m) {
    std::vector<Aabb<double>> v(std::size_t(m.start->rows()));
    for (std::size_t i = 0; i < v.size(); ++i) v[i] = swept_box(m, {int(i)}, g);
    return v;
  };
  const auto face_boxes = [&](const MeshMotion<double>& m) {
    const Faces& F = *m.faces;
    std::vector<Aabb<double>> f(std::size_t(F.rows()));
    for (std::size_t i = 0; i < f.size(); ++i) f[i] = swept_box(m, {F(Eigen::Index(i), 0), F(Eigen::Index(i), 1), F(Eigen::Index(i), 2)}, g);
    return f;
  };
  const auto vf = [&](int mesh, const MeshMotion<double>& mv, const MeshMotion<double>& mf) {
    const std::vector<Aabb<double>> vb = vertex_boxes(mv), fb = face_boxes(mf);
    const Faces& F = *mf.faces;
    sweep_pairs(vb, fb, [&](int v, int f) {
      if (self && (F(f, 0) == v || F(f, 1) == v || F(f, 2) == v)) return;
      const Key k{0, mesh, v, f, -1};
      overlapping.push_back(k);
      ++out.tests;
      const auto r = vertex_face_ccd(mv.p0(v), mf.p0(F(f, 0)), mf.p0(F(f, 1)), mf.p0(F(f, 2)), mv.p1(v), mf.p1(F(f, 0)),
                                     mf.p1(F(f, 1)), mf.p1(F(f, 2)), opt);
      if (r.hit) oracle.push_back(k);
    });
  };
  vf(0, a, mb);
  if (!self) vf(1, mb, a);
  const std::vector<std::array<int, 2>> ea = edges_of(*a.faces), eb = self ? ea : edges_of(*mb.faces);
  std::vector<Aabb<double>> ba(ea.size()), bb(eb.size());
  for (std::size_t i = 0; i < ea.size(); ++i) ba[i] = swept_box(a, {ea[i][0], ea[i][1]}, g);
  for (std::size_t i = 0; i < eb.size(); ++i) bb[i] = swept_box(mb, {eb[i][0], eb[i][1]}, g);
  sweep_pairs(ba, bb, [&](int i, int j) {
    std::array<int, 2> x = ea[std::size_t(i)], y = eb[std::size_t(j)];
    if (self) {
      if (i >= j) return;  // each unordered pair once (the sweep gives both orders)
      if (x[0] == y[0] || x[0] == y[1] || x[1] == y[0] || x[1] == y[1]) return;
    }
    const Key k{1, x[0], x[1], y[0], y[1]};
    overlapping.push_back(k);
    ++out.tests;
    const auto r = edge_edge_ccd(a.p0(x[0]), a.p0(x[1]), mb.p0(y[0]), mb.p0(y[1]), a.p1(x[0]), a.p1(x[1]), mb.p1(y[0]), mb.p1(y[1]), opt);
    if (r.hit) oracle.push_back(k);
  });
  std::vector<Key> reported;
  for (const auto& c : got.contacts) reported.push_back(key_of(c));
  for (std::vector<Key>* v : {&oracle, &overlapping, &reported}) {
    std::sort(v->begin(), v->end());
    v->erase(std::unique(v->begin(), v->end()), v->end());
  }
  const auto has = [](const std::vector<Key>& v, const Key& k) { return std::binary_search(v.begin(), v.end(), k); };
  for (const Key& k : oracle) out.missed += !has(reported, k);
  for (const Key& k : reported) out.extra += has(overlapping, k) && !has(oracle, k);
  out.hits = oracle.size();
  return out;
}

bool same_result(const MeshCcdResult<double>& x, const MeshCcdResult<double>& y) {
  if (x.hit != y.hit || x.toi != y.toi || x.triangle_pairs != y.triangle_pairs || x.primitive_tests != y.primitive_tests ||
      x.contacts.size() != y.contacts.size())
    return false;
  for (std::size_t k = 0; k < x.contacts.size(); ++k)
    if (key_of(x.contacts[k]) != key_of(y.contacts[k]) || x.contacts[k].result.toi != y.contacts[k].result.toi) return false;
  return true;
}

// ---- scenes --------------------------------------------------------------------------------

struct Row {
  std::string scene;
  int steps = 0;
  double triangle_pairs = 0, primitive_tests = 0, contacts = 0;  // per step
  double refit_ms = 0, one_ms = 0, wall_ms = 0, caller_ms = 0, process_ms = 0;  // per step
  int differing = 0;
  OracleCheck oracle;
  int checked = 0;
};

/// Runs `query(threads)` for one step on one thread and on T, accumulating into r.
template <class Q>
MeshCcdResult<double> time_step(Q&& query, int threads, Row& r) {
  double t0 = bench::thread_seconds();
  MeshCcdResult<double> one = query(1);
  r.one_ms += (bench::thread_seconds() - t0) * 1e3;
  t0 = bench::thread_seconds();
  const double p0 = bench::process_seconds();
  const auto w0 = Clock::now();
  const MeshCcdResult<double> many = query(threads);
  r.wall_ms += bench::seconds_since(w0) * 1e3;
  r.caller_ms += (bench::thread_seconds() - t0) * 1e3;
  r.process_ms += (bench::process_seconds() - p0) * 1e3;
  r.differing += !same_result(one, many);
  r.triangle_pairs += double(one.triangle_pairs);
  r.primitive_tests += double(one.primitive_tests);
  r.contacts += double(one.contacts.size());
  return one;
}

void finish(Row& r) {
  for (double* v : {&r.triangle_pairs, &r.primitive_tests, &r.contacts, &r.refit_ms, &r.one_ms, &r.wall_ms, &r.caller_ms, &r.process_ms})
    *v /= double(r.steps);
}

Aabb<double> bounds_of(const TriangleMesh<double>& mesh) {
  Aabb<double> box;
  for (Eigen::Index i = 0; i < mesh.V.rows(); ++i) box.extend(Vec3<double>(mesh.V.row(i).transpose()));
  return box;
}

/// The step loop of both scenes. The moving mesh has `mesh`'s faces and, at the boundary of
/// steps s - 1 and s, the vertices `place(s, out)` writes. Its swept tree is built once and
/// refitted (timed) every step; `query(motion, tree, threads)` runs on one thread and on T
/// (time_step), and over the first C steps `check(motion, result)` compares it with the oracle.
template <class Place, class Query, class Check>
Row run_scene(const char* name, const TriangleMesh<double>& mesh, const Args& args, int threads, const CcdOptions& opt,
              Place&& place, Query&& query, Check&& check) {
  Row r;
  r.scene = name;
  r.steps = args.steps;
  Vertices<double> x0, x1;
  place(0, x0);
  place(1, x1);
  MeshMotion<double> m = make_mesh_motion(x0, x1, mesh.F);
  SweptMeshBvh<double> tree = SweptMeshBvh<double>::build(m, opt.min_separation);
  for (int s = 0; s < args.steps; ++s) {
    if (s > 0) {
      x0 = x1;
      place(s + 1, x1);
      m = make_mesh_motion(x0, x1, mesh.F);
      const double t0 = bench::thread_seconds();
      tree.refit(m);
      r.refit_ms += (bench::thread_seconds() - t0) * 1e3;
    }
    const MeshCcdResult<double> res = time_step([&](int t) { return query(m, tree, t); }, threads, r);
    if (s < args.check_steps) {
      r.oracle += check(m, res);
      ++r.checked;
    }
  }
  finish(r);
  return r;
}

/// pair: the mesh at rest against a turned copy sinking into it (mesh_ccd).
Row run_pair(const TriangleMesh<double>& mesh, const Args& args, int threads, const CcdOptions& opt) {
  const Aabb<double> box = bounds_of(mesh);
  const double diag = (box.max - box.min).norm();
  const Vec3<double> c = box.center();
  const Eigen::Matrix3d turn = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  // B's vertices at step s: turned about the centre by 0.02 s more about z, lifted by (0.12 - 0.01 s) diag
  const auto place = [&](int s, Vertices<double>& out) {
    const Eigen::Matrix3d R = Eigen::AngleAxisd(0.02 * s, Eigen::Vector3d::UnitZ()).toRotationMatrix() * turn;
    const Vec3<double> lift(0, (0.12 - 0.01 * s) * diag, 0);
    out.resize(mesh.V.rows(), 3);
    for (Eigen::Index i = 0; i < mesh.V.rows(); ++i) out.row(i) = (R * (mesh.V.row(i).transpose() - c) + c + lift).transpose();
  };
  const MeshMotion<double> ma = make_mesh_motion(mesh.V, mesh.V, mesh.F);
  const SweptMeshBvh<double> ta = SweptMeshBvh<double>::build(ma, opt.min_separation);
  return run_scene(
      "pair", mesh, args, threads, opt, place,
      [&](const MeshMotion<double>& mb, const SweptMeshBvh<double>& tb, int t) { return mesh_ccd(ma, ta, mb, tb, opt, t); },
      [&](const MeshMotion<double>& mb, const MeshCcdResult<double>& res) { return check_against_oracle(ma, &mb, opt, res); });
}

/// self: the mesh folding under a travelling wave (mesh_self_ccd).
Row run_self(const TriangleMesh<double>& mesh, const Args& args, int threads, const CcdOptions& opt) {
  const Aabb<double> box = bounds_of(mesh);
  const double diag = (box.max - box.min).norm();
  const double k = 2 * 3.14159265358979 * 16 / diag;  // 16 waves across the diagonal: folds where amplitude * k > 1
  const auto shape = [&](int s, Vertices<double>& out) {
    out.resize(mesh.V.rows(), 3);
    for (Eigen::Index i = 0; i < mesh.V.rows(); ++i) {
      const Vec3<double> p = mesh.V.row(i).transpose();
      const double ph = 0.4 * s;
      const Vec3<double> d(std::sin(k * p.y() + ph), std::sin(k * p.z() + 1.3 * ph), std::sin(k * p.x() + 0.7 * ph));
      out.row(i) = (p + 0.012 * diag * d).transpose();
    }
  };
  return run_scene(
      "self", mesh, args, threads, opt, shape,
      [&](const MeshMotion<double>& m, const SweptMeshBvh<double>& t, int th) { return mesh_self_ccd(m, t, opt, th); },
      [&](const MeshMotion<double>& m, const MeshCcdResult<double>& res) { return check_against_oracle(m, nullptr, opt, res); });
}

}  // namespace

int main(int argc, char** argv) {
  const Args args = parse(argc, argv);
  TriangleMesh<double> mesh;
  try {
    mesh = args.mesh.empty() ? make_torus<double>(1.0, 0.35, 160, 64) : bench::load_mesh_or_exit(args.mesh, kUsage);
    validate_mesh(mesh, args.mesh.empty() ? "generated torus" : args.mesh);
    bench::require_extent(mesh, args.mesh.empty() ? "generated torus" : args.mesh);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "impact-mesh-ccd-bench: %s\n", e.what());
    return 1;
  }
  const int threads = resolve_threads(args.threads);
  const CcdOptions opt;  // the defaults: tolerance 1e-6, minimum separation 0
  std::printf("impact-mesh-ccd-bench: %s (%d triangles, %d vertices), %d steps, %d threads\n",
              args.mesh.empty() ? "generated torus" : args.mesh.c_str(), mesh.num_triangles(), int(mesh.V.rows()), args.steps, threads);
  std::vector<Row> rows;
  try {
    rows.push_back(run_pair(mesh, args, threads, opt));
    rows.push_back(run_self(mesh, args, threads, opt));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "impact-mesh-ccd-bench: %s\n", e.what());
    return 1;
  }
  std::printf("\nper step: triangle pairs, primitive tests, contacts; ms (1 thread: CPU time; %d threads: wall clock, CPU of the\n"
              "calling thread, CPU of the process); speed-up by the wall clock and by the CPU times; oracle over the first %d step(s)\n",
              threads, args.check_steps);
  std::printf("%-6s %10s %11s %9s %9s %10s %9s %9s %9s %7s %7s %9s %12s %7s %6s\n", "scene", "tri pairs", "prim tests", "contacts",
              "refit ms", "1 thread", "wall", "caller", "process", "wall x", "cpu x", "differing", "oracle hits", "missed", "extra");
  bool bad = false;
  std::vector<std::string> json_rows;
  for (const Row& r : rows) {
    const double cpu_x = bench::cpu_speedup(r.one_ms, r.caller_ms, r.process_ms, threads);
    const double wall_x = r.one_ms / std::max(r.wall_ms, 1e-12);
    std::printf("%-6s %10.0f %11.0f %9.1f %9.3f %10.3f %9.3f %9.3f %9.3f %6.2fx %6.2fx %9d %12zu %7zu %6zu\n", r.scene.c_str(),
                r.triangle_pairs, r.primitive_tests, r.contacts, r.refit_ms, r.one_ms, r.wall_ms, r.caller_ms, r.process_ms, wall_x,
                cpu_x, r.differing, r.oracle.hits, r.oracle.missed, r.oracle.extra);
    bad = bad || r.differing > 0 || r.oracle.missed > 0;
    bench::JsonObject o;
    o.add("scene", r.scene).add("steps", r.steps).add("triangle_pairs", r.triangle_pairs).add("primitive_tests", r.primitive_tests);
    o.add("contacts", r.contacts).add("refit_ms", r.refit_ms).add("ms_1_thread", r.one_ms).add("ms_wall", r.wall_ms);
    o.add("ms_caller_cpu", r.caller_ms).add("ms_process_cpu", r.process_ms).add("speedup_wall", wall_x).add("speedup_cpu", cpu_x);
    o.add("differing_steps", r.differing).add("oracle_steps", r.checked).add("oracle_hits", r.oracle.hits);
    o.add("oracle_tests", r.oracle.tests).add("missed", r.oracle.missed).add("extra", r.oracle.extra);
    json_rows.push_back(o.str());
  }
  if (!args.json.empty()) {
    bench::JsonObject top;
    top.add("bench", "impact-mesh-ccd-bench").add("mesh", args.mesh.empty() ? "generated:torus" : args.mesh);
    top.add("triangles", mesh.num_triangles()).add("steps", args.steps).add("threads", threads);
    top.raw("rows", bench::JsonObject::array(json_rows));
    if (!bench::write_file(args.json, top.str())) {
      std::fprintf(stderr, "impact-mesh-ccd-bench: cannot write %s\n", args.json.c_str());
      return 1;
    }
  }
  if (bad) std::printf("\nFAILED: an answer differs between thread counts or misses an oracle hit\n");
  return bad ? 3 : 0;
}
