// SPDX-License-Identifier: MIT
// Fuzz target: cloth_collision_step on small scenes decoded from the input: one or two jittered
// grid sheets (2-4 x 2-4 vertices, spacing 1, vertices on a grid of 1/8) with per-sheet and
// per-vertex velocities, some vertices pinned (still, or scripted to move), and an optional
// kinematic obstacle sheet (still or moving); the thickness 2^-3 .. 2^-7; every stage switched,
// both zone methods, few passes and rounds (so the zones and the fail-safe are reached); float or
// double (the grid, the velocities and the thickness are exact in both). A start
// closer than the thickness is InvalidInput (the default StartViolation::Throw) and ends the run;
// so must a start that intersects (checked against verify_cloth_state: accepting one is a finding).
// Checked against oracles independent of the step (tests/cloth/cloth_oracles.hpp, verify_state):
//  - the corrected end positions are finite, and pinned vertices end where they were scripted to;
//  - when the step reports collision_free: no triangle pair intersects at the end (exact
//    predicates), every non-adjacent pair stays at least the thickness apart (up to 1e-6 of it, the
//    rounding of the closest points in float) at 17 sample times of the motion, and the CCD of every pair over the whole corrected motion with a minimum
//    separation of 0.9 h finds nothing (so no pair dips below h between the samples either);
//  - when no infinite-mass vertex moves (pinned ones still, the obstacle still), the step must
//    report collision_free: putting every movable vertex back at its start is always a way out.
#include "cloth/cloth_oracles.hpp"
#include "fuzz_input.hpp"
#include "impact/cloth/collision_step.hpp"
#include "impact/cloth/verify_state.hpp"
#include "impact/core/error.hpp"

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

namespace {

using impact::Faces;
using impact::Vertices;

/// A sheet of nx x ny vertices (grid spacing 8 fine units) jittered by up to 2 units, lifted by
/// `lift` units in z and shifted by (sx, sy); positions and velocities in fine units (1/8).
struct Sheet {
  std::vector<std::array<int, 3>> x, v;
  std::vector<std::array<int, 3>> tris;
};

Sheet read_sheet(impact::fuzz::Input& in, int lift) {
  Sheet s;
  const int nx = 2 + int(in.byte() % 3), ny = 2 + int(in.byte() % 3);
  const int sx = int(in.range(-6, 6)), sy = int(in.range(-6, 6));
  const std::array<int, 3> common{int(in.range(-16, 16)), int(in.range(-16, 16)), int(in.range(-16, 16))};
  const bool flip = in.flag();
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      s.x.push_back({8 * i + sx + int(in.range(-2, 2)), 8 * j + sy + int(in.range(-2, 2)), lift + int(in.range(-2, 2))});
      s.v.push_back({common[0] + int(in.range(-4, 4)), common[1] + int(in.range(-4, 4)), common[2] + int(in.range(-4, 4))});
    }
  for (int j = 0; j + 1 < ny; ++j)
    for (int i = 0; i + 1 < nx; ++i) {
      const int a = j * nx + i, b = a + 1, c = a + nx, d = c + 1;
      if (flip) {
        s.tris.push_back({a, b, d});
        s.tris.push_back({a, d, c});
      } else {
        s.tris.push_back({a, b, c});
        s.tris.push_back({b, d, c});
      }
    }
  return s;
}

[[noreturn]] void fail(const std::string& what, double h) {
  impact::fuzz::fail("cloth (h " + std::to_string(h) + "): " + what);
}

template <class S> int run(impact::fuzz::Input& in, std::uint8_t mode) {
  const S unit = S(1) / 8;
  const S h = std::ldexp(S(1), -3 - int(mode % 5));

  // the cloth: one or two sheets, the second lifted by 0-16 units
  std::vector<Sheet> sheets{read_sheet(in, 0)};
  if (mode & 8u) sheets.push_back(read_sheet(in, int(in.range(0, 16))));
  int nv = 0, nf = 0;
  for (const Sheet& s : sheets) nv += int(s.x.size()), nf += int(s.tris.size());
  Vertices<S> x0(nv, 3), x1(nv, 3);
  Faces F(nf, 3);
  Eigen::Matrix<S, Eigen::Dynamic, 1> inverse_mass = Eigen::Matrix<S, Eigen::Dynamic, 1>::Ones(nv);
  int vo = 0, fo = 0;
  for (const Sheet& s : sheets) {
    for (std::size_t i = 0; i < s.x.size(); ++i)
      for (int k = 0; k < 3; ++k) {
        x0(vo + int(i), k) = unit * s.x[i][std::size_t(k)];
        x1(vo + int(i), k) = unit * (s.x[i][std::size_t(k)] + s.v[i][std::size_t(k)]);
      }
    for (std::size_t f = 0; f < s.tris.size(); ++f)
      for (int k = 0; k < 3; ++k) F(fo + int(f), k) = vo + s.tris[f][std::size_t(k)];
    vo += int(s.x.size()), fo += int(s.tris.size());
  }
  // pinned vertices: still, or (mode bit 16) moving as scripted
  bool scripted_motion = false;
  const std::uint8_t pins = in.byte();
  for (int i = 0; i < nv && i < 8; ++i)
    if (pins & (1u << i)) {
      inverse_mass(i) = 0;
      if (!(mode & 16u)) x1.row(i) = x0.row(i);
      scripted_motion = scripted_motion || x1.row(i) != x0.row(i);
    }
  // an obstacle sheet below the cloth, still or (mode bit 64) moving
  impact::ClothObstacles<S> obstacles;
  Vertices<S> ox0, ox1;
  Faces oF;
  if (mode & 32u) {
    const Sheet o = read_sheet(in, -int(in.range(1, 16)));
    ox0.resize(Eigen::Index(o.x.size()), 3), ox1.resize(Eigen::Index(o.x.size()), 3), oF.resize(Eigen::Index(o.tris.size()), 3);
    for (std::size_t i = 0; i < o.x.size(); ++i)
      for (int k = 0; k < 3; ++k) {
        ox0(Eigen::Index(i), k) = unit * o.x[i][std::size_t(k)];
        ox1(Eigen::Index(i), k) = unit * (o.x[i][std::size_t(k)] + ((mode & 64u) ? o.v[i][std::size_t(k)] : 0));
      }
    for (std::size_t f = 0; f < o.tris.size(); ++f)
      for (int k = 0; k < 3; ++k) oF(Eigen::Index(f), k) = o.tris[f][std::size_t(k)];
    obstacles.kinematic.push_back({&ox0, &ox1, &oF});
    scripted_motion = scripted_motion || ox1 != ox0;
  }

  impact::ClothCollisionOptions<S> opt;
  opt.thickness = h;
  const std::uint8_t stages = in.byte();
  opt.proximity = (stages & 1u) != 0;
  opt.impulses = (stages & 2u) != 0;
  opt.zones = (stages & 4u) != 0;
  opt.zone_method = (stages & 8u) ? impact::ZoneMethod::Rigid : impact::ZoneMethod::Harmon;
  opt.impulse_passes = int(in.byte() % 4);
  opt.max_zone_iterations = int(in.byte() % 6);
  opt.proximity_rounds = 1 + int(in.byte() % 8);
  opt.friction = S(in.byte() % 4) / 4;
  opt.separation_margin = S(in.byte() % 3) / 8;

  // An intersecting start must be refused: the start check tests the triangle pairs it gathers
  // exactly, so an edge piercing a triangle far from its boundary (every vertex-face and edge-edge
  // pair farther than h) is an InvalidInput too. The oracle is the independent exact check.
  const bool start_intersects = impact::verify_cloth_state(F, x0, obstacles, impact::ObstacleTime::Start).intersections != 0;

  Vertices<S> x = x1;
  impact::ClothStepStats stats;
  try {
    stats = impact::cloth_collision_step(F, inverse_mass, x0, x, obstacles, opt);
  } catch (const impact::InvalidInput&) {
    return 0;  // a start closer than h, an intersecting start or a degenerate input: refused
  }
  if (start_intersects) fail("an intersecting start was accepted", h);

  for (int i = 0; i < nv; ++i) {
    if (!x.row(i).allFinite()) fail("vertex " + std::to_string(i) + " ends non-finite", h);
    if (inverse_mass(i) == 0 && x.row(i) != x1.row(i)) fail("pinned vertex " + std::to_string(i) + " was moved", h);
  }
  if (!stats.collision_free) {
    if (!scripted_motion) fail("not collision-free although no infinite-mass vertex moves", h);
    if (stats.unresolved.empty()) fail("not collision-free with no unresolved pair listed", h);
    return 0;
  }
  const impact::ClothStateReport end = impact::verify_cloth_state(F, x, obstacles, impact::ObstacleTime::End);
  if (end.intersections != 0) fail(std::to_string(end.intersections) + " intersecting triangle pairs at the end", h);
  const cloth_test::Combined<S> c = cloth_test::combine(F, x0, x, obstacles);
  const double sampled = cloth_test::sampled_min_distance(c, 16, 2 * h);
  if (!(sampled >= double(h) * (1 - 1e-6))) fail("a pair comes " + std::to_string(sampled) + " apart at a sample time", h);
  const int hits = cloth_test::all_pairs_ccd_hits(c, S(0.9) * h);
  if (hits != 0) fail(std::to_string(hits) + " pairs come within 0.9 h over the corrected motion", h);
  return 0;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  impact::fuzz::Input in(data, size);
  const std::uint8_t mode = in.byte();
  return (mode & 128u) ? run<float>(in, mode) : run<double>(in, mode);
}
