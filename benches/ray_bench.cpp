// SPDX-License-Identifier: MIT
// impact-ray-bench: first-hit ray (segment) casts against a triangle mesh, impact against Intel
// Embree 3 in the same run, speed and wrong answers against an exact referee.
//
//   impact-ray-bench [MESH] [--rays N] [--set short|long|edges|all] [--threads T] [--repeat K]
//                    [--grid G] [--compact C] [--wide-leaf L] [--seed X] [--verbose] [--json FILE]
//
// Without MESH a built-in closed mesh (a torus) is used. --verbose lists impact's wrong answers
// (set, ray, verdict, origin and direction) on stderr. The mesh's box is first moved into
// [D, 2D]^3 (D the power of two above its diagonal) and every coordinate rounded to float, so that
// every library sees the same triangles (Embree stores floats) and every coordinate, of the mesh
// and of the rays, is a multiple of one spacing G = D 2^-23: the exact referee (ray_referee.hpp)
// then works in 128-bit integers, and rays aimed at a vertex pass through it exactly, in float as
// in double. The sets (N rays each, origins and directions multiples of G, exact in float):
//  - short: origins uniform in the mesh's box, random directions, segments 1% of the diagonal;
//  - long:  the same with segments one diagonal long;
//  - edges: rays aimed at a mesh vertex (half of them; the ray passes exactly through it) or at a
//           random point of an edge rounded to the grid (the other half), from an origin uniform
//           in the box, continuing to twice the distance (t_max = 2).
// Methods (all one first-hit query per ray, t in [0, t_max]):
//  - impact CompactBvh: ray_mesh_first_hit through a CompactBvh (leaves of C, 4 by default) of
//    the MeshBvh (default build: spatial middle split, leaves of 1), double precision;
//  - impact CompactBvh+grid: the same cast started from DistanceGrid::start_node (G cells along
//    the longest side, 64 by default), as the particles cast their legs;
//  - impact WideBvh: ray_mesh_first_hit through a WideBvh (bvh/wide_bvh.hpp: the binary SAH tree
//    collapsed to 4 children a node, leaves of L, 4 by default, the triangles copied in leaf
//    order), double;
//  - impact WideBvh8: the same with 8 children a node (WideBvh<double, 8>: the node test eight
//    boxes at once with AVX when the CPU has it, checked at run time, else two halves in SSE);
//  - embree HIGH / HIGH robust (when built with Embree 3): one device, one scene with one
//    triangle geometry (float3 vertex and uint3 index buffers), RTC_BUILD_QUALITY_HIGH on both,
//    the robust row with RTC_SCENE_FLAG_ROBUST; rtcIntersect1 with an RTCIntersectContext per ray
//    (tnear 0, tfar t_max, mask all), as Embree's tutorials set it up.
// Every method hands the same hit record to its caller and the bench keeps all of it (Answer: the
// triangle, t, the barycentric weights u and v, the unit normal; Embree's Ng normalised as its
// users would), so that no compiler leaves out of one library's cast what the other computes.
// Reported per method and set: rays per second on one thread (thread CPU time; the median of K
// repeats, the methods interleaved, with the range), rays per second on T threads (wall clock,
// parallel_for over the rays), wrong answers against the referee (missed: no hit reported though
// the segment crosses the mesh; touched: the first contact missed (no hit, or a later one
// reported), where the segment only touches the surface, e.g. grazes a silhouette vertex: the
// points 256 (or 4096) grid spacings before and after the contact are on the same side of the surface,
// judged by the parity of exact crossings to far points (right for closed meshes; on open ones,
// like the bunny with its holes, a contact at the boundary stays counted as missed or skipped);
// extra: the reported triangle is not crossed; skipped: the reported triangle is crossed strictly
// after the first crossing; wrong is their sum; a segment that starts exactly on a triangle crosses
// it at t = 0 through its front face (d . n < 0); moving away from it, both no hit there (the
// library's tie rule, query/ray_mesh.hpp) and a hit at t = 0 (a ray tracer's convention) are
// accepted, for every library judged; see ray_referee.hpp), build milliseconds (impact: the MeshBvh,
// the CompactBvh and the grid, or the WideBvh; Embree: device, buffers and rtcCommitScene), bytes (impact: the
// MeshBvh with its copy of the mesh, the CompactBvh and the grid; Embree: what its memory monitor
// callback counts after the commit, buffers included), and the hit record's error against impact's
// CompactBvh cast (double) on the rays where both report the same triangle (t_err: the largest
// |t - t'| / t_max; bary_err: of u and v; n_err: |n - n'|). Exits 1 when, on a closed mesh (every
// edge shared by two triangles), an impact method misses a crossing or reports a triangle that
// is not crossed (its casts are watertight: a segment that passes through the surface is never
// missed; a graze of a silhouette vertex may be, its shear rounding the vertex off the ray), or
// when its T-thread answers differ from its one-thread answers.
#include "bench_util.hpp"
#include "impact/core/parallel.hpp"
#include "impact/geometry/mesh_generators.hpp"
#include "impact/query/distance_grid.hpp"
#include "impact/query/ray_mesh.hpp"
#include "impact/query/ray_wide_bvh.hpp"
#include "ray_referee.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <optional>
#include <random>
#include <string>

#ifdef IMPACT_HAVE_EMBREE
#include "embree_peer.hpp"
#endif

using namespace impact;
using impact::bench::Clock;
using impact::bench::IPoint;
using impact::bench::RayReferee;
using impact::bench::seconds_since;
using impact::bench::thread_seconds;

namespace {

struct Args {
  std::string mesh, json, set = "all";
  long rays = 1000000;
  int threads = 0, repeat = 3, grid = 64, compact = 4, wide_leaf = 4;
  std::uint64_t seed = 1;
  bool verbose = false;
};

/// One set of segments: origin o, direction d, parameters [0, t_max].
struct RaySet {
  std::string name;
  std::vector<Vec3<double>> o, d;
  double t_max = 1;
};

/// A method: its build figures and its cast (returns the row of F hit, or -1).
/// What a cast hands its user, the same for every library: the triangle hit (-1: none), the ray
/// parameter t, two barycentric weights (u, v: of the triangle's second and third vertex) and the
/// unit normal. Every method fills all of it, as its users read it, so that no compiler leaves
/// out a part one library computes anyway (Embree fills its whole hit record; impact's cast,
/// inlined into a handler that reads only the triangle, would skip the normal and the weights).
struct Answer {
  std::int32_t triangle = -1;
  double t = 0, u = 0, v = 0;
  Vec3<double> normal = Vec3<double>::Zero();
};

template <class Hit> Answer impact_answer(const std::optional<Hit>& h) {
  if (!h) return {};
  return {h->triangle, double(h->t), double(h->barycentric[1]), double(h->barycentric[2]), h->normal.template cast<double>()};
}

/// Whether two answers are the same, bit for bit (the threads check).
bool same_answer(const Answer& a, const Answer& b) {
  return a.triangle == b.triangle && std::memcmp(&a.t, &b.t, sizeof a.t) == 0 && std::memcmp(&a.u, &b.u, sizeof a.u) == 0 &&
         std::memcmp(&a.v, &b.v, sizeof a.v) == 0 && std::memcmp(a.normal.data(), b.normal.data(), sizeof(double) * 3) == 0;
}

struct Method {
  std::string library, name;
  double build_ms = 0;
  std::size_t bytes = 0;
  std::function<Answer(const Vec3<double>&, const Vec3<double>&, double)> cast;
};

struct Row {
  std::string library, method, set;
  double rate = 0, rate_lo = 0, rate_hi = 0, rate_threads = 0;
  long missed = 0, extra = 0, skipped = 0, touched = 0;
  /// Against impact's CompactBvh cast (double) on the rays where both report the same triangle:
  /// the largest |t - t'| / t_max, |u - u'| or |v - v'|, and |n - n'|.
  double t_err = 0, bary_err = 0, normal_err = 0;
  double build_ms = 0;
  std::size_t bytes = 0;
  long wrong() const { return missed + extra + skipped + touched; }
};

#ifdef IMPACT_HAVE_EMBREE
std::atomic<long long> embree_bytes{0};
bool embree_monitor(void*, ssize_t bytes, bool) {
  embree_bytes += bytes;
  return true;
}

/// Embree 3 as its users set it up (see the file comment and embree_peer.hpp), with its build
/// time (device, buffers and rtcCommitScene) and the bytes its memory monitor counts. The first
/// two members are read before the scene is made (members initialise in declaration order).
struct EmbreeMethod {
  const long long bytes_before = embree_bytes.load();
  const Clock::time_point t0 = Clock::now();
  bench::EmbreeScene scene;
  double build_ms = 0;
  std::size_t bytes = 0;

  EmbreeMethod(const TriangleMesh<double>& m, bool robust) : scene(robust, embree_monitor) {
    scene.add(m.V, m.F);  // exact: the bench's mesh is in float
    scene.commit();
    build_ms = 1e3 * seconds_since(t0);
    bytes = static_cast<std::size_t>(embree_bytes.load() - bytes_before);
  }

  /// The hit record as Embree's users read it: the normal is Ng normalised (Embree's Ng is
  /// the unnormalised geometric normal).
  Answer cast(const Vec3<double>& o, const Vec3<double>& d, double t_max) const {
    const RTCRayHit rh = scene.first_hit(o, d, float(t_max));
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return {};
    const Vec3<double> ng(rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z);
    return {static_cast<std::int32_t>(rh.hit.primID), double(rh.ray.tfar), double(rh.hit.u), double(rh.hit.v), ng / ng.norm()};
  }
};
#endif

/// The mesh moved into [D, 2D]^3 and rounded to float (see the file comment); `grid` gets G.
TriangleMesh<double> to_float_grid(const TriangleMesh<double>& in, double& grid) {
  Aabb<double> box;
  for (int i = 0; i < in.num_vertices(); ++i) box.extend(in.vertex(i));
  const double diag = (box.max - box.min).norm();
  const double D = std::ldexp(1.0, std::ilogb(diag) + 1);  // a power of two above the diagonal
  grid = std::ldexp(D, -23);
  TriangleMesh<double> out = in;
  for (int i = 0; i < in.num_vertices(); ++i)
    for (int k = 0; k < 3; ++k) out.V(i, k) = double(float(in.V(i, k) - box.min[k] + D));
  return out;
}

double snap(double x, double g) { return std::nearbyint(x / g) * g; }

std::vector<RaySet> make_sets(const TriangleMesh<double>& m, double g, const Args& a) {
  Aabb<double> box;
  for (int i = 0; i < m.num_vertices(); ++i) box.extend(m.vertex(i));
  const double diag = (box.max - box.min).norm();
  std::mt19937_64 gen(a.seed);
  auto uni = [&](double lo, double hi) { return lo + (hi - lo) * (double(gen() >> 11) * 0x1.0p-53); };
  auto origin = [&] {
    Vec3<double> o;
    for (int k = 0; k < 3; ++k) o[k] = std::clamp(snap(uni(box.min[k], box.max[k]), g), box.min[k], box.max[k]);
    return o;
  };
  auto direction = [&](double len) {
    for (;;) {
      Vec3<double> d(uni(-1, 1), uni(-1, 1), uni(-1, 1));
      if (d.squaredNorm() > 1 || d.squaredNorm() < 1e-6) continue;
      d = d.normalized() * len;
      for (int k = 0; k < 3; ++k) d[k] = snap(d[k], g);
      if (d.squaredNorm() > 0) return d;
    }
  };
  std::vector<RaySet> sets;
  const std::size_t n = static_cast<std::size_t>(a.rays);
  for (const auto& [name, len] : {std::make_pair(std::string("short"), 0.01 * diag), std::make_pair(std::string("long"), diag)}) {
    if (a.set != "all" && a.set != name) continue;
    RaySet s;
    s.name = name;
    for (std::size_t i = 0; i < n; ++i) {
      s.o.push_back(origin());
      s.d.push_back(direction(len));
    }
    sets.push_back(std::move(s));
  }
  if (a.set == "all" || a.set == "edges") {
    RaySet s;
    s.name = "edges";
    s.t_max = 2;
    std::uniform_int_distribution<int> tri(0, m.num_triangles() - 1), corner(0, 2);
    for (std::size_t i = 0; i < n; ++i) {
      const int t = tri(gen), c = corner(gen);
      const Vec3<double> va = m.vertex(m.F(t, c)), vb = m.vertex(m.F(t, (c + 1) % 3));
      Vec3<double> p = va;
      if (i % 2 == 1) {
        const double u = uni(0, 1);
        for (int k = 0; k < 3; ++k) p[k] = snap(va[k] + u * (vb[k] - va[k]), g);
      }
      Vec3<double> o = origin();
      if (o == p) o[0] = o[0] == box.min[0] ? o[0] + g : o[0] - g;
      s.o.push_back(o);
      s.d.push_back(p - o);  // exact: multiples of G below 2^24 G
    }
    sets.push_back(std::move(s));
  }
  return sets;
}

IPoint to_int(const Vec3<double>& p, double g) {
  return {static_cast<std::int64_t>(p.x() / g), static_cast<std::int64_t>(p.y() / g), static_cast<std::int64_t>(p.z() / g)};
}

/// Side of point q (units of G) against a closed mesh: the parity of the exact crossings of three
/// segments from q to points far outside the mesh's box, by majority (a segment through an edge
/// or a vertex could count one crossing twice).
int side(const RayReferee& referee, const IPoint& q) {
  const std::int64_t far = std::int64_t(1) << 25;  // beyond [D, 2D] = [2^23, 2^24] units
  const IPoint ends[3] = {{q.x + 7919, q.y - 104729, far}, {q.x - 4831, far, q.z + 7727}, {far, q.y + 3571, q.z - 6007}};
  int odd = 0;
  for (const auto& e : ends) odd += referee.count(q, e) % 2;
  return odd >= 2 ? 1 : 0;
}

/// True when the segment's points 256, or 4096, grid spacings before and after its first contact
/// (rounded to the grid) are on the same side of the mesh: the segment touches the surface there
/// (a silhouette vertex or edge) without passing through it. (Two distances: for a segment
/// almost tangent to the surface, rounding the nearer points to the grid can put one of them
/// inside; the farther pair is then still right.)
bool touch_only(const RayReferee& referee, const Vec3<double>& o, const Vec3<double>& d, double t_max, const RayReferee::First& ref, double g) {
  const double t = t_max * double(ref.num) / double(ref.den);
  auto at = [&](double tt) {
    Vec3<double> q = o + tt * d;
    for (int k = 0; k < 3; ++k) q[k] = snap(q[k], g);
    return to_int(q, g);
  };
  for (const double spacings : {256.0, 4096.0}) {
    const double dt = spacings * g / d.norm();
    if (side(referee, at(std::max(t - dt, 0.0))) == side(referee, at(std::min(t + dt, t_max)))) return true;
  }
  return false;
}

/// True when every edge of the mesh is shared by exactly two triangles (the touch classification
/// by parities is then exact).
bool is_closed(const TriangleMesh<double>& m) {
  std::vector<std::pair<int, int>> edges;
  for (int t = 0; t < m.num_triangles(); ++t)
    for (int k = 0; k < 3; ++k) edges.emplace_back(std::minmax(m.F(t, k), m.F(t, (k + 1) % 3)));
  std::sort(edges.begin(), edges.end());
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i;
    while (j < edges.size() && edges[j] == edges[i]) ++j;
    if (j - i != 2) return false;
    i = j;
  }
  return true;
}

}  // namespace

constexpr const char* kUsage =
    "usage: impact-ray-bench [MESH] [--rays N] [--set short|long|edges|all] [--threads T] [--repeat K]\n"
    "                        [--grid G] [--compact C] [--wide-leaf L] [--seed X] [--verbose] [--json FILE]\n"
    "Wrong answers are judged by an exact referee; a segment from a point exactly on a triangle crosses it\n"
    "(at t = 0) through its front face (d . n < 0); moving away, no hit there and a hit at t = 0 are both\n"
    "accepted (impact's tie rule and a ray tracer's convention), for every library judged.\n";

int main(int argc, char** argv) {
  Args a;
  for (int i = 1; i < argc; ++i) {
    const std::string s = argv[i];
    auto next = [&] { return bench::option_value(argc, argv, i, kUsage); };
    auto integer = [&](long long lo, long long hi) { return int(bench::parse_integer(s, next(), lo, hi, kUsage)); };
    if (s == "--rays") a.rays = integer(1, 10000000);
    else if (s == "--set") a.set = next();
    else if (s == "--threads") a.threads = integer(0, 1024);
    else if (s == "--repeat") a.repeat = integer(1, 1000);
    else if (s == "--grid") a.grid = integer(0, 4096);
    else if (s == "--compact") a.compact = integer(1, 1024);
    else if (s == "--wide-leaf") a.wide_leaf = integer(1, 1024);
    else if (s == "--verbose") a.verbose = true;
    else if (s == "--seed") a.seed = bench::parse_seed(s, next(), kUsage);
    else if (s == "--json") a.json = next();
    else if (!s.empty() && s[0] == '-') bench::reject_option(s, kUsage);
    else if (a.mesh.empty()) a.mesh = s;
    else bench::exit_usage("more than one mesh given", kUsage);
  }
  if (a.set != "all" && a.set != "short" && a.set != "long" && a.set != "edges")
    bench::exit_usage("--set must be short, long, edges or all", kUsage);
  bench::check_writable(a.json, kUsage);

  TriangleMesh<double> source;
  try {
    source = a.mesh.empty() ? make_torus<double>(1.0, 0.4, 192, 96) : bench::read_mesh<double>(a.mesh);
    if (source.num_triangles() == 0) throw InvalidInput("the mesh has no triangles");
    bench::require_extent(source, a.mesh);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "impact-ray-bench: %s\n", e.what());
    return 1;
  }
  const std::string mesh_name = a.mesh.empty() ? "generated:torus" : a.mesh;
  double g = 0;
  const TriangleMesh<double> mesh = to_float_grid(source, g);
  const int threads = resolve_threads(a.threads);
  const bool closed = is_closed(mesh);

  // impact: the particles' set-up (default MeshBvh build, CompactBvh, distance grid)
  std::vector<Method> methods;
  const auto tb = Clock::now();
  const MeshBvh<Aabb<double>> bvh(mesh);
  const CompactBvh compact(bvh.tree(), a.compact);
  const double bvh_ms = 1e3 * seconds_since(tb);
  methods.push_back({"impact", "CompactBvh", bvh_ms, bvh.memory_bytes() + compact.memory_bytes(),
                     [&](const Vec3<double>& o, const Vec3<double>& d, double t_max) {
                       return impact_answer(ray_mesh_first_hit(bvh, compact, Ray<double>(o, d, t_max)));
                     }});
  DistanceGrid<double> grid;
  if (a.grid > 0) {
    const auto tg = Clock::now();
    DistanceGridConfig<double> gcfg;
    gcfg.resolution = a.grid;
    gcfg.threads = 1;
    grid = DistanceGrid<double>(bvh, gcfg);
    methods.push_back({"impact", "CompactBvh+grid", bvh_ms + 1e3 * seconds_since(tg), bvh.memory_bytes() + compact.memory_bytes() + grid.memory_bytes(),
                       [&](const Vec3<double>& o, const Vec3<double>& d, double t_max) {
                         const std::int32_t start = grid.start_node(o, Vec3<double>(o + t_max * d));
                         if (start == DistanceGrid<double>::kNoTriangle) return Answer{};
                         return impact_answer(ray_mesh_first_hit(bvh, compact, Ray<double>(o, d, t_max), RigidTransform<double>(), nullptr, start));
                       }});
  }
  const auto twb = Clock::now();
  WideBvhConfig wcfg;
  wcfg.leaf_size = a.wide_leaf;
  const WideBvh<double> wide(mesh, wcfg);
  methods.push_back({"impact", "WideBvh", 1e3 * seconds_since(twb), wide.memory_bytes(),
                     [&](const Vec3<double>& o, const Vec3<double>& d, double t_max) {
                       return impact_answer(ray_mesh_first_hit(wide, Ray<double>(o, d, t_max)));
                     }});
  const auto twb8 = Clock::now();
  const WideBvh<double, 8> wide8(mesh, wcfg);
  methods.push_back({"impact", "WideBvh8", 1e3 * seconds_since(twb8), wide8.memory_bytes(),
                     [&](const Vec3<double>& o, const Vec3<double>& d, double t_max) {
                       return impact_answer(ray_mesh_first_hit(wide8, Ray<double>(o, d, t_max)));
                     }});
  const std::size_t impact_methods = methods.size();
#ifdef IMPACT_HAVE_EMBREE
  const EmbreeMethod embree_fast(mesh, false), embree_robust(mesh, true);
  methods.push_back({"embree", "HIGH", embree_fast.build_ms, embree_fast.bytes,
                     [&](const Vec3<double>& o, const Vec3<double>& d, double t_max) { return embree_fast.cast(o, d, t_max); }});
  methods.push_back({"embree", "HIGH robust", embree_robust.build_ms, embree_robust.bytes,
                     [&](const Vec3<double>& o, const Vec3<double>& d, double t_max) { return embree_robust.cast(o, d, t_max); }});
  const bool have_embree = true;
#else
  const bool have_embree = false;
#endif

  // the referee's integer mesh
  std::vector<IPoint> iv(static_cast<std::size_t>(mesh.num_vertices()));
  for (int i = 0; i < mesh.num_vertices(); ++i) iv[static_cast<std::size_t>(i)] = to_int(mesh.vertex(i), g);
  std::vector<std::array<int, 3>> iff(static_cast<std::size_t>(mesh.num_triangles()));
  for (int t = 0; t < mesh.num_triangles(); ++t) iff[static_cast<std::size_t>(t)] = {mesh.F(t, 0), mesh.F(t, 1), mesh.F(t, 2)};
  const RayReferee referee(std::move(iv), std::move(iff));

  const std::vector<RaySet> sets = make_sets(mesh, g, a);
  std::printf("impact-ray-bench: %s, %d triangles (moved into [D, 2D]^3 and rounded to float, spacing %g), %ld rays per set, %d threads\n",
              mesh_name.c_str(), mesh.num_triangles(), g, a.rays, threads);
  if (!have_embree) std::printf("built without Embree 3 (libembree-dev not found at configure time): no Embree rows\n");

  std::vector<Row> rows;
  bool impact_wrong = false;
  for (const RaySet& s : sets) {
    const std::size_t n = s.o.size();
    // the referee, on T threads
    const auto tr = Clock::now();
    std::vector<RayReferee::First> ref(n);
    std::vector<IPoint> io(n), ie(n);
    parallel_for(n, threads, [&](std::size_t i) {
      io[i] = to_int(s.o[i], g);
      ie[i] = to_int(Vec3<double>(s.o[i] + s.t_max * s.d[i]), g);  // exact: multiples of G
      ref[i] = referee.first(io[i], ie[i]);
    });
    long crossing = 0;
    for (const auto& r : ref) crossing += r.hit ? 1 : 0;
    std::printf("\nset %s: %zu segments, t_max %g, %.1f%% cross the mesh (referee: %.1f s on %d threads)\n", s.name.c_str(), n, s.t_max,
                100.0 * double(crossing) / double(n), seconds_since(tr), threads);
    std::vector<std::vector<double>> rates(methods.size());
    std::vector<std::vector<Answer>> answers(methods.size(), std::vector<Answer>(n));
    for (int rep = 0; rep < a.repeat; ++rep)
      for (std::size_t m = 0; m < methods.size(); ++m) {
        auto& out = answers[m];
        const auto& cast = methods[m].cast;
        const double t0 = thread_seconds();
        for (std::size_t i = 0; i < n; ++i) out[i] = cast(s.o[i], s.d[i], s.t_max);
        rates[m].push_back(double(n) / std::max(thread_seconds() - t0, 1e-12));
      }
    for (std::size_t m = 0; m < methods.size(); ++m) {
      Row w;
      w.library = methods[m].library;
      w.method = methods[m].name;
      w.set = s.name;
      w.build_ms = methods[m].build_ms;
      w.bytes = methods[m].bytes;
      const auto sm = bench::summarize(rates[m]);
      w.rate = sm.median;
      w.rate_lo = *std::min_element(rates[m].begin(), rates[m].end());
      w.rate_hi = sm.max;
      std::vector<Answer> par(n);
      const auto& cast = methods[m].cast;
      const auto tw = Clock::now();
      parallel_for(n, threads, [&](std::size_t i) { par[i] = cast(s.o[i], s.d[i], s.t_max); });
      w.rate_threads = double(n) / std::max(seconds_since(tw), 1e-12);
      std::vector<int> verdict(n);
      parallel_for(n, threads, [&](std::size_t i) { verdict[i] = referee.judge(io[i], ie[i], ref[i], answers[m][i].triangle); });
      // a first contact missed (no hit, or a later one) where the segment only touches the mesh
      // (the points just before and just after it are on the same side of the surface) is a touch
      parallel_for(n, threads, [&](std::size_t i) {
        if ((verdict[i] == 1 || verdict[i] == 3) && touch_only(referee, s.o[i], s.d[i], s.t_max, ref[i], g)) verdict[i] = 4;
      });
      for (std::size_t i = 0; i < n; ++i) {
        const Answer &x = answers[m][i], &x0 = answers[0][i];
        if (x.triangle >= 0 && x.triangle == x0.triangle) {
          w.t_err = std::max(w.t_err, std::abs(x.t - x0.t) / s.t_max);
          w.bary_err = std::max({w.bary_err, std::abs(x.u - x0.u), std::abs(x.v - x0.v)});
          w.normal_err = std::max(w.normal_err, (x.normal - x0.normal).norm());
        }
        if (a.verbose && m < impact_methods && verdict[i] != 0)
          std::fprintf(stderr, "%s %s ray %zu: %s, answer %d, first crossing %d; o = (%.9g, %.9g, %.9g), d = (%.9g, %.9g, %.9g)\n",
                       w.method.c_str(), s.name.c_str(), i, verdict[i] == 1 ? "missed" : verdict[i] == 2 ? "extra" : verdict[i] == 3 ? "skipped" : "touched",
                       answers[m][i].triangle, ref[i].triangle, s.o[i].x(), s.o[i].y(), s.o[i].z(), s.d[i].x(), s.d[i].y(), s.d[i].z());
        w.touched += verdict[i] == 4;
        w.missed += verdict[i] == 1;
        w.extra += verdict[i] == 2;
        w.skipped += verdict[i] == 3;
        if (!same_answer(par[i], answers[m][i]) && m < impact_methods) {
          std::fprintf(stderr, "impact-ray-bench: %s answers differently on %d threads (ray %zu)\n", w.method.c_str(), threads, i);
          return 1;
        }
      }
      if (m < impact_methods && w.missed + w.extra > 0) impact_wrong = true;
      rows.push_back(w);
    }
  }

  std::printf("\n%-7s %-16s %-6s %12s %25s %12s %8s %7s %7s %6s %7s %9s %10s %9s %9s %9s\n", "library", "method", "set", "rays/s(1)", "range", "rays/s(T)",
              "wrong", "missed", "touched", "extra", "skipped", "build_ms", "bytes", "t_err", "bary_err", "n_err");
  std::vector<std::string> items;
  for (const auto& w : rows) {
    char range[64];
    std::snprintf(range, sizeof range, "%.3g-%.3g", w.rate_lo, w.rate_hi);
    std::printf("%-7s %-16s %-6s %12.4g %25s %12.4g %8ld %7ld %7ld %6ld %7ld %9.1f %10zu %9.2g %9.2g %9.2g\n", w.library.c_str(), w.method.c_str(), w.set.c_str(),
                w.rate, range, w.rate_threads, w.wrong(), w.missed, w.touched, w.extra, w.skipped, w.build_ms, w.bytes, w.t_err, w.bary_err, w.normal_err);
    bench::JsonObject o;
    o.add("library", w.library).add("method", w.method).add("set", w.set).add("rays_per_s", w.rate);
    o.add("rays_per_s_min", w.rate_lo).add("rays_per_s_max", w.rate_hi).add("threads", threads).add("rays_per_s_threads", w.rate_threads);
    o.add("wrong", static_cast<long long>(w.wrong())).add("missed", static_cast<long long>(w.missed));
    o.add("touched", static_cast<long long>(w.touched)).add("extra", static_cast<long long>(w.extra)).add("skipped", static_cast<long long>(w.skipped));
    o.add("build_ms", w.build_ms).add("bytes", w.bytes);
    o.add("t_err", w.t_err).add("bary_err", w.bary_err).add("normal_err", w.normal_err);
    items.push_back(o.str());
  }
  // ratios within this run: impact's methods over Embree HIGH, per set
  for (const auto& w : rows)
    if (w.library == "impact")
      for (const auto& e : rows)
        if (e.library == "embree" && e.method == "HIGH" && e.set == w.set)
          std::printf("%s %s / embree HIGH on %s: %.2fx\n", w.library.c_str(), w.method.c_str(), w.set.c_str(), w.rate / std::max(e.rate, 1e-300));
  if (!a.json.empty()) {
    bench::JsonObject top;
    top.add("bench", "impact-ray-bench").add("mesh", mesh_name).add("triangles", mesh.num_triangles()).add("rays", static_cast<long long>(a.rays));
    top.add("repeat", a.repeat).add("threads", threads).add("embree", have_embree);
    top.raw("rows", bench::JsonObject::array(items));
    if (!bench::write_file(a.json, top.str())) {
      std::fprintf(stderr, "impact-ray-bench: cannot write %s\n", a.json.c_str());
      return 1;
    }
  }
  if (impact_wrong) {
    if (closed) {
      std::fprintf(stderr, "impact-ray-bench: an impact method missed a crossing or reported an extra one (exact referee)\n");
      return 1;
    }
    std::printf("note: the mesh is open (some edge is not shared by exactly two triangles): contacts at its boundary or in front of\n"
                "its holes cannot be told apart from crossings by parities, so impact's misses there count as missed\n");
  }
  return 0;
}
