// SPDX-License-Identifier: MIT
// impact-cloth-bench: the cloth collision step (cloth/collision_step.hpp) on the scenes of
// cloth_scenes.hpp, driven by the reference mass-spring model (cloth/cloth_model.hpp).
//
//   impact-cloth-bench [--scene drape|twist|layers|spin|shot] [--resolution N] [--layers K]
//                      [--steps S] [--dt DT] [--thickness H] [--method harmon|rigid|impulses]
//                      [--obstacle MESH] [--speed V] [--impulse-passes P] [--proximity-rounds R] [--threads T] [--every K]
//                      [--json FILE] [--write-final FILE.obj]
//
// Each step: the model proposes x1 from x0 and the velocities (dynamics), the collision step
// corrects it into x1' (collision), the velocities become (x1' - x0) / dt, and the new state is
// checked by verify_cloth_state, the exact oracle (triangle-triangle intersections with exact
// predicates, independent of the CCD the step uses), every step. Printed per step (every K-th
// with --every) and in total: dynamics and collision time (per stage: broad, proximity, impulses,
// zones, fail-safe), collisions handled, CCD passes, gatherings, candidate pairs, CCD tests run,
// zones, largest zone, fail-safe uses, exact
// intersections after the step, the minimum separation of non-adjacent primitives (searched up to
// 4 H; "inf" beyond), the kinetic energy the collision step removed (sum m (|v1|^2 - |v1'|^2) / 2
// over the free vertices) and the change of the free vertices' linear momentum by the collision
// step relative to their momentum (nonzero where obstacles or pinned vertices push; in pure
// self-contact the zones should keep it). In total also: the collision step's process CPU time
// (std::clock: with --threads 1 the time of the one thread, unaffected by waiting on a loaded
// machine), the zones' momentum error (ClothStepStats::zone_momentum_error, linear and angular),
// and the broad phase's work per step: candidate pairs, gatherings, CCD tests, and candidate tests
// settled by the distance bound.
// --method: harmon = every stage with Harmon's inelastic zones; rigid = rigid impact zones;
// impulses = proximity and CCD impulses only (then the fail-safe).
// --speed V: the bullet's speed in the shot scene (m/s, default 1000).
// --impulse-passes P: passes of CCD impulses before the zones (default: the library's, 3); with 0
// the zones take every CCD collision, which is where harmon and rigid differ.
// --proximity-rounds R: the proximity relaxation's round budget (ClothCollisionOptions::
// proximity_rounds, >= 1; default the library's, 30).
// Exit status 1 when any step ends with an exact intersection (the target is none, ever).
#include "bench_util.hpp"
#include "cloth_scenes.hpp"
#include "impact/cloth/collision_step.hpp"
#include "impact/cloth/verify_state.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

using namespace impact;
using impact::bench::Clock;
using impact::bench::JsonObject;

namespace {

struct Args {
  bench::ClothSceneConfig scene;
  int steps = -1;
  double dt = 1.0 / 120;
  double thickness = 0.004;
  std::string method = "harmon", obstacle, json, write_final;
  int threads = 1, every = 1, impulse_passes = -1, proximity_rounds = -1;
};

int default_steps(const std::string& scene) {
  if (scene == "twist") return 480;
  if (scene == "shot") return 60;
  return 240;
}

double ms_since(Clock::time_point t0) { return 1e3 * bench::seconds_since(t0); }

std::string num(double v) {
  if (!std::isfinite(v)) return "null";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.9g", v);
  return buf;
}

bool write_final_obj(const std::string& path, const bench::ClothScene& s, double t) {
  std::ofstream f(path);
  f.precision(9);
  int base = 1;
  const int per = static_cast<int>(s.x.rows()) / s.components, tris = static_cast<int>(s.rest.F.rows()) / s.components;
  for (int c = 0; c < s.components; ++c) {
    f << "o cloth" << c << "\n";
    for (int i = c * per; i < (c + 1) * per; ++i) f << "v " << s.x(i, 0) << ' ' << s.x(i, 1) << ' ' << s.x(i, 2) << "\n";
    for (int k = c * tris; k < (c + 1) * tris; ++k)
      f << "f " << s.rest.F(k, 0) - c * per + base << ' ' << s.rest.F(k, 1) - c * per + base << ' ' << s.rest.F(k, 2) - c * per + base << "\n";
    base += per;
  }
  for (const auto& r : s.rigid) {
    const RigidTransform<double> pose = r.pose(t);
    f << "o " << r.name << "\n";
    for (int i = 0; i < r.mesh.num_vertices(); ++i) {
      const Vec3<double> p = pose.apply(r.mesh.vertex(i));
      f << "v " << p.x() << ' ' << p.y() << ' ' << p.z() << "\n";
    }
    for (int k = 0; k < r.mesh.num_triangles(); ++k)
      f << "f " << r.mesh.F(k, 0) + base << ' ' << r.mesh.F(k, 1) + base << ' ' << r.mesh.F(k, 2) + base << "\n";
    base += r.mesh.num_vertices();
  }
  return bool(f);
}

constexpr const char* kUsage =
    "usage: impact-cloth-bench [--scene drape|twist|layers|spin|shot] [--resolution N] [--layers K] [--steps S]\n"
    "                          [--dt DT] [--thickness H] [--method harmon|rigid|impulses] [--obstacle MESH]\n"
    "                          [--speed V] [--impulse-passes P] [--proximity-rounds R] [--threads T] [--every K] [--json FILE]\n"
    "                          [--write-final FILE.obj]\n";

}  // namespace

int main(int argc, char** argv) {
  Args a;
  for (int i = 1; i < argc; ++i) {
    const std::string s = argv[i];
    auto next = [&] { return bench::option_value(argc, argv, i, kUsage); };
    auto integer = [&](long long lo, long long hi) { return int(bench::parse_integer(s, next(), lo, hi, kUsage)); };
    auto real = [&](double lo, double hi) { return bench::parse_real(s, next(), lo, hi, kUsage); };
    if (s == "--scene") a.scene.scene = next();
    else if (s == "--resolution") a.scene.resolution = integer(1, 2000);
    else if (s == "--layers") a.scene.layers = integer(1, 1000);
    else if (s == "--steps") a.steps = integer(1, 1000000);
    else if (s == "--dt") a.dt = real(0, 1e3);
    else if (s == "--thickness") a.thickness = real(0, 1e3);
    else if (s == "--method") a.method = next();
    else if (s == "--obstacle") a.obstacle = next();
    else if (s == "--speed") a.scene.speed = real(0, 1e9);
    else if (s == "--impulse-passes") a.impulse_passes = integer(0, 1000000);
    else if (s == "--proximity-rounds") a.proximity_rounds = integer(0, 1000000);
    else if (s == "--threads") a.threads = integer(1, 1024);
    else if (s == "--every") a.every = integer(1, 1000000);
    else if (s == "--json") a.json = next();
    else if (s == "--write-final") a.write_final = next();
    else bench::reject_option(s, kUsage);
  }
  if (a.steps < 0) a.steps = default_steps(a.scene.scene);
  std::setvbuf(stdout, nullptr, _IOLBF, 0);  // one line per step, also into a file
  if (!(a.dt > 0)) bench::exit_usage("--dt must be above 0", kUsage);
  if (!(a.thickness > 0)) bench::exit_usage("--thickness must be above 0", kUsage);
  if (a.method != "harmon" && a.method != "rigid" && a.method != "impulses")
    bench::exit_usage("--method must be harmon, rigid or impulses", kUsage);
  bench::check_writable(a.json, kUsage);
  bench::check_writable(a.write_final, kUsage, "--write-final");

  TriangleMesh<double> obstacle_mesh;
  std::unique_ptr<bench::ClothScene> scene;
  try {
    if (!a.obstacle.empty()) {
      obstacle_mesh = bench::read_mesh<double>(a.obstacle);  // without assimp: OBJ only
      a.scene.obstacle = &obstacle_mesh;
    }
    scene = bench::make_cloth_scene(a.scene);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "impact-cloth-bench: %s\n", e.what());
    return 2;
  }
  bench::ClothScene& s = *scene;
  const int nv = static_cast<int>(s.x.rows()), nt = static_cast<int>(s.rest.F.rows());

  ClothCollisionOptions<double> opt;
  opt.thickness = a.thickness;
  opt.friction = s.friction;
  opt.threads = a.threads;
  opt.zones = a.method != "impulses";
  opt.zone_method = a.method == "rigid" ? ZoneMethod::Rigid : ZoneMethod::Harmon;
  if (a.impulse_passes >= 0) opt.impulse_passes = a.impulse_passes;
  if (a.proximity_rounds >= 0) opt.proximity_rounds = a.proximity_rounds;
  ClothCollisionWorkspace<double> workspace;
  Eigen::Matrix<double, Eigen::Dynamic, 1> inverse_mass(nv);
  for (int i = 0; i < nv; ++i) inverse_mass(i) = s.model.kinematic(i) ? 0.0 : 1.0 / s.model.mass(i);
  ClothVerifyOptions vopt;
  vopt.distance_cutoff = 4 * a.thickness;
  ImplicitStepOptions<double> iopt;
  iopt.dt = a.dt;

  std::printf("impact-cloth-bench: scene %s, method %s, %d vertices, %d triangles, %d cloth(s), %zu obstacle(s), dt %.6g s, h %.6g m, "
              "%d steps, %d impulse pass(es), %d thread(s)\n",
              s.name.c_str(), a.method.c_str(), nv, nt, s.components, s.rigid.size(), a.dt, a.thickness, a.steps, opt.impulse_passes, a.threads);
  std::printf("%5s %8s %8s %7s %7s %7s %7s %7s %6s %4s %4s %8s %7s %5s %6s %3s %5s %10s %11s %9s\n", "step", "dyn_ms", "coll_ms", "broad",
              "prox", "impul", "zones", "fsafe", "coll", "pass", "gath", "cand", "ccd", "zones", "lgst", "fs", "inter", "min_sep", "E_removed", "dp_rel");

  std::vector<std::string> rows;
  std::vector<double> dyn_ms, coll_ms, coll_cpu_ms;
  double stage_ms[5] = {0, 0, 0, 0, 0};
  std::size_t candidates_total = 0, ccd_total = 0, skipped_total = 0, kept_total = 0, gatherings_total = 0;
  std::size_t max_inter = 0, total_inter_steps = 0, failsafe_steps = 0, collisions_total = 0, zones_total = 0, largest_zone = 0;
  double min_sep = std::numeric_limits<double>::infinity(), energy_removed = 0, worst_dp = 0, zone_dp = 0, zone_dl = 0;
  ScriptedVertices<double> script;
  for (int step = 0; step < a.steps; ++step) {
    const double t0 = step * a.dt, t1 = (step + 1) * a.dt;
    // dynamics
    auto c0 = Clock::now();
    if (s.script) s.script(t1, script);
    const ImplicitStepResult<double> pred = implicit_euler_step(s.model, s.x, s.v, iopt, s.script ? &script : nullptr);
    const double dms = ms_since(c0);
    // collision
    Vertices<double> x1 = pred.x1;
    const ClothObstacles<double> obstacles = s.obstacles(t0, t1);
    c0 = Clock::now();
    const std::clock_t cpu0 = std::clock();
    ClothStepStats st;
    try {
      st = cloth_collision_step<double>(s.rest.F, inverse_mass, s.x, x1, obstacles, opt, &workspace);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "impact-cloth-bench: step %d: %s\n", step, e.what());
      return 1;
    }
    const double cms = ms_since(c0);
    const double ccpu = 1e3 * double(std::clock() - cpu0) / CLOCKS_PER_SEC;
    // energy and momentum the collision step took out
    double e_removed = 0;
    Vec3<double> p_before = Vec3<double>::Zero(), p_after = Vec3<double>::Zero();
    double p_scale = 0;
    for (int i = 0; i < nv; ++i) {
      if (inverse_mass(i) == 0) continue;
      const double m = s.model.mass(i);
      const Vec3<double> vb = (pred.x1.row(i) - s.x.row(i)).transpose() / a.dt, va = (x1.row(i) - s.x.row(i)).transpose() / a.dt;
      e_removed += 0.5 * m * (vb.squaredNorm() - va.squaredNorm());
      p_before += m * vb;
      p_after += m * va;
      p_scale += m * vb.norm();
    }
    const double dp_rel = p_scale > 0 ? (p_after - p_before).norm() / p_scale : 0.0;
    s.v = (x1 - s.x) / a.dt;
    s.x = x1;
    // the oracle
    const ClothStateReport rep = verify_cloth_state<double>(s.rest.F, s.x, obstacles, ObstacleTime::End, vopt);

    const std::size_t collisions = st.proximity.collisions + st.impulses.collisions + st.zones.collisions + st.failsafe.collisions;
    const int passes = st.impulses.passes + st.zones.passes + st.failsafe.passes;
    dyn_ms.push_back(dms);
    coll_ms.push_back(cms);
    coll_cpu_ms.push_back(ccpu);
    const double stg[5] = {st.broad.ms, st.proximity.ms, st.impulses.ms, st.zones.ms, st.failsafe.ms};
    for (int k = 0; k < 5; ++k) stage_ms[k] += stg[k];
    max_inter = std::max(max_inter, rep.intersections);
    total_inter_steps += rep.intersections > 0;
    failsafe_steps += st.failsafe_used;
    collisions_total += collisions;
    candidates_total += st.candidates_vf + st.candidates_ee;
    ccd_total += st.ccd_tests;
    skipped_total += st.ccd_skipped;
    kept_total += st.ccd_kept;
    gatherings_total += static_cast<std::size_t>(st.broad.passes);
    zones_total += st.zone_count;
    largest_zone = std::max(largest_zone, st.largest_zone);
    min_sep = std::min(min_sep, rep.min_distance);
    energy_removed += e_removed;
    worst_dp = std::max(worst_dp, dp_rel);
    zone_dp = std::max(zone_dp, st.zone_momentum_error);
    zone_dl = std::max(zone_dl, st.zone_angular_momentum_error);
    if (step % a.every == 0 || step + 1 == a.steps || rep.intersections > 0)
      std::printf("%5d %8.2f %8.2f %7.2f %7.2f %7.2f %7.2f %7.2f %6zu %4d %4d %8zu %7zu %5zu %6zu %3d %5zu %10.3e %11.4e %9.2e\n", step, dms, cms, stg[0],
                  stg[1], stg[2], stg[3], stg[4], collisions, passes, st.broad.passes, st.candidates_vf + st.candidates_ee, st.ccd_tests, st.zone_count,
                  st.largest_zone, st.failsafe_used ? 1 : 0, rep.intersections, rep.min_distance, e_removed, dp_rel);
    JsonObject row;
    row.add("step", step).add("dynamics_ms", dms).add("collision_ms", cms).add("collision_cpu_ms", ccpu).add("collisions", collisions).add("zones", st.zone_count)
        .add("largest_zone", st.largest_zone).add("failsafe", st.failsafe_used).add("intersections", rep.intersections)
        .add("gatherings", st.broad.passes).add("proximity_rounds", st.proximity.passes).add("proximity_converged", st.proximity_converged).add("candidates", st.candidates_vf + st.candidates_ee).add("ccd_tests", st.ccd_tests)
        .add("ccd_skipped", st.ccd_skipped).add("ccd_kept", st.ccd_kept).raw("min_separation", num(rep.min_distance)).add("energy_removed", e_removed)
        .add("zone_momentum_error", st.zone_momentum_error).add("zone_angular_momentum_error", st.zone_angular_momentum_error);
    rows.push_back(row.str());
  }

  const bench::Summary cs = bench::summarize(coll_ms), ds = bench::summarize(dyn_ms), cc = bench::summarize(coll_cpu_ms);
  std::printf("totals: dynamics %.2f ms/step mean; collision %.2f ms/step mean (median %.2f, max %.2f): broad %.2f, proximity %.2f, "
              "impulses %.2f, zones %.2f, fail-safe %.2f ms/step\n",
              ds.mean, cs.mean, cs.median, cs.max, stage_ms[0] / a.steps, stage_ms[1] / a.steps, stage_ms[2] / a.steps, stage_ms[3] / a.steps,
              stage_ms[4] / a.steps);
  std::printf("totals: collision CPU time (process, one thread: the wall time above includes waiting on a loaded machine) %.2f ms/step "
              "mean, max %.2f\n",
              cc.mean, cc.max);
  std::printf("totals: collisions %zu, zones %zu, largest zone %zu, fail-safe in %zu step(s), exact intersections: max %zu, in %zu step(s); "
              "min separation %s m (h = %g); kinetic energy removed %.6g J; worst relative momentum change %.3g\n",
              collisions_total, zones_total, largest_zone, failsafe_steps, max_inter, total_inter_steps, num(min_sep).c_str(), a.thickness,
              energy_removed, worst_dp);
  std::printf("totals: zones' momentum error (largest, relative): linear %.3g, angular about x0 %.3g\n", zone_dp, zone_dl);
  std::printf("totals: broad phase per step: %.1f candidate pairs, %.2f gatherings; %.1f CCD tests, %.1f candidate tests settled by the "
              "distance bound, %.1f re-tests avoided by a proof kept from an earlier pass\n",
              double(candidates_total) / a.steps, double(gatherings_total) / a.steps, double(ccd_total) / a.steps, double(skipped_total) / a.steps,
              double(kept_total) / a.steps);

  if (!a.json.empty()) {
    JsonObject totals;
    totals.add("collision_ms_mean", cs.mean).add("collision_ms_max", cs.max).add("collision_cpu_ms_mean", cc.mean).add("dynamics_ms_mean", ds.mean)
        .add("intersections_max", max_inter).raw("min_separation", num(min_sep)).add("failsafe", failsafe_steps)
        .add("energy_removed", energy_removed).add("zone_momentum_error", zone_dp).add("zone_angular_momentum_error", zone_dl);
    JsonObject out;
    out.add("bench", "impact-cloth-bench").add("scene", s.name).add("method", a.method).add("vertices", nv).add("triangles", nt)
        .add("steps", a.steps).add("impulse_passes", opt.impulse_passes).raw("rows", JsonObject::array(rows)).raw("totals", totals.str());
    if (!bench::write_file(a.json, out.str())) {
      std::fprintf(stderr, "impact-cloth-bench: cannot write %s\n", a.json.c_str());
      return 1;
    }
  }
  if (!a.write_final.empty() && !write_final_obj(a.write_final, s, a.steps * a.dt)) {
    std::fprintf(stderr, "impact-cloth-bench: cannot write %s\n", a.write_final.c_str());
    return 1;
  }
  return max_inter > 0 ? 1 : 0;
}
