// SPDX-License-Identifier: MIT
// impact-convex-bench: per shape pair, boolean / distance / penetration queries per second for
// impact's convex layer (convex/query.hpp) and FCL 0.7 on the same shapes and poses, with the error
// of each against an oracle independent of both (tests/support/convex_oracle.hpp):
//   distance     the certified bracket of the ellipsoid method (width < 1e-11), error |d - mid|
//   penetration  the exact least overlap over the candidate axes for box/hull pairs; for curved
//                shapes the better of two upper bounds of the true depth, the least overlap found
//                by a grid search over directions and the least ray exit distance found by a
//                pattern search from the grid's direction (ray_depth_upper; only a depth above
//                it counts as error)
//   boolean      mismatches against the oracle's sign where |signed distance| > 1e-6 of the size
//   normal angle penetration rows: the angle in radians between a library's normal and a referee's,
//                the least overlap f(n) = h_A(n) + h_B(-n) minimised over unit n by nested grids
//                (referee_normals) from three starts: the oracle's direction search, impact's
//                normal and FCL's; the angle is to the nearest of those minimisers whose f is
//                within 1e-9 of the size of the least (two directions can tie); its floor is about
//                1e-8 rad where f is smooth at its minimum (f is quadratic there, resolved to
//                rounding), below where it has a kink (polytopes)
// Errors are relative to the larger shape's size (shape_size). Timing: each query's libraries run
// side by side in short blocks, taking turns (the first of each round alternating too), and a row
// gives the median block rate (side_by_side_rates); the answers and errors come from an untimed pass.
// FCL is set up as its users do:
// fcl::Sphere / Capsule / Cylinder / Cone / Box / Convex, fcl::collide and fcl::distance on
// CollisionGeometry + Transform3 with default requests (its default narrow-phase solver, the libccd
// one: GST_LIBCCD), contacts requested for penetration (CollisionRequest(1, true)) and nearest
// points for distance (DistanceRequest(true)), since impact returns both.
// The bench exits with status 3 when any impact answer disagrees with the oracle where the oracle
// decides (the mism column of impact's rows; FCL's mismatches are reported, not judged), so its
// smoke run fails on a wrong answer, as the scene and CCD benches do.
//
// Mesh against convex (convex/mesh_convex.hpp), rows "mesh-<shape>": a triangle mesh in a MeshBvh
// (OBB tree) against each shape, the shape's centre near a random vertex (within 1.5 of its size),
// random rotations of both; boolean (mesh_convex_collides), distance (mesh_convex_distance) and
// contacts (mesh_convex_contacts) against FCL's BVHModel<OBBRSS> (beginModel / addSubModel /
// endModel) with fcl::collide (default request; for contacts CollisionRequest(100000, true), every
// triangle with its penetration) and fcl::distance (default request). The oracle over every
// triangle (pruned by the triangles' own boxes, exact pruning): the ellipsoid method's certified
// distance bracket of each triangle against the shape, and for overlaps the direction search's
// least overlap; boolean mismatches count where the oracle is more than 1e-6 of the size from
// touching; distance error |d - bracket midpoint|; contacts: mismatches of "colliding" only;
// contacts-mpr: impact with MeshConvexOptions::fast_contacts (MPR per triangle, as FCL), time only.
// The shapes are scaled to 1/8 of the mesh's bounding-box diagonal.
//
// Hull builds, `--hulls` (only these rows then; issue 15's "own quickhull or qhull, measured"):
// convex_hull() against qhull (Debian libqhull_r; benches/qhull_peer.hpp: qh_new_qhull with
// "qhull Qt", the hull's vertices and triangles read back, qhull's memory freed: what a user does
// to get a hull) on point sets a user would pass, at 10, 100, ... up to --hull-max-points points:
//   ball-N          uniform in the unit ball (few hull vertices)
//   sphere-N        uniform on the unit sphere (every point a vertex)
//   cube-corners-N  the 8 corners of a cube, each repeated, moved by up to 1e-6 per coordinate
//                   (clusters of nearly coincident and nearly coplanar points)
//   cube-faces-N    the 8 corners and points on the cube's faces (coplanar points, 8 vertices)
//   flat-disc-N     points in a disc in z = 0 (no hull: both must refuse)
//   mesh-FILE       the vertices of each mesh of $IMPACT_DATA_DIR/meshes (or of --mesh FILE)
// Each build is timed over --hull-reps repetitions of at least --min-time / reps seconds, the two
// libraries alternating; the table gives the median and range per build and qhull's median over
// impact's. Agreement: the sorted vertex coordinates of both hulls are compared; a vertex of one
// that the other lacks must lie within 1e-9 of the extent (half the bounding box's largest side)
// inside the other hull (qhull merges, and impact drops, points that close to a face), and the
// volumes must agree within 1e-9 relatively; where one refuses (InvalidInput, a qhull error) the
// other must too. A disagreement counts as a mismatch, and the bench then exits with status 3.
// Without qhull the rows say "absent".
//
//   impact-convex-bench [--pairs N] [--json FILE] [--min-time SECONDS] [--mesh FILE] [--mesh-poses N] [--only TEXT]
//   impact-convex-bench --hulls [--hull-max-points N] [--hull-reps N] [--min-time SECONDS] [--mesh FILE] [--only TEXT] [--json FILE]
// --only runs the rows whose pair name contains TEXT (e.g. "cylinder", "mesh-"). Without --mesh a generated mesh is used (a torus of 7,200 triangles with its vertices moved by
// up to 5 %).
#include "bench_util.hpp"
#include "impact/convex/mesh_convex.hpp"
#include "impact/convex/query.hpp"
#include "impact/geometry/mesh_generators.hpp"
#include "support/convex_oracle.hpp"
#ifdef IMPACT_HAVE_FCL
#include "support/convex_fcl.hpp"
#include "support/fcl_oracle.hpp"

#include <fcl/geometry/bvh/BVH_model.h>
#include <fcl/math/bv/OBBRSS.h>
#endif
#ifdef IMPACT_HAVE_QHULL
#include "qhull_peer.hpp"
#endif

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <functional>
#include <iterator>
#include <limits>
#include <string>
#include <utility>
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
  double mean_angle = -1, max_angle = -1;  ///< penetration rows: normal angle against the referee (rad)
};

struct Reference {
  double signed_distance = 0;  // > 0 separated (bracket midpoint), < 0 minus the depth reference
  bool separated = false, intersecting = false;
  bool exact_depth = false;  // polytope pairs: the depth reference is exact, else an upper bound
  V3 normal = V3::UnitZ();   // intersecting: the direction search's least-overlap normal
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
  r.normal = o.normal;
  double depth = -o.value;
  if (depth > 1e-6 * scale) depth = std::min(depth, test::ray_depth_upper(a, pa, b, pb, o.normal));
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

/// The referee of the normal (see the file comment): f(n) = h_A(n) + h_B(-n) minimised by nested
/// 11 x 11 grids over a cap about the best direction so far, its angular radius from 1e-2 shrinking
/// threefold per level to 1e-12, from each start; the minimisers whose f is within `tie` of the
/// least.
template <class A, class B>
std::vector<V3> referee_normals(const A& a, const Pose& pa, const B& b, const Pose& pb, const std::vector<V3>& starts,
                                double tie) {
  std::vector<std::pair<double, V3>> found;
  for (V3 n : starts) {
    if (!(n.squaredNorm() > 0.5)) continue;
    n.normalize();
    double fn = test::overlap_along(a, pa, b, pb, n);
    for (double rho = 1e-2; rho > 1e-12; rho /= 3) {
      const V3 u = (std::abs(n.x()) < 0.6 ? V3::UnitX() : V3::UnitY()).cross(n).normalized(), w = n.cross(u);
      V3 bn = n;
      for (int i = -5; i <= 5; ++i)
        for (int j = -5; j <= 5; ++j) {
          const V3 c = (n + rho * (i / 5.0) * u + rho * (j / 5.0) * w).normalized();
          const double f = test::overlap_along(a, pa, b, pb, c);
          if (f < fn) {
            fn = f;
            bn = c;
          }
        }
      n = bn;
    }
    found.emplace_back(fn, n);
  }
  double least = std::numeric_limits<double>::infinity();
  for (const auto& [f, n] : found) least = std::min(least, f);
  std::vector<V3> out;
  for (const auto& [f, n] : found)
    if (f <= least + tie) out.push_back(n);
  return out;
}

/// The angle (rad) between unit n and the nearest of `refs`.
double angle_to(const V3& n, const std::vector<V3>& refs) {
  double best = std::numeric_limits<double>::infinity();
  for (const V3& m : refs) best = std::min(best, std::atan2(n.cross(m).norm(), n.dot(m)));
  return best;
}

/// The libraries' bodies timed side by side (body(i) runs one query on pose i): short blocks of
/// each in turn, a block being whole passes over the n poses for at least min_time / kBlocks
/// seconds (at least one pass), the library that opens each round rotating (impact, FCL; FCL,
/// impact; ...), until every library has run for at least min_time seconds (one block each when
/// min_time is 0). Returns each library's median block rate, in queries per second. Load that
/// drifts during a row (other work on the machine) then moves every library's blocks alike,
/// where timing one library's queries after the other's moved their ratio by up to 40 %.
constexpr int kBlocks = 15;
std::vector<double> side_by_side_rates(std::size_t n, double min_time, const std::vector<std::function<void(std::size_t)>>& bodies) {
  const std::size_t k = bodies.size();
  std::vector<std::vector<double>> block_rates(k);
  std::vector<double> total(k, 0.0);
  const double block_time = min_time / kBlocks;
  for (std::size_t round = 0;; ++round) {
    for (std::size_t j = 0; j < k; ++j) {
      const std::size_t lib = (round + j) % k;
      std::size_t count = 0;
      const auto t0 = Clock::now();
      double t = 0;
      do {
        for (std::size_t i = 0; i < n; ++i) bodies[lib](i);
        count += n;
        t = seconds_since(t0);
      } while (t < block_time);
      total[lib] += t;
      block_rates[lib].push_back(double(count) / t);
    }
    if (*std::min_element(total.begin(), total.end()) >= min_time) break;
  }
  std::vector<double> rates;
  for (const auto& r : block_rates) rates.push_back(bench::summarize(r).median);
  return rates;
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

// One result row; errors are given relative to `scale`, the size of the pair's shapes.
Row make_row(const std::string& pair, const char* query, const char* lib, double qps, const Errors& e, double scale) {
  Row r;
  r.pair = pair;
  r.query = query;
  r.library = lib;
  r.qps = qps;
  r.mean_error = e.n ? e.sum / e.n / scale : 0;
  r.max_error = e.max / scale;
  r.mismatches = e.mismatches;
  r.samples = e.n;
  return r;
}

volatile double g_sink = 0;

// Each library's query behind a function that is never inlined, so that callgrind can count its
// instructions alone (docs/convex-notes.md, note 10: valgrind --tool=callgrind
// --toggle-collect='*bench_impact_penetration*', and likewise bench_fcl_penetration,
// bench_impact_boolean, bench_fcl_boolean, bench_impact_distance, bench_fcl_distance). The error
// pass and the timed loop both call them.
template <class A, class B>
[[gnu::noinline]] bool bench_impact_boolean(const A& a, const Pose& pa, const B& b, const Pose& pb) {
  return convex_intersect(a, pa, b, pb);
}
template <class A, class B>
[[gnu::noinline]] ConvexDistance<double> bench_impact_distance(const A& a, const Pose& pa, const B& b, const Pose& pb) {
  return convex_distance(a, pa, b, pb);
}
template <class A, class B>
[[gnu::noinline]] ConvexContact<double> bench_impact_penetration(const A& a, const Pose& pa, const B& b, const Pose& pb) {
  return convex_penetration(a, pa, b, pb);
}
#ifdef IMPACT_HAVE_FCL
[[gnu::noinline]] bool bench_fcl_boolean(const test::FclShapePair& fcl, const Pose& pa, const Pose& pb) { return fcl.collide(pa, pb); }
[[gnu::noinline]] double bench_fcl_distance(const test::FclShapePair& fcl, const Pose& pa, const Pose& pb, V3* wa, V3* wb) {
  return fcl.distance(pa, pb, wa, wb);
}
[[gnu::noinline]] bool bench_fcl_penetration(const test::FclShapePair& fcl, const Pose& pa, const Pose& pb, double& depth,
                                             V3& normal, V3& point) {
  return fcl.penetration(pa, pb, depth, normal, point);
}
#endif

template <class A, class B>
void run_pair(const std::string& name, const A& a, const B& b, int n_poses, double min_time, std::vector<Row>& rows) {
  const double scale = std::max(shape_size(a), shape_size(b));
  const auto poses = test::convex_poses(n_poses, 0.9 * (shape_size(a) + shape_size(b)), std::hash<std::string>{}(name) & 0xffff);
  std::vector<Reference> ref;
  for (const auto& [pa, pb] : poses) ref.push_back(reference(a, pa, b, pb, scale));
  const std::size_t n = poses.size();

  const auto add = [&](const char* query, const char* lib, double qps, const Errors& e) {
    rows.push_back(make_row(name, query, lib, qps, e, scale));
  };

  // the normals of each library's penetrations (valid where set), for the angle column
  std::vector<V3> impact_normal(n, V3::Zero()), fcl_normal(n, V3::Zero());
  std::size_t impact_row = 0, fcl_row = 0;
  // the error passes (untimed), impact's then FCL's; then the three queries timed side by side
  std::vector<std::function<void(std::size_t)>> boolean_bodies, distance_bodies, penetration_bodies;
  Errors ieb, ied, iep;
  {
    Errors &eb = ieb, &ed = ied, &ep = iep;
    for (std::size_t i = 0; i < n; ++i) {
      const auto& [pa, pb] = poses[i];
      const bool hit = bench_impact_boolean(a, pa, b, pb);
      const auto d = bench_impact_distance(a, pa, b, pb);
      const auto c = bench_impact_penetration(a, pa, b, pb);
      if (ref[i].separated || ref[i].intersecting) {
        ++eb.n;
        eb.mismatches += hit != ref[i].intersecting;
        ed.mismatches += d.intersecting != ref[i].intersecting;
        ep.mismatches += c.intersecting != ref[i].intersecting;
      }
      if (ref[i].separated && !d.intersecting) ed.add(std::abs(d.distance - ref[i].signed_distance));
      if (ref[i].intersecting && c.intersecting) {
        ep.add(depth_error(c.depth, ref[i]));
        impact_normal[i] = c.normal;
      }
    }
    boolean_bodies.emplace_back([&](std::size_t i) { g_sink = g_sink + bench_impact_boolean(a, poses[i].first, b, poses[i].second); });
    distance_bodies.emplace_back(
        [&](std::size_t i) { g_sink = g_sink + bench_impact_distance(a, poses[i].first, b, poses[i].second).distance; });
    penetration_bodies.emplace_back(
        [&](std::size_t i) { g_sink = g_sink + bench_impact_penetration(a, poses[i].first, b, poses[i].second).depth; });
  }
#ifdef IMPACT_HAVE_FCL
  const test::FclShapePair fcl{test::to_fcl_shape(a), test::to_fcl_shape(b)};
  Errors feb, fed, fep;
  V3 fcl_wa, fcl_wb, fcl_normal_sink, fcl_point_sink;
  double fcl_depth_sink = 0;
  {
    Errors &eb = feb, &ed = fed, &ep = fep;
    for (std::size_t i = 0; i < n; ++i) {
      const auto& [pa, pb] = poses[i];
      const bool hit = bench_fcl_boolean(fcl, pa, pb);
      V3 wa, wb;
      const double d = bench_fcl_distance(fcl, pa, pb, &wa, &wb);
      double depth = 0;
      V3 normal, point;
      const bool pen = bench_fcl_penetration(fcl, pa, pb, depth, normal, point);
      if (ref[i].separated || ref[i].intersecting) {
        ++eb.n;
        eb.mismatches += hit != ref[i].intersecting;
        ed.mismatches += (d <= 0) != ref[i].intersecting;
        ep.mismatches += pen != ref[i].intersecting;
      }
      if (ref[i].separated && d > 0) ed.add(std::abs(d - ref[i].signed_distance));
      if (ref[i].intersecting && pen) {
        ep.add(depth_error(depth, ref[i]));
        fcl_normal[i] = normal;
      }
    }
    boolean_bodies.emplace_back([&](std::size_t i) { g_sink = g_sink + bench_fcl_boolean(fcl, poses[i].first, poses[i].second); });
    distance_bodies.emplace_back(
        [&](std::size_t i) { g_sink = g_sink + bench_fcl_distance(fcl, poses[i].first, poses[i].second, &fcl_wa, &fcl_wb); });
    penetration_bodies.emplace_back([&](std::size_t i) {
      g_sink = g_sink + bench_fcl_penetration(fcl, poses[i].first, poses[i].second, fcl_depth_sink, fcl_normal_sink, fcl_point_sink);
    });
  }
#endif
  const std::vector<double> qb = side_by_side_rates(n, min_time, boolean_bodies);
  const std::vector<double> qd = side_by_side_rates(n, min_time, distance_bodies);
  const std::vector<double> qp = side_by_side_rates(n, min_time, penetration_bodies);
  add("boolean", "impact", qb[0], ieb);
  add("distance", "impact", qd[0], ied);
  impact_row = rows.size();
  add("penetration", "impact", qp[0], iep);
#ifdef IMPACT_HAVE_FCL
  add("boolean", "fcl", qb[1], feb);
  add("distance", "fcl", qd[1], fed);
  fcl_row = rows.size();
  add("penetration", "fcl", qp[1], fep);
#endif
  // the normal angle against the referee, on the poses the oracle calls intersecting
  Errors ai, af;
  for (std::size_t i = 0; i < n; ++i) {
    if (!ref[i].intersecting) continue;
    const auto& [pa, pb] = poses[i];
    const std::vector<V3> refs = referee_normals(a, pa, b, pb, {ref[i].normal, impact_normal[i], fcl_normal[i]}, 1e-9 * scale);
    if (impact_normal[i].squaredNorm() > 0) ai.add(angle_to(impact_normal[i], refs));
    if (fcl_normal[i].squaredNorm() > 0) af.add(angle_to(fcl_normal[i], refs));
  }
  const auto set_angles = [&](std::size_t row, const Errors& e) {
    if (row >= rows.size() || e.n == 0) return;
    rows[row].mean_angle = e.sum / e.n;
    rows[row].max_angle = e.max;
  };
  set_angles(impact_row, ai);
  if (fcl_row > 0) set_angles(fcl_row, af);
}


// ---- mesh against convex ----

struct MeshReference {
  bool separated = false, intersecting = false;
  double distance = 0;  // bracket midpoint when separated
};

/// The oracle over every triangle (see the file comment).
template <class Shape>
MeshReference mesh_reference(const TriangleMesh<double>& m, const Pose& pm, const Shape& s, const Pose& ps, double size) {
  const Aabb<double> sb = bounding_box(s, ps);
  std::vector<std::pair<double, int>> order;
  for (int t = 0; t < m.F.rows(); ++t) {
    const Triangle<double> tri = m.triangle(t);
    const V3 a = pm.apply(tri.a), b = pm.apply(tri.b), c = pm.apply(tri.c);
    const V3 lo = a.cwiseMin(b).cwiseMin(c), hi = a.cwiseMax(b).cwiseMax(c);
    const V3 e = (lo - sb.max).cwiseMax(sb.min - hi).cwiseMax(V3::Zero());
    order.emplace_back(e.norm(), t);
  }
  std::sort(order.begin(), order.end());
  double lower = std::numeric_limits<double>::infinity(), upper = lower;
  bool overlap = false;
  for (const auto& [gap, t] : order) {
    if (gap > upper) break;
    const TriangleShape<double> tri(m.triangle(t));
    const auto br = test::distance_bracket(tri, pm, s, ps, 1000);
    lower = std::min(lower, br.lower);
    upper = std::min(upper, br.upper);
    if (!overlap && br.upper < 1e-9 * size && test::signed_distance_oracle(tri, pm, s, ps, 1500, 1).value < -1e-6 * size) overlap = true;
  }
  MeshReference r;
  r.separated = lower > 1e-6 * size;
  r.intersecting = overlap;
  r.distance = (lower + upper) / 2;
  return r;
}

template <class Shape>
void run_mesh(const std::string& name, const TriangleMesh<double>& m, const Shape& s, int n_poses, double min_time,
              std::vector<Row>& rows) {
  const MeshBvh<Obb<double>> tree(m);
  const double size = shape_size(s);
  test::Rng rng(std::hash<std::string>{}(name) & 0xffff);
  std::vector<std::pair<Pose, Pose>> poses;
  for (int i = 0; i < n_poses; ++i) {
    const Pose pm{rng.rotation(), rng.vec(-1, 1)};
    const V3 v = m.V.row(static_cast<Eigen::Index>(rng.index(std::uint64_t(m.V.rows())))).transpose();
    poses.emplace_back(pm, Pose{rng.rotation(), pm.apply(v) + rng.vec(-1.5 * size, 1.5 * size)});
  }
  std::vector<MeshReference> ref;
  for (const auto& [pm, ps] : poses) ref.push_back(mesh_reference(m, pm, s, ps, size));
  const std::size_t n = poses.size();
  const auto add = [&](const char* query, const char* lib, double qps, const Errors& e) {
    rows.push_back(make_row(name, query, lib, qps, e, size));
  };
  // the error passes (untimed), impact's then FCL's; then each query timed side by side (the
  // contacts: impact's default, impact's fast_contacts and FCL's in turn)
  std::vector<std::function<void(std::size_t)>> boolean_bodies, distance_bodies, contact_bodies;
  Errors ieb, ied, iec;
  MeshConvexOptions<double> fast;
  fast.fast_contacts = true;
  {
    Errors &eb = ieb, &ed = ied, &ec = iec;
    for (std::size_t i = 0; i < n; ++i) {
      const auto& [pm, ps] = poses[i];
      const bool hit = mesh_convex_collides(tree, pm, s, ps);
      const auto d = mesh_convex_distance(tree, pm, s, ps);
      const auto c = mesh_convex_contacts(tree, pm, s, ps);
      if (ref[i].separated || ref[i].intersecting) {
        ++eb.n;
        ++ec.n;
        eb.mismatches += hit != ref[i].intersecting;
        ed.mismatches += d.intersecting != ref[i].intersecting;
        ec.mismatches += c.colliding != ref[i].intersecting;
      }
      if (ref[i].separated && !d.intersecting) ed.add(std::abs(d.distance - ref[i].distance));
    }
    boolean_bodies.emplace_back([&](std::size_t i) { g_sink = g_sink + mesh_convex_collides(tree, poses[i].first, s, poses[i].second); });
    distance_bodies.emplace_back(
        [&](std::size_t i) { g_sink = g_sink + mesh_convex_distance(tree, poses[i].first, s, poses[i].second).distance; });
    contact_bodies.emplace_back([&](std::size_t i) {
      g_sink = g_sink + double(mesh_convex_contacts(tree, poses[i].first, s, poses[i].second).contacts.size());
    });
    contact_bodies.emplace_back([&](std::size_t i) {
      g_sink = g_sink + double(mesh_convex_contacts(tree, poses[i].first, s, poses[i].second, fast).contacts.size());
    });
  }
#ifdef IMPACT_HAVE_FCL
  const auto model = test::make_fcl_model<fcl::OBBRSSd>(m);
  const auto shape = test::to_fcl_shape(s);
  const auto collide = [&](std::size_t i, std::size_t max_contacts, bool contacts) {
    fcl::CollisionRequestd req(max_contacts, contacts);
    fcl::CollisionResultd res;
    fcl::collide(model.get(), test::to_fcl(poses[i].first), shape.get(), test::to_fcl(poses[i].second), req, res);
    return contacts ? res.numContacts() : std::size_t(res.isCollision());
  };
  const auto distance = [&](std::size_t i) {
    fcl::DistanceRequestd req;
    fcl::DistanceResultd res;
    fcl::distance(model.get(), test::to_fcl(poses[i].first), shape.get(), test::to_fcl(poses[i].second), req, res);
    return res.min_distance;
  };
  Errors feb, fed, fec;
  {
    Errors &eb = feb, &ed = fed, &ec = fec;
    for (std::size_t i = 0; i < n; ++i) {
      const bool hit = collide(i, 1, false) != 0;
      const double d = distance(i);
      const bool any = collide(i, 100000, true) != 0;
      if (ref[i].separated || ref[i].intersecting) {
        ++eb.n;
        ++ec.n;
        eb.mismatches += hit != ref[i].intersecting;
        ed.mismatches += (d <= 0) != ref[i].intersecting;
        ec.mismatches += any != ref[i].intersecting;
      }
      if (ref[i].separated && d > 0) ed.add(std::abs(d - ref[i].distance));
    }
    boolean_bodies.emplace_back([&](std::size_t i) { g_sink = g_sink + double(collide(i, 1, false)); });
    distance_bodies.emplace_back([&](std::size_t i) { g_sink = g_sink + distance(i); });
    contact_bodies.emplace_back([&](std::size_t i) { g_sink = g_sink + double(collide(i, 100000, true)); });
  }
#endif
  const std::vector<double> qb = side_by_side_rates(n, min_time, boolean_bodies);
  const std::vector<double> qd = side_by_side_rates(n, min_time, distance_bodies);
  const std::vector<double> qc = side_by_side_rates(n, min_time, contact_bodies);
  add("boolean", "impact", qb[0], ieb);
  add("distance", "impact", qd[0], ied);
  add("contacts", "impact", qc[0], iec);
  add("contacts-mpr", "impact", qc[1], Errors{});
#ifdef IMPACT_HAVE_FCL
  add("boolean", "fcl", qb[1], feb);
  add("distance", "fcl", qd[1], fed);
  add("contacts", "fcl", qc[2], fec);
#endif
}


// ---- hull builds (--hulls) ----

/// One point set of the hull rows: its name and points (n x 3).
struct HullSet {
  std::string name;
  Vertices<double> points;
};

/// The generated point sets of the hull rows at n points (see the file comment).
std::vector<HullSet> generated_hull_sets(int n) {
  std::vector<HullSet> sets;
  test::Rng rng(1000 + std::uint64_t(n));
  const auto in_ball = [&] {
    for (;;) {
      const V3 x = rng.vec(-1, 1);
      if (x.squaredNorm() <= 1 && x.squaredNorm() > 1e-6) return x;
    }
  };
  const std::string size = "-" + std::to_string(n);
  HullSet ball{"ball" + size, Vertices<double>(n, 3)}, sphere{"sphere" + size, Vertices<double>(n, 3)};
  HullSet corners{"cube-corners" + size, Vertices<double>(n, 3)}, faces{"cube-faces" + size, Vertices<double>(n, 3)};
  HullSet flat{"flat-disc" + size, Vertices<double>(n, 3)};
  for (int i = 0; i < n; ++i) {
    ball.points.row(i) = in_ball().transpose();
    sphere.points.row(i) = in_ball().normalized().transpose();
    const V3 corner((i & 1) ? 1.0 : -1.0, (i & 2) ? 1.0 : -1.0, (i & 4) ? 1.0 : -1.0);
    corners.points.row(i) = (corner + rng.vec(-1e-6, 1e-6)).transpose();
    V3 f = rng.vec(-1, 1);
    if (i < 8) {
      f = corner;  // the cube's corners exactly, then points on its faces
    } else {
      const int axis = int(rng.index(3));
      f[axis] = rng.uniform() < 0.5 ? -1.0 : 1.0;
    }
    faces.points.row(i) = f.transpose();
    V3 d = in_ball();
    d.z() = 0;
    flat.points.row(i) = d.transpose();
  }
  sets.push_back(std::move(ball));
  sets.push_back(std::move(sphere));
  sets.push_back(std::move(corners));
  sets.push_back(std::move(faces));
  sets.push_back(std::move(flat));
  return sets;
}

/// One library's build of one set: median and range of the build time over the repetitions, and
/// the hull (vertex coordinates, triangles' planes, volume), or its refusal.
struct HullBuild {
  bool refused = false;
  std::string error;
  std::vector<double> times;  // seconds per build, one per repetition
  std::vector<std::array<double, 3>> vertices;  // sorted
  std::vector<std::array<double, 4>> planes;    // unit outward normal n, offset o: n . x = o
  int triangles = 0, faces = -1;
  double volume = 0;
};

/// The volume of a closed convex triangulation: tetrahedra from an interior point c (any order of
/// the triangles' vertices, since each is taken in absolute value).
template <class Corner>
double hull_volume(std::size_t triangles, const V3& c, const Corner& corner) {
  double v = 0;
  for (std::size_t t = 0; t < triangles; ++t) v += std::abs((corner(t, 0) - c).dot((corner(t, 1) - c).cross(corner(t, 2) - c))) / 6;
  return v;
}

/// Times `build` (which returns whether it built a hull) for at least `rep_time` seconds of whole
/// builds (at least one); appends the seconds per build to out.times.
template <class Build>
void time_builds(double rep_time, HullBuild& out, const Build& build) {
  std::size_t count = 0;
  const auto t0 = Clock::now();
  double t = 0;
  do {
    g_sink = g_sink + double(build());
    ++count;
    t = seconds_since(t0);
  } while (t < rep_time);
  out.times.push_back(t / double(count));
}

/// impact's hull of p (or its refusal), untimed.
HullBuild impact_hull_build(const Vertices<double>& p) {
  HullBuild b;
  ConvexHull<double> h;
  try {
    h = convex_hull(p);
  } catch (const InvalidInput& e) {
    b.refused = true;
    b.error = e.what();
  }
  if (b.refused) return b;
  for (Eigen::Index i = 0; i < h.vertices.rows(); ++i) b.vertices.push_back({h.vertices(i, 0), h.vertices(i, 1), h.vertices(i, 2)});
  std::sort(b.vertices.begin(), b.vertices.end());
  b.triangles = int(h.triangles.rows());
  b.faces = int(h.faces.size());
  const auto corner = [&](std::size_t t, int k) -> V3 { return h.vertices.row(h.triangles(Eigen::Index(t), k)).transpose(); };
  for (std::size_t t = 0; t < std::size_t(b.triangles); ++t) {
    const V3 n = (corner(t, 1) - corner(t, 0)).cross(corner(t, 2) - corner(t, 0)).normalized();
    b.planes.push_back({n.x(), n.y(), n.z(), n.dot(corner(t, 0))});
  }
  b.volume = hull_volume(std::size_t(b.triangles), h.centroid, corner);
  return b;
}

#ifdef IMPACT_HAVE_QHULL
/// qhull's hull of p (or its refusal), untimed.
HullBuild qhull_hull_build(const Vertices<double>& p, FILE* err) {
  HullBuild b;
  std::vector<double> xyz(p.data(), p.data() + 3 * p.rows());
  const bench::QhullHull q = bench::qhull_hull(xyz, int(p.rows()), err);
  if (!q.ok) {
    b.refused = true;
    b.error = q.error.empty() ? "qhull failed" : q.error;
    return b;
  }
  V3 c = V3::Zero();
  for (int v : q.vertices) {
    c += p.row(v).transpose();
    b.vertices.push_back({p(v, 0), p(v, 1), p(v, 2)});
  }
  c /= double(q.vertices.size());
  std::sort(b.vertices.begin(), b.vertices.end());
  b.triangles = int(q.triangles.size());
  for (const auto& pl : q.planes) b.planes.push_back({pl[0], pl[1], pl[2], -pl[3]});
  b.volume = hull_volume(q.triangles.size(), c, [&](std::size_t t, int k) -> V3 {
    return p.row(q.triangles[t][static_cast<std::size_t>(k)]).transpose();
  });
  return b;
}
#endif

#ifdef IMPACT_HAVE_QHULL
/// How far the points lie outside the hull of `planes` (the largest n . x - o; <= 0 inside).
double outside_distance(const std::vector<std::array<double, 3>>& points, const std::vector<std::array<double, 4>>& planes) {
  double worst = -std::numeric_limits<double>::infinity();
  for (const auto& x : points) {
    double d = -std::numeric_limits<double>::infinity();
    for (const auto& pl : planes) d = std::max(d, pl[0] * x[0] + pl[1] * x[1] + pl[2] * x[2] - pl[3]);
    worst = std::max(worst, d);
  }
  return worst;
}

/// The agreement of two builds of one set (see the file comment).
struct HullAgreement {
  bool agree = true;
  int vertex_difference = 0;   // vertices in one hull and not the other
  double max_outside = 0;      // of those, the farthest outside the other hull, relative to the extent
  double volume_difference = 0;  // |V_impact - V_qhull| / V_qhull
};

constexpr double kHullOutsideTolerance = 1e-9, kHullVolumeTolerance = 1e-9;

HullAgreement compare_hulls(const HullBuild& a, const HullBuild& b, double extent) {
  HullAgreement r;
  if (a.refused || b.refused) {
    r.agree = a.refused && b.refused;
    return r;
  }
  std::vector<std::array<double, 3>> only_a, only_b;
  std::set_difference(a.vertices.begin(), a.vertices.end(), b.vertices.begin(), b.vertices.end(), std::back_inserter(only_a));
  std::set_difference(b.vertices.begin(), b.vertices.end(), a.vertices.begin(), a.vertices.end(), std::back_inserter(only_b));
  r.vertex_difference = int(only_a.size() + only_b.size());
  if (!only_a.empty()) r.max_outside = std::max(r.max_outside, outside_distance(only_a, b.planes) / extent);
  if (!only_b.empty()) r.max_outside = std::max(r.max_outside, outside_distance(only_b, a.planes) / extent);
  r.volume_difference = std::abs(a.volume - b.volume) / b.volume;
  r.agree = r.max_outside <= kHullOutsideTolerance && r.volume_difference <= kHullVolumeTolerance;
  return r;
}
#endif

/// The meshes of the hull rows: `mesh_path` when given, else every mesh file in
/// $IMPACT_DATA_DIR/meshes (none without it or without a mesh loader), sorted by name.
std::vector<std::string> hull_mesh_files(const std::string& mesh_path) {
  if (!mesh_path.empty()) return {mesh_path};
  std::vector<std::string> files;
#ifdef IMPACT_HAVE_IO
  const char* d = std::getenv("IMPACT_DATA_DIR");
  if (!d || !*d) return files;
  const std::filesystem::path dir = std::filesystem::path(d) / "meshes";
  std::error_code ec;
  if (!std::filesystem::is_directory(dir, ec)) return files;
  for (const auto& e : std::filesystem::directory_iterator(dir, ec)) {
    const std::string ext = e.path().extension().string();
    if (ext == ".obj" || ext == ".off" || ext == ".ply" || ext == ".stl") files.push_back(e.path().string());
  }
  std::sort(files.begin(), files.end());
#endif
  return files;
}

/// The hull rows: build every set with impact and qhull, print the table, add the JSON rows;
/// returns the number of sets where the two disagree.
int run_hulls(const std::vector<int>& sizes, const std::string& mesh_path, int max_points, int reps, double min_time,
              const std::function<bool(const std::string&)>& wanted, std::vector<std::string>& items) {
  std::vector<HullSet> sets;
  for (int n : sizes)
    for (HullSet& s : generated_hull_sets(n))
      if (wanted(s.name)) sets.push_back(std::move(s));
  for (const std::string& f : hull_mesh_files(mesh_path)) {
    const std::string name = "mesh-" + f.substr(f.find_last_of('/') + 1);
    if (!wanted(name)) continue;
    TriangleMesh<double> m;
    try {
      m = bench::load_mesh_or_exit(f, "");
    } catch (const std::exception& e) {
      std::printf("%s: not loaded (%s)\n", name.c_str(), e.what());
      continue;
    }
    if (m.V.rows() > max_points) {
      std::printf("%s: %d vertices, more than --hull-max-points %d: left out\n", name.c_str(), int(m.V.rows()), max_points);
      continue;
    }
    sets.push_back({name, m.V});
  }
#ifdef IMPACT_HAVE_QHULL
  FILE* err = std::tmpfile();
#endif
  const double rep_time = min_time / reps;
  std::printf("hull builds: impact convex_hull() and %s, %d repetitions of >= %.3f s each; times per build, median (min-max)\n",
#ifdef IMPACT_HAVE_QHULL
              (std::string("qhull qh_new_qhull \"") + bench::qhull_options() + "\"").c_str(),
#else
              "qhull (absent: built without libqhull_r)",
#endif
              reps, rep_time);
  std::printf("%-26s %7s %15s %15s %24s %24s %9s %6s %9s %9s %5s\n", "set", "points", "impact V/T/F", "qhull V/T", "impact ms",
              "qhull ms", "qh/impact", "Vdiff", "outside", "vol diff", "agree");
  int mismatches = 0;
  for (const HullSet& s : sets) {
    const int n = int(s.points.rows());
    HullBuild ib = impact_hull_build(s.points);
    const auto ms = [](const HullBuild& b) {
      const auto [lo_it, hi_it] = std::minmax_element(b.times.begin(), b.times.end());
      char text[64];
      std::snprintf(text, sizeof text, "%.4g (%.4g-%.4g)", 1e3 * bench::summarize(b.times).median, 1e3 * *lo_it, 1e3 * *hi_it);
      return std::string(text);
    };
    const auto shape = [](const HullBuild& b, bool with_faces) {
      if (b.refused) return std::string("refused");
      return std::to_string(b.vertices.size()) + "/" + std::to_string(b.triangles) + (with_faces ? "/" + std::to_string(b.faces) : "");
    };
    const auto row = [&](const char* lib, const HullBuild& b) {
      JsonObject o;
      o.add("pair", "hull-" + s.name).add("query", "hull-build").add("library", lib).add("points", n);
      const bench::Summary t = bench::summarize(b.times);
      o.add("median_build_s", t.median).add("min_build_s", *std::min_element(b.times.begin(), b.times.end())).add("max_build_s", t.max);
      o.add("builds_per_s", 1 / t.median).add("refused", b.refused);
      if (b.refused) {
        o.add("error", b.error);
      } else {
        o.add("hull_vertices", b.vertices.size()).add("triangles", b.triangles).add("volume", b.volume);
        if (b.faces >= 0) o.add("faces", b.faces);
      }
      return o;
    };
    const auto impact_build = [&] {
      try {
        return convex_hull(s.points).vertices.rows() > 0;
      } catch (const InvalidInput&) {
        return false;
      }
    };
#ifdef IMPACT_HAVE_QHULL
    HullBuild qb = qhull_hull_build(s.points, err);
    const Vec3<double> lo = s.points.colwise().minCoeff().transpose(), hi = s.points.colwise().maxCoeff().transpose();
    const double extent = std::max((hi - lo).maxCoeff() / 2, std::numeric_limits<double>::min());
    std::vector<double> xyz(s.points.data(), s.points.data() + 3 * n);
    // the repetitions alternate between the two libraries, the first library alternating too
    for (int r = 0; r < reps; ++r) {
      const auto qhull_build = [&] { return bench::qhull_hull(xyz, n, err).ok; };
      if (r % 2 == 0) {
        time_builds(rep_time, ib, impact_build);
        time_builds(rep_time, qb, qhull_build);
      } else {
        time_builds(rep_time, qb, qhull_build);
        time_builds(rep_time, ib, impact_build);
      }
    }
    const HullAgreement a = compare_hulls(ib, qb, extent);
    mismatches += !a.agree;
    const double ratio = bench::summarize(qb.times).median / bench::summarize(ib.times).median;
    char ratio_text[32];
    std::snprintf(ratio_text, sizeof ratio_text, "%.2fx", ratio);
    std::printf("%-26s %7d %15s %15s %24s %24s %9s %6d %9.1e %9.1e %5s\n", s.name.c_str(), n, shape(ib, true).c_str(), shape(qb, false).c_str(),
                ms(ib).c_str(), ms(qb).c_str(), ratio_text, a.vertex_difference, a.max_outside, a.volume_difference, a.agree ? "yes" : "NO");
    JsonObject oi = row("impact", ib);
    oi.add("mismatches", int(!a.agree)).add("vertex_difference", a.vertex_difference).add("max_outside", a.max_outside);
    oi.add("volume_difference", a.volume_difference).add("qhull_time_over_impact", ratio);
    items.push_back(oi.str());
    items.push_back(row("qhull", qb).str());
#else
    for (int r = 0; r < reps; ++r) time_builds(rep_time, ib, impact_build);
    std::printf("%-26s %7d %15s %15s %24s %24s %9s %6s %9s %9s %5s\n", s.name.c_str(), n, shape(ib, true).c_str(), "absent", ms(ib).c_str(),
                "absent", "", "", "", "", "");
    items.push_back(row("impact", ib).str());
    JsonObject oq;
    oq.add("pair", "hull-" + s.name).add("query", "hull-build").add("library", "qhull").add("points", n).add("absent", true);
    items.push_back(oq.str());
#endif
    std::fflush(stdout);
  }
#ifdef IMPACT_HAVE_QHULL
  if (err) std::fclose(err);
#endif
  if (sets.empty()) std::printf("no hull set selected\n");
  return mismatches;
}

}  // namespace

int main(int argc, char** argv) {
  int n_poses = 1000;
  double min_time = 0.2;
  std::string json, mesh_path;
  int mesh_poses = 200;
  std::string only;
  bool hulls = false;
  int hull_max_points = 200000, hull_reps = 5;
  const char* usage =
      "usage: impact-convex-bench [--pairs N] [--json FILE] [--min-time SECONDS] [--mesh FILE] [--mesh-poses N] [--only TEXT]\n"
      "       impact-convex-bench --hulls [--hull-max-points N] [--hull-reps N] [--min-time SECONDS] [--mesh FILE] [--only TEXT] [--json FILE]\n";
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--pairs") {
      n_poses = int(bench::parse_integer(arg, bench::option_value(argc, argv, i, usage), 1, 10000000, usage));
    } else if (arg == "--json") {
      json = bench::option_value(argc, argv, i, usage);
    } else if (arg == "--min-time") {
      min_time = bench::parse_real(arg, bench::option_value(argc, argv, i, usage), 0, 3600, usage);
    } else if (arg == "--mesh") {
      mesh_path = bench::option_value(argc, argv, i, usage);
    } else if (arg == "--mesh-poses") {
      mesh_poses = int(bench::parse_integer(arg, bench::option_value(argc, argv, i, usage), 1, 10000000, usage));
    } else if (arg == "--only") {
      only = bench::option_value(argc, argv, i, usage);
    } else if (arg == "--hulls") {
      hulls = true;
    } else if (arg == "--hull-max-points") {
      hull_max_points = int(bench::parse_integer(arg, bench::option_value(argc, argv, i, usage), 10, 10000000, usage));
    } else if (arg == "--hull-reps") {
      hull_reps = int(bench::parse_integer(arg, bench::option_value(argc, argv, i, usage), 1, 1000, usage));
    } else {
      bench::reject_option(arg, usage);
    }
  }
  bench::check_writable(json, usage);
  if (hulls) {
    std::vector<int> sizes;
    for (int s = 10; s <= hull_max_points; s *= 10) sizes.push_back(s);
    std::vector<std::string> items;
    const int mismatches =
        run_hulls(sizes, mesh_path, hull_max_points, hull_reps, min_time, [&](const std::string& name) { return only.empty() || name.find(only) != std::string::npos; },
                  items);
    if (!json.empty()) {
      JsonObject top;
      top.add("bench", "impact-convex-bench").add("mode", "hulls").add("hull_max_points", hull_max_points).add("hull_reps", hull_reps);
      top.add("min_time_s", min_time);
      if (!only.empty()) top.add("only", only);
#ifdef IMPACT_HAVE_QHULL
      top.add("peer", std::string(qh_version2) + " (libqhull_r), qh_new_qhull \"" + bench::qhull_options() + "\"");
#else
      top.add("peer", "qhull absent (built without libqhull_r)");
#endif
      top.raw("rows", JsonObject::array(items));
      if (!impact::bench::write_file(json, top.str())) {
        std::fprintf(stderr, "impact-convex-bench: cannot write %s\n", json.c_str());
        return 1;
      }
    }
    if (mismatches) {
      std::fprintf(stderr, "impact-convex-bench: %d hull sets where impact and qhull disagree (see the agree column)\n", mismatches);
      return 3;
    }
    return 0;
  }
  TriangleMesh<double> mesh;
  std::string mesh_name = "generated torus";
  try {
    if (!mesh_path.empty()) {
      mesh = bench::load_mesh_or_exit(mesh_path, usage);
      mesh_name = mesh_path.substr(mesh_path.find_last_of('/') + 1);
    } else {
      mesh = make_torus(1.0, 0.35, 120, 30);
      test::Rng jitter(99);
      for (Eigen::Index i = 0; i < mesh.V.rows(); ++i) mesh.V.row(i) *= jitter.uniform(0.95, 1.05);
    }
    validate_mesh(mesh, mesh_name);
    bench::require_extent(mesh, mesh_name);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "impact-convex-bench: %s\n", e.what());
    return 1;
  }
  const test::ConvexZoo z;
  std::vector<Row> rows;
  std::printf("impact-convex-bench: %d poses per pair, each query timed for >= %.2f s; errors relative to the larger shape's size\n",
              n_poses, min_time);
  const auto wanted = [&](const std::string& name) { return only.empty() || name.find(only) != std::string::npos; };
  const auto pair = [&](const std::string& name, const auto& a, const auto& b, int np, double mt, std::vector<Row>& out) {
    if (wanted(name)) run_pair(name, a, b, np, mt, out);
  };
  // every unordered pair of the six shapes (21)
  pair("sphere-sphere", z.sphere, z.sphere, n_poses, min_time, rows);
  pair("sphere-capsule", z.sphere, z.capsule, n_poses, min_time, rows);
  pair("capsule-capsule", z.capsule, z.capsule, n_poses, min_time, rows);
  pair("sphere-box", z.sphere, z.box, n_poses, min_time, rows);
  pair("box-box", z.box, z.box, n_poses, min_time, rows);
  pair("capsule-box", z.capsule, z.box, n_poses, min_time, rows);
  pair("sphere-cylinder", z.sphere, z.cylinder, n_poses, min_time, rows);
  pair("capsule-cylinder", z.capsule, z.cylinder, n_poses, min_time, rows);
  pair("cylinder-cylinder", z.cylinder, z.cylinder, n_poses, min_time, rows);
  pair("cylinder-box", z.cylinder, z.box, n_poses, min_time, rows);
  pair("sphere-cone", z.sphere, z.cone, n_poses, min_time, rows);
  pair("capsule-cone", z.capsule, z.cone, n_poses, min_time, rows);
  pair("cylinder-cone", z.cylinder, z.cone, n_poses, min_time, rows);
  pair("cone-cone", z.cone, z.cone, n_poses, min_time, rows);
  pair("cone-box", z.cone, z.box, n_poses, min_time, rows);
  pair("sphere-hull", z.sphere, z.hull, n_poses, min_time, rows);
  pair("capsule-hull", z.capsule, z.hull, n_poses, min_time, rows);
  pair("cylinder-hull", z.cylinder, z.hull, n_poses, min_time, rows);
  pair("cone-hull", z.cone, z.hull, n_poses, min_time, rows);
  pair("box-hull", z.box, z.hull, n_poses, min_time, rows);
  pair("hull-hull", z.hull, z.hull, n_poses, min_time, rows);
  const auto mesh_row = [&](const std::string& name, const TriangleMesh<double>& m, const auto& s, int np, double mt, std::vector<Row>& out) {
    if (wanted(name)) run_mesh(name, m, s, np, mt, out);
  };
  if (wanted("mesh-sphere") || wanted("mesh-capsule") || wanted("mesh-cylinder") || wanted("mesh-cone") || wanted("mesh-box") ||
      wanted("mesh-hull")) {
    const double diag = (mesh.V.colwise().maxCoeff() - mesh.V.colwise().minCoeff()).norm();
    const double k = diag / 8 / 0.5;  // the zoo's shapes are about 0.5 in size (shape_size)
    std::printf("mesh: %s, %d triangles; shapes scaled by %.3g (1/8 of the bounding-box diagonal); %d poses per shape\n", mesh_name.c_str(),
                int(mesh.F.rows()), k, mesh_poses);
    Vertices<double> hv = z.hull.vertices * k;
    mesh_row("mesh-sphere", mesh, Sphere<double>(V3::Zero(), z.sphere.radius * k), mesh_poses, min_time, rows);
    mesh_row("mesh-capsule", mesh, Capsule<double>(z.capsule.radius * k, z.capsule.half_length * k), mesh_poses, min_time, rows);
    mesh_row("mesh-cylinder", mesh, Cylinder<double>(z.cylinder.radius * k, z.cylinder.half_length * k), mesh_poses, min_time, rows);
    mesh_row("mesh-cone", mesh, Cone<double>(z.cone.radius * k, z.cone.half_length * k), mesh_poses, min_time, rows);
    mesh_row("mesh-box", mesh, Box<double>(z.box.half * k), mesh_poses, min_time, rows);
    mesh_row("mesh-hull", mesh, convex_hull(hv), mesh_poses, min_time, rows);
  }

  if (rows.empty()) bench::exit_usage("--only " + only + " names no pair", usage);
  std::printf("%-18s %-12s %-7s %12s %10s %10s %5s %7s %14s %10s %10s\n", "pair", "query", "library", "queries/s", "mean err",
              "max err", "mism", "samples", "impact/FCL", "mean ang", "max ang");
  std::vector<std::string> items;
  int impact_mismatches = 0;  // impact's answers against the oracle's decided ones (FCL's are only reported)
  for (const Row& r : rows) {
    if (r.library == "impact") impact_mismatches += r.mismatches;
    double ratio = 0;
    if (r.library == "impact")
      for (const Row& o : rows)
        if (o.library == "fcl" && o.pair == r.pair && o.query == r.query) ratio = r.qps / o.qps;
    char ratio_text[32] = "";
    if (ratio > 0) std::snprintf(ratio_text, sizeof ratio_text, "%.2fx", ratio);
    char angle_text[2][32] = {"", ""};
    if (r.max_angle >= 0) {
      std::snprintf(angle_text[0], sizeof angle_text[0], "%.2e", r.mean_angle);
      std::snprintf(angle_text[1], sizeof angle_text[1], "%.2e", r.max_angle);
    }
    std::printf("%-18s %-12s %-7s %12.0f %10.2e %10.2e %5d %7d %14s %10s %10s\n", r.pair.c_str(), r.query.c_str(), r.library.c_str(),
                r.qps, r.mean_error, r.max_error, r.mismatches, r.samples, ratio_text, angle_text[0], angle_text[1]);
    JsonObject o;
    o.add("pair", r.pair).add("query", r.query).add("library", r.library).add("queries_per_s", r.qps).add("mean_error", r.mean_error);
    o.add("max_error", r.max_error).add("mismatches", r.mismatches).add("samples", r.samples);
    if (r.max_angle >= 0) o.add("mean_normal_angle", r.mean_angle).add("max_normal_angle", r.max_angle);
    items.push_back(o.str());
  }
  if (!json.empty()) {
    JsonObject top;
    top.add("bench", "impact-convex-bench").add("poses_per_pair", n_poses).add("min_time_s", min_time);
    if (!only.empty()) top.add("only", only);
    top.add("mesh", mesh_name).add("mesh_triangles", int(mesh.F.rows())).add("mesh_poses", mesh_poses);
#ifdef IMPACT_HAVE_FCL
    top.add("peer", "FCL 0.7, fcl::collide / fcl::distance on shape primitives, default requests (GST_LIBCCD); mesh rows: BVHModel<OBBRSS>");
#else
    top.add("peer", "none (built without FCL)");
#endif
    top.raw("rows", JsonObject::array(items));
    if (!impact::bench::write_file(json, top.str())) {
      std::fprintf(stderr, "impact-convex-bench: cannot write %s\n", json.c_str());
      return 1;
    }
  }
  if (impact_mismatches) {
    std::fprintf(stderr, "impact-convex-bench: %d impact answers disagree with the oracle away from touching (see the mism column)\n",
                 impact_mismatches);
    return 3;
  }
  return 0;
}
