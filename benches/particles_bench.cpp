// SPDX-License-Identifier: MIT
// impact-particles-bench: particles against a triangle mesh, run time against error.
//
//   impact-particles-bench [MESH] [--particles N] [--steps S] [--dt DT] [--naive-particles M]
//                          [--ref-particles R] [--substeps K] [--free-ball F] [--sort-every N] [--float] [--leaf L] [--grid G]
//                          [--compact C] [--wide 0|1] [--threads T] [--seed X] [--quick] [--json FILE]
//
// Without MESH a built-in closed mesh (a torus) is used. The particles start uniformly in the
// mesh's bounding box (inside and outside the mesh, never exactly on it: such starts are drawn
// again, and the count is printed) with random directions and speeds whose
// displacement per step is about 1% of the box diagonal, under gravity (-y), inside a container
// box slightly larger than the mesh's box, with an elastic material (restitution 1, no friction)
// so that energy should be conserved. The same initial particles run with
//  - backtrack:  continuous stepping, BVH first-hit ray casts;
//  - backtrack-wide: the same with the mesh collider's ray casts through a WideBvh (--wide 1, the
//                default; MeshCollider::wide_tree), its build printed and not timed;
//  - project:    unconstrained step, then projection to the closest surface point (BVH);
//  - naive:      backtracking with every triangle tested (a one-leaf tree), for the first M
//                particles;
//  - reference:  backtracking with K sub-steps per step, for the first R particles: the
//                accuracy reference of the position errors;
//  - embree-user: (when built with Embree 3) the loop a user would write on Embree: the mesh and
//                the container in one RTC_BUILD_QUALITY_HIGH scene, one rtcIntersect1 (float) per
//                leg of the free-flight chord, at a hit a move there backed off 1e-5 of the
//                diagonal along the chord and the same elastic response (reflection about the
//                hit's normal), at most max_iterations legs a step; its escapes are audited like
//                backtracking's (every move it makes, against the mesh, exactly).
// --free-ball F sets StepOptions::free_ball_factor (0 disables the free-ball cache); --sort-every N
// reorders the particles along a Morton curve every N steps (spatial_order, timed; 0: never);
// --float runs everything in single precision (double by default); --leaf L sets the tree's
// maximum leaf size (BuildConfig::leaf_size, 1 by default); --grid G gives the backtracking,
// reference and projection mesh colliders a DistanceGrid of G cells along the box's longest side
// (64 by default; 0: none), built once before the runs and not timed (its build time is printed);
// --compact C gives the backtracking and reference colliders a CompactBvh copy of the tree with
// leaves of up to C triangles for their ray casts (4 by default; 0: none).
// --threads T (default: the hardware concurrency) adds the threads rows: backtracking and
// projection stepped by step_particles with StepOptions::threads = 1 and = T, both timed by the
// wall clock in the same run, and checked to end in exactly the same state (positions and
// velocities bit for bit). Their speed-up is printed by the wall clock and by the CPU times (one
// thread's CPU time over max(the caller's CPU time, the workers' per worker)), which is what an
// idle machine would show when the wall clock measures the neighbours too.
// --quick runs only the reference, backtrack-wide and embree-user rows (for profiling and for
// comparing builds: the other rows, the threads rows included, are left out).
// Each method runs twice from the same start: once timed, once audited for escapes (the audit's
// tree walks between steps would disturb the timing); the bench checks that both end alike.
// Reported per method: particle-steps per second (stepping only, single thread, thread CPU time), particles
// escaped, the mean and max distance to the reference's final positions, the mean relative energy
// error, and the share of particle-steps with at least one impact. Escaped: for the backtracking
// methods, a particle one of whose travelled legs (step_particle's on_leg) crosses a triangle,
// i.e. passed through the surface (valid on open meshes too); for projection, which moves
// particles by jumps, a step whose start-to-end segment crosses the mesh an odd number of times,
// i.e. the particle changed sides (exact for closed meshes only); for every method, a particle
// outside the container.
#include "bench_util.hpp"
#include "impact/geometry/mesh_generators.hpp"
#include "impact/response/particle_step.hpp"
#include "support/exact_triangle.hpp"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>
#include <tuple>

#ifdef IMPACT_HAVE_EMBREE
#include "embree_peer.hpp"
#endif

using namespace impact;
using impact::bench::process_seconds;
using impact::bench::thread_seconds;

namespace {

struct Args {
  std::string mesh, json;
  int particles = 20000, steps = 100, naive_particles = 20, ref_particles = 1000, substeps = 16;
  double dt = 1e-2, free_ball = 8;
  int sort_every = 10;
  bool use_float = false;
  int leaf = 1;
  int grid = 64;
  int compact = 4;
  int wide = 1;
  int threads = 0;
  bool quick = false;
  std::uint64_t seed = 1;
};

struct Row {
  std::string method;
  int threads = 1;
  int particles = 0, steps = 0;
  double rate = 0, pos_err_mean = 0, pos_err_max = 0, energy_rel_err = 0, impact_share = 0;
  int escaped = 0;
};

/// Crossings of the segment a -> b with the mesh (every triangle hit, watertight rule).
template <class S> int crossings(const MeshBvh<Aabb<S>>& m, const Vec3<S>& a, const Vec3<S>& b) {
  using BV = Aabb<S>;
  const Vec3<S> d = b - a;
  if (d.squaredNorm() == 0) return 0;
  const PreparedRay<S> pr(Ray<S>(a, d, S(1)));
  const Vec3<S> inv = detail::safe_inverse(d);
  int n = 0;
  traverse(
      m.tree(), [&](const BV& bv) { return detail::ray_box_entry(a, inv, bv, S(1)).has_value(); },
      [&](std::int32_t k) {
        n += intersect_ray_triangle(pr, m.triangle(k)).has_value() ? 1 : 0;
        return true;
      });
  return n;
}

/// Whether p lies exactly on a triangle of the mesh (exact test).
template <class S> bool on_mesh(const MeshBvh<Aabb<S>>& m, const Vec3<S>& p) {
  bool on = false;
  traverse(
      m.tree(), [&](const Aabb<S>& bv) { return bv.contains(p); },
      [&](std::int32_t k) {
        on = test::triangles_intersect_exact(m.triangle(k), Triangle<S>(p, p, p));
        return !on;
      });
  return on;
}

template <class S> double energy(const Particle<S>& p, const Vec3<S>& g, const Vec3<S>& origin) {
  return 0.5 * double(p.velocity.squaredNorm()) - double(g.dot(p.position - origin));
}

template <class S> struct RunResult {
  std::vector<Particle<S>> final;
  double seconds = 0;
  int escaped = 0;
  double energy_rel_err = 0;
  double impact_share = 0;
};

/// The particles of one run and what the bench tracks for each (its initial index, whether it
/// escaped, its start energy), kept in step when the particles are re-sorted: the bookkeeping that
/// run() and run_embree() share.
template <class S> struct TrackedParticles {
  std::vector<Particle<S>> ps;
  std::vector<std::uint32_t> id;  // id[i]: the initial index of the particle now at i
  std::vector<char> escaped;
  std::vector<double> e0;  // start energies
  Vec3<S> g, origin;       // gravity and the zero of the potential energy

  TrackedParticles(std::vector<Particle<S>> initial, const Vec3<S>& gravity, const Vec3<S>& energy_origin)
      : ps(std::move(initial)), id(ps.size()), escaped(ps.size(), 0), e0(ps.size()), g(gravity), origin(energy_origin) {
    for (std::size_t i = 0; i < ps.size(); ++i) {
      id[i] = static_cast<std::uint32_t>(i);
      e0[i] = energy(ps[i], g, origin);
    }
  }

  /// Reorders the particles along a Morton curve (spatial_order), their initial indices, escape
  /// flags and start energies with them: the bench's --sort-every step.
  void sort_spatially() {
    const auto order = spatial_order(ps);
    std::vector<Particle<S>> sorted(ps.size());
    std::vector<std::uint32_t> sorted_id(ps.size());
    std::vector<char> sorted_esc(ps.size());
    std::vector<double> sorted_e0(ps.size());
    for (std::size_t i = 0; i < order.size(); ++i) {
      sorted[i] = ps[order[i]];
      sorted_id[i] = id[order[i]];
      sorted_esc[i] = escaped[order[i]];
      sorted_e0[i] = e0[order[i]];
    }
    ps.swap(sorted);
    id.swap(sorted_id);
    escaped.swap(sorted_esc);
    e0.swap(sorted_e0);
  }

  /// Sets r's escape count, mean relative energy error and final states (back in the initial
  /// order).
  void finish(RunResult<S>& r) const {
    double err = 0;
    for (std::size_t i = 0; i < ps.size(); ++i) {
      r.escaped += escaped[i];
      err += std::abs(energy(ps[i], g, origin) - e0[i]) / std::max(e0[i], 1e-300);
    }
    r.energy_rel_err = ps.empty() ? 0 : err / double(ps.size());
    r.final.resize(ps.size());
    for (std::size_t i = 0; i < ps.size(); ++i) r.final[id[i]] = ps[i];
  }
};

template <class S>
RunResult<S> run(std::vector<Particle<S>> initial, const ColliderSet<S, Aabb<S>>& cs, const MeshBvh<Aabb<S>>& audit_mesh, const Aabb<S>& container,
                 const StepOptions<S>& opt, double dt, int steps, int substeps, bool audit, int sort_every, bool wall = false) {
  // thread CPU time (the machine may be shared, the method rows step on one thread), or the wall
  // clock (the threads rows: a parallel run spends CPU time on several threads)
  const auto thread_seconds = [wall] { return wall ? bench::wall_seconds() : bench::thread_seconds(); };
  RunResult<S> r;
  TrackedParticles<S> t(std::move(initial), opt.gravity, container.min);
  std::vector<Particle<S>>& ps = t.ps;
  std::vector<char>& escaped = t.escaped;
  // backtracking moves particles along legs, which are audited; projection by jumps: its sides
  const bool audit_legs = cs.meshes.empty() || cs.meshes[0].strategy != Strategy::Project;
  std::vector<Vec3<S>> before(ps.size());
  StepStats st;
  const S h = S(dt / substeps);
  for (int s = 0; s < steps; ++s) {
    if (sort_every > 0 && s % sort_every == 0) {
      const double t0 = thread_seconds();
      t.sort_spatially();
      r.seconds += thread_seconds() - t0;
    }
    for (std::size_t i = 0; i < ps.size(); ++i) before[i] = ps[i].position;
    const double t0 = thread_seconds();
    if (audit && audit_legs) {  // the same steps, one particle at a time, watching every leg
      for (int k = 0; k < substeps; ++k)
        for (std::size_t i = 0; i < ps.size(); ++i)
          st += step_particle(ps[i], cs, h, opt, [&](const Vec3<S>& from, const Vec3<S>& to) {
            if (crossings(audit_mesh, from, to) > 0) escaped[i] = 1;
          });
    } else {
      for (int k = 0; k < substeps; ++k) st += step_particles(ps, cs, h, opt);
    }
    r.seconds += thread_seconds() - t0;
    if (!audit) continue;
    for (std::size_t i = 0; i < ps.size(); ++i) {
      if (escaped[i]) continue;
      if (!container.contains(ps[i].position) || (!audit_legs && crossings(audit_mesh, before[i], ps[i].position) % 2 == 1))
        escaped[i] = 1;
    }
  }
  t.finish(r);
  r.impact_share = double(st.particles_hit) / (double(ps.size()) * steps * substeps);
  return r;
}

/// The timed run without the audit (its tree walks between steps would evict the caches the
/// stepping uses), then the same run audited for escapes; stepping is deterministic, so both must
/// end in the same state, which is checked.
template <class S>
RunResult<S> measure(const std::vector<Particle<S>>& ps, const ColliderSet<S, Aabb<S>>& cs, const MeshBvh<Aabb<S>>& audit_mesh,
                     const Aabb<S>& container, const StepOptions<S>& opt, double dt, int steps, int substeps, int sort_every) {
  const RunResult<S> timed = run(ps, cs, audit_mesh, container, opt, dt, steps, substeps, false, sort_every);
  RunResult<S> audited = run(ps, cs, audit_mesh, container, opt, dt, steps, substeps, true, sort_every);
  for (std::size_t i = 0; i < ps.size(); ++i)
    if (timed.final[i].position != audited.final[i].position || timed.final[i].velocity != audited.final[i].velocity) {
      std::fprintf(stderr, "impact-particles-bench: the timed and the audited runs differ (particle %zu)\n", i);
      std::exit(1);
    }
  audited.seconds = timed.seconds;
  return audited;
}


#ifdef IMPACT_HAVE_EMBREE
/// The peer a user would write with Intel Embree 3: the mesh and the container's 12 triangles in
/// one scene (RTC_BUILD_QUALITY_HIGH, float vertices), and a step loop of its own: the chord of
/// the free flight over the rest of the step cast with one rtcIntersect1 per leg; at a hit the
/// particle moves there, backed off along the chord by `offset`, and its velocity at the time of
/// impact (the chord fraction of the rest of the step) is reflected about the hit's normal
/// turned against the chord (the elastic material: restitution 1, no friction); at most
/// max_iterations legs a step, the rest of the step dropped after the last.
class EmbreeParticles {
 public:
  EmbreeParticles(const TriangleMesh<double>& m, const Aabb<double>& container) {
    scene_.add(m.V, m.F);
    // the container: 12 triangles
    Vertices<double> V(8, 3);
    for (int i = 0; i < 8; ++i)
      V.row(i) << (i & 1 ? container.max.x() : container.min.x()), (i & 2 ? container.max.y() : container.min.y()),
          (i & 4 ? container.max.z() : container.min.z());
    Faces F(12, 3);
    F << 0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4, 2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3, 7, 5;
    scene_.add(V, F);
    scene_.commit();
  }

  /// One particle's step of length dt (see the class comment); on_leg(from, to) sees every move.
  template <class S, class OnLeg>
  bool step(Particle<S>& p, S dt, const Vec3<S>& g, int max_iterations, S offset, OnLeg&& on_leg) const {
    Vec3<S> x = p.position, v = p.velocity;
    S left = dt;
    bool hit_any = false;
    for (int it = 0; it < max_iterations && left > S(0); ++it) {
      const Vec3<S> c = v * left + S(0.5) * left * left * g;  // the chord of the free flight
      const RTCRayHit rh = scene_.first_hit(x, c, 1.0f);
      if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) {
        on_leg(x, Vec3<S>(x + c));
        x += c;
        v += left * g;
        left = S(0);
        break;
      }
      hit_any = true;
      const S t = S(rh.ray.tfar), len = c.norm();
      Vec3<S> n(S(rh.hit.Ng_x), S(rh.hit.Ng_y), S(rh.hit.Ng_z));
      n.normalize();
      if (n.dot(c) > S(0)) n = -n;
      const S back = len > S(0) ? std::min(t, offset / len) : t;
      const Vec3<S> to = x + (t - back) * c;
      on_leg(x, to);
      x = to;
      const S tau = t * left;
      v += tau * g;
      const S vn = v.dot(n);
      if (vn < S(0)) v -= S(2) * vn * n;
      left -= tau;
    }
    p.position = x;
    p.velocity = v;
    return hit_any;
  }

 private:
  bench::EmbreeScene scene_;
};

/// The Embree peer's run: the same particles, steps, sorting and audit as run().
template <class S>
RunResult<S> run_embree(std::vector<Particle<S>> initial, const EmbreeParticles& e, const MeshBvh<Aabb<S>>& audit_mesh, const Aabb<S>& container,
                        const StepOptions<S>& opt, double dt, int steps, bool audit, int sort_every, S offset) {
  RunResult<S> r;
  TrackedParticles<S> t(std::move(initial), opt.gravity, container.min);
  std::vector<Particle<S>>& ps = t.ps;
  std::vector<char>& escaped = t.escaped;
  std::size_t hits = 0;
  for (int s = 0; s < steps; ++s) {
    if (sort_every > 0 && s % sort_every == 0) {
      const double t0 = thread_seconds();
      t.sort_spatially();
      r.seconds += thread_seconds() - t0;
    }
    const double t0 = thread_seconds();
    for (std::size_t i = 0; i < ps.size(); ++i) {
      if (audit)
        hits += e.step(ps[i], S(dt), opt.gravity, opt.max_iterations, offset, [&](const Vec3<S>& from, const Vec3<S>& to) {
          if (crossings(audit_mesh, from, to) > 0) escaped[i] = 1;
        });
      else
        hits += e.step(ps[i], S(dt), opt.gravity, opt.max_iterations, offset, [](const Vec3<S>&, const Vec3<S>&) {});
    }
    r.seconds += thread_seconds() - t0;
    if (audit)
      for (std::size_t i = 0; i < ps.size(); ++i)
        if (!container.contains(ps[i].position)) escaped[i] = 1;
  }
  t.finish(r);
  r.impact_share = double(hits) / (double(ps.size()) * steps);
  return r;
}
#endif

/// A threads row: the run (wall clock, as RunResult::seconds) and the CPU time of the calling
/// thread and of the process over the whole run.
template <class S> struct ThreadsRun {
  RunResult<S> r;
  double caller = 0, process = 0;
};

/// The threads rows: the timed run (no audit) with opt.threads = 1 and = threads; exits when the
/// two end differently. Returns {1-thread, T-thread}.
template <class S>
std::pair<ThreadsRun<S>, ThreadsRun<S>> measure_threads(const std::vector<Particle<S>>& ps, const ColliderSet<S, Aabb<S>>& cs,
                                                        const MeshBvh<Aabb<S>>& audit_mesh, const Aabb<S>& container, StepOptions<S> opt,
                                                        double dt, int steps, int sort_every, int threads) {
  ThreadsRun<S> out[2];
  for (int k = 0; k < 2; ++k) {
    opt.threads = k == 0 ? 1 : threads;
    const double c0 = thread_seconds(), p0 = process_seconds();
    out[k].r = run(ps, cs, audit_mesh, container, opt, dt, steps, 1, false, sort_every, true);
    out[k].caller = thread_seconds() - c0;
    out[k].process = process_seconds() - p0;
  }
  for (std::size_t i = 0; i < ps.size(); ++i)
    if (out[0].r.final[i].position != out[1].r.final[i].position || out[0].r.final[i].velocity != out[1].r.final[i].velocity) {
      std::fprintf(stderr, "impact-particles-bench: %d threads end differently from 1 (particle %zu)\n", threads, i);
      std::exit(1);
    }
  return {std::move(out[0]), std::move(out[1])};
}

}  // namespace

template <class S> int run_all(const Args& a) {
  using BV = Aabb<S>;
  TriangleMesh<S> mesh;
  try {
    mesh = a.mesh.empty() ? make_torus<S>(1.0, 0.4, 192, 96) : bench::read_mesh<S>(a.mesh);
    bench::require_extent(mesh, a.mesh);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "impact-particles-bench: %s\n", e.what());
    return 1;
  }
  const std::string mesh_name = a.mesh.empty() ? "generated:torus" : a.mesh;

  MeshBvhConfig cfg;
  cfg.build.leaf_size = a.leaf;
  const MeshBvh<BV> bvh(mesh, cfg);
  MeshBvhConfig one_leaf;
  one_leaf.build.leaf_size = mesh.num_triangles();
  const MeshBvh<BV> flat(mesh, one_leaf);

  Aabb<S> box;
  for (int i = 0; i < mesh.num_vertices(); ++i) box.extend(mesh.vertex(i));
  const double diag = 2 * box.half_diagonal();
  const Aabb<S> container(box.min.array() - 0.05 * diag, box.max.array() + 0.05 * diag);
  const double speed = 0.01 * diag / a.dt;

  // initial particles: uniform in the mesh's box, random directions, speed ~1% of the diagonal
  // per step (0.5x to 1.5x). A start exactly on the mesh is drawn again: such a particle is on
  // neither side, so whether its first move passes through the surface is a matter of convention
  // (the audit would count any leg from it that enters the mesh's plane as a crossing). Where the
  // coordinates' grid is coarse against the mesh (a small mesh far from the origin in float) many
  // draws round onto a triangle. The redraws come from a second stream, so that every other
  // particle keeps the start it has without them.
  std::mt19937_64 gen(a.seed), regen(a.seed ^ 0x5bd1e995u);
  auto uniform = [](std::mt19937_64& g, double lo, double hi) { return lo + (hi - lo) * (double(g() >> 11) * 0x1.0p-53); };
  auto uni = [&](double lo, double hi) { return uniform(gen, lo, hi); };
  std::vector<Particle<S>> ps(static_cast<std::size_t>(a.particles));
  // (at most 64 times: a flat mesh can cover its whole box; the starts left on it are counted)
  int redrawn = 0, left_on_mesh = 0;
  for (auto& p : ps) {
    for (int k = 0; k < 3; ++k) p.position[k] = uni(box.min[k], box.max[k]);
    for (int draw = 0; on_mesh(bvh, p.position); ++draw) {
      if (draw == 64) {
        ++left_on_mesh;
        break;
      }
      ++redrawn;
      for (int k = 0; k < 3; ++k) p.position[k] = S(uniform(regen, box.min[k], box.max[k]));
    }
    Vec3<S> dir;
    do dir = Vec3<S>(uni(-1, 1), uni(-1, 1), uni(-1, 1));
    while (dir.squaredNorm() > 1 || dir.squaredNorm() < 1e-6);
    p.velocity = dir.normalized() * speed * uni(0.5, 1.5);
  }

  StepOptions<S> opt;
  opt.threads = 1;  // the method rows: one thread (thread CPU time); the threads rows below vary it
  opt.free_ball_factor = a.free_ball;
  opt.gravity = Vec3<S>(0, -speed / (50 * a.dt), 0);  // changes the speed by its own size in 50 steps
  const Material<S> elastic = Material<S>::elastic();
  auto scene = [&](const MeshBvh<BV>& m, Strategy st) {
    ColliderSet<S, BV> cs;
    cs.meshes.emplace_back(m, ColliderSide::TwoSided, elastic);
    cs.boxes.emplace_back(container, ColliderSide::Inside, elastic);
    cs.meshes[0].strategy = st;
    cs.boxes[0].strategy = Strategy::Backtrack;
    return cs;
  };
  const double tg0 = thread_seconds();  // the grid's build: once per mesh, like the tree's
  DistanceGridConfig<S> gcfg;
  gcfg.resolution = a.grid;
  const DistanceGrid<S> grid = a.grid > 0 ? DistanceGrid<S>(bvh, gcfg) : DistanceGrid<S>();
  const double grid_seconds = thread_seconds() - tg0;
  auto cs_bt = scene(bvh, Strategy::Backtrack);
  if (a.grid > 0) cs_bt.meshes[0].distance_grid = &grid;
  const CompactBvh compact = a.compact > 0 ? CompactBvh(bvh.tree(), a.compact) : CompactBvh();
  if (a.compact > 0) cs_bt.meshes[0].compact_tree = &compact;
  const double tw0 = thread_seconds();
  const WideBvh<S> wide = a.wide ? WideBvh<S>(mesh) : WideBvh<S>();
  const double wide_seconds = thread_seconds() - tw0;
  auto cs_wide = cs_bt;
  cs_wide.meshes[0].compact_tree = nullptr;
  cs_wide.meshes[0].wide_tree = &wide;

  auto cs_pr = scene(bvh, Strategy::Project);
  if (a.grid > 0) cs_pr.meshes[0].distance_grid = &grid;  // skips the particles it proves far from the surface
  const auto cs_naive = scene(flat, Strategy::Backtrack);

  const int n_ref = std::min(a.ref_particles, a.particles);
  const int n_naive = std::min(a.naive_particles, a.particles);
  std::vector<Particle<S>> ref_init(ps.begin(), ps.begin() + n_ref), naive_init(ps.begin(), ps.begin() + n_naive);

  std::printf("impact-particles-bench: %s, %d triangles, %d particles x %d steps, dt %g, speed %.3g (%.2f%% of the diagonal per step)\n",
              mesh_name.c_str(), mesh.num_triangles(), a.particles, a.steps, a.dt, speed, 100 * speed * a.dt / diag);
  std::printf("starts exactly on the mesh: %d drawn again, %d left on it after 64 draws\n", redrawn, left_on_mesh);
  if (a.grid > 0)
    std::printf("distance grid: %d cells along the longest side, %.1f MB, built in %.2f s (not timed)\n", a.grid, double(grid.memory_bytes()) / 1e6,
                grid_seconds);
  const RunResult<S> ref = measure(ref_init, cs_bt, bvh, container, opt, a.dt, a.steps, a.substeps, a.sort_every);
  const std::vector<Particle<S>> none;  // --quick: the rows left out run no particles
  const RunResult<S> bt = measure(a.quick ? none : ps, cs_bt, bvh, container, opt, a.dt, a.steps, 1, a.sort_every);
  const RunResult<S> pr = measure(a.quick ? none : ps, cs_pr, bvh, container, opt, a.dt, a.steps, 1, a.sort_every);
  const RunResult<S> nv = measure(a.quick ? none : naive_init, cs_naive, bvh, container, opt, a.dt, a.steps, 1, a.sort_every);
  const int n_main = a.quick ? 0 : a.particles;
  if (a.wide)
    std::printf("wide tree: %.1f MB, built in %.2f s (not timed)\n", double(wide.memory_bytes()) / 1e6, wide_seconds);

  auto row = [&](const char* method, const RunResult<S>& r, int n, int substeps) {
    Row w;
    w.method = method;
    w.particles = n;
    w.steps = a.steps;
    w.rate = double(n) * a.steps * substeps / std::max(r.seconds, 1e-12);
    w.escaped = r.escaped;
    w.energy_rel_err = r.energy_rel_err;
    w.impact_share = r.impact_share;
    std::vector<double> e;
    for (int i = 0; i < std::min<int>(n, n_ref); ++i)
      e.push_back((r.final[static_cast<std::size_t>(i)].position - ref.final[static_cast<std::size_t>(i)].position).norm());
    const auto sm = bench::summarize(e);
    w.pos_err_mean = sm.mean;
    w.pos_err_max = sm.max;
    return w;
  };
  std::vector<Row> rows = {row("backtrack", bt, n_main, 1), row("project", pr, n_main, 1), row("naive", nv, a.quick ? 0 : n_naive, 1),
                           row("reference", ref, n_ref, a.substeps)};
  if (a.wide) rows.push_back(row("backtrack-wide", measure(ps, cs_wide, bvh, container, opt, a.dt, a.steps, 1, a.sort_every), a.particles, 1));
#ifdef IMPACT_HAVE_EMBREE
  {
    // the peer: a user's loop on Embree (float casts), backed off 1e-5 of the diagonal at each hit
    Aabb<double> cbox(container.min.template cast<double>(), container.max.template cast<double>());
    TriangleMesh<double> md;
    md.V = mesh.V.template cast<double>();
    md.F = mesh.F;
    const EmbreeParticles emb(md, cbox);
    const S offset = S(1e-5 * diag);
    const RunResult<S> timed = run_embree(ps, emb, bvh, container, opt, a.dt, a.steps, false, a.sort_every, offset);
    RunResult<S> audited = run_embree(ps, emb, bvh, container, opt, a.dt, a.steps, true, a.sort_every, offset);
    for (std::size_t i = 0; i < ps.size(); ++i)
      if (timed.final[i].position != audited.final[i].position) {
        std::fprintf(stderr, "impact-particles-bench: the timed and the audited Embree runs differ (particle %zu)\n", i);
        return 1;
      }
    audited.seconds = timed.seconds;
    rows.push_back(row("embree-user", audited, a.particles, 1));
  }
#else
  std::printf("built without Embree 3 (libembree-dev not found at configure time): no embree-user row\n");
#endif
  // threads rows (wall clock): the escapes and errors are those of the audited one-thread rows
  // above, since the runs end in the same state (checked)
  const int threads = resolve_threads(a.threads);
  std::vector<std::tuple<std::string, double, double>> speedups;  // name, by the wall clock, by the CPU times
  for (const auto& [name, cs, base_index] : {std::make_tuple("backtrack", &cs_bt, 0), std::make_tuple("project", &cs_pr, 1)}) {
    if (a.quick) break;
    const auto [one, many] = measure_threads(ps, *cs, bvh, container, opt, a.dt, a.steps, a.sort_every, threads);
    const Row base = rows[std::size_t(base_index)];  // a copy: rows grows below
    for (const auto* r : {&one, &many}) {
      Row w = base;
      w.method = std::string(name) + "-wall";
      w.threads = r == &one ? 1 : threads;
      w.rate = double(a.particles) * a.steps / std::max(r->r.seconds, 1e-12);
      rows.push_back(w);
    }
    speedups.emplace_back(name, one.r.seconds / std::max(many.r.seconds, 1e-12),
                          bench::cpu_speedup(one.caller, many.caller, many.process, threads));
  }
  std::printf("%-14s %7s %9s %6s %16s %8s %12s %12s %14s %12s\n", "method", "threads", "particles", "steps", "particle_steps/s", "escaped",
              "pos_err_mean", "pos_err_max", "energy_rel_err", "impact_share");
  std::vector<std::string> items;
  for (const auto& w : rows) {
    std::printf("%-14s %7d %9d %6d %16.4g %8d %12.4g %12.4g %14.4g %12.3f\n", w.method.c_str(), w.threads, w.particles, w.steps, w.rate,
                w.escaped, w.pos_err_mean, w.pos_err_max, w.energy_rel_err, w.impact_share);
    bench::JsonObject o;
    o.add("method", w.method).add("threads", w.threads).add("particles", w.particles).add("steps", w.steps).add("particle_steps_per_s", w.rate);
    o.add("escaped", w.escaped).add("pos_err_mean", w.pos_err_mean).add("pos_err_max", w.pos_err_max).add("energy_rel_err", w.energy_rel_err);
    o.add("impact_share", w.impact_share);
    items.push_back(o.str());
  }
  std::printf("share of particle-steps with an impact (backtrack): %.1f%%; reference: %d sub-steps\n", 100 * bt.impact_share,
              a.substeps);
  if (n_naive > 0 && !a.quick) std::printf("backtrack / naive speed: %.0fx\n", rows[0].rate / std::max(rows[2].rate, 1e-300));
  for (const auto& w : rows)
    if (w.method == "embree-user")
      for (const auto& m : rows)
        if ((m.method == "backtrack" || m.method == "backtrack-wide") && m.particles > 0)
          std::printf("%s / embree-user speed: %.2fx\n", m.method.c_str(), m.rate / std::max(w.rate, 1e-300));
  for (const auto& [name, x, y] : speedups)
    std::printf("%s, %d threads / 1 thread (same final state): %.2fx by the wall clock, %.2fx by the CPU times%s\n", name.c_str(),
                threads, x, y, a.particles < 512 ? " (fewer than 512 particles: stepped serially)" : "");
  if (!a.json.empty()) {
    bench::JsonObject top;
    top.add("bench", "impact-particles-bench").add("mesh", mesh_name).add("triangles", mesh.num_triangles()).add("dt", a.dt);
    top.add("substeps", a.substeps).add("diagonal", diag).add("grid", a.grid).add("grid_build_s", grid_seconds).add("compact", a.compact).add("wide", a.wide);
    top.add("starts_redrawn", redrawn).add("starts_on_mesh", left_on_mesh);
    top.raw("rows", bench::JsonObject::array(items));
    if (!bench::write_file(a.json, top.str())) {
      std::fprintf(stderr, "impact-particles-bench: cannot write %s\n", a.json.c_str());
      return 1;
    }
  }
  return 0;
}

constexpr const char* kUsage =
    "usage: impact-particles-bench [MESH] [--particles N] [--steps S] [--dt DT] [--naive-particles M]\n"
    "                              [--ref-particles R] [--substeps K] [--free-ball F] [--sort-every N] [--float] [--leaf L]\n"
    "                              [--grid G] [--compact C] [--wide 0|1] [--threads T] [--seed X] [--quick] [--json FILE]\n";

int main(int argc, char** argv) {
  Args a;
  for (int i = 1; i < argc; ++i) {
    const std::string s = argv[i];
    auto next = [&] { return bench::option_value(argc, argv, i, kUsage); };
    auto integer = [&](long long lo, long long hi) { return int(bench::parse_integer(s, next(), lo, hi, kUsage)); };
    if (s == "--particles") a.particles = integer(1, 10000000);
    else if (s == "--steps") a.steps = integer(1, 1000000);
    else if (s == "--dt") a.dt = bench::parse_real(s, next(), 0, 1e3, kUsage);
    else if (s == "--naive-particles") a.naive_particles = integer(0, 1000000);
    else if (s == "--ref-particles") a.ref_particles = integer(0, 10000000);
    else if (s == "--substeps") a.substeps = integer(1, 1024);
    else if (s == "--free-ball") a.free_ball = bench::parse_real(s, next(), 0, 1e6, kUsage);
    else if (s == "--float") a.use_float = true;
    else if (s == "--quick") a.quick = true;
    else if (s == "--leaf") a.leaf = integer(1, 1024);
    else if (s == "--grid") a.grid = integer(0, 4096);
    else if (s == "--compact") a.compact = integer(0, 1024);
    else if (s == "--wide") a.wide = integer(0, 1);
    else if (s == "--sort-every") a.sort_every = integer(0, 1000000);
    else if (s == "--threads") a.threads = integer(0, 1024);
    else if (s == "--seed") a.seed = bench::parse_seed(s, next(), kUsage);
    else if (s == "--json") a.json = next();
    else if (!s.empty() && s[0] == '-') bench::reject_option(s, kUsage);
    else if (a.mesh.empty()) a.mesh = s;
    else bench::exit_usage("more than one mesh given", kUsage);
  }
  if (!(a.dt > 0)) bench::exit_usage("--dt must be above 0", kUsage);
  bench::check_writable(a.json, kUsage);

  return a.use_float ? run_all<float>(a) : run_all<double>(a);
}
