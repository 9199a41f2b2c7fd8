// SPDX-License-Identifier: MIT
// A twisting cloth run for the collision step: an n x n grid pinned at two opposite edges, one
// edge turned about the grid's axis and pushed towards the other, so the cloth wraps into itself
// (dense self-contact). The dynamics is a small position-based model written here (inertia,
// gravity, Gauss-Seidel edge-length constraints): the collision step is the subject.
#pragma once

#include "impact/cloth/collision_step.hpp"
#include "impact/cloth/verify_state.hpp"
#include "impact/geometry/mesh_generators.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <utility>
#include <vector>

namespace cloth_test {

struct TwistResult {
  int steps_run = 0;
  int not_collision_free = 0;
  std::size_t intersections_seen = 0;
  double min_distance = 0;
  std::size_t zones = 0, failsafe_steps = 0;
  std::size_t ccd_tests = 0, collisions = 0;
  int front_steps = 0;  // steps whose gathering walked on from the last step's front
  std::vector<double> final_x;  // the last positions, row by row
};

template <class S>
TwistResult twist_run(int n, int steps, double turns, impact::ZoneMethod method, int verify_every, int threads = 1,
                      bool walk_from_root = false) {
  using namespace impact;
  auto g = make_grid<S>(n, n, S(1));
  const double h = 0.2 / n, dt = 0.01;
  const auto nv = g.V.rows();
  std::set<std::pair<int, int>> edge_set;
  for (Eigen::Index f = 0; f < g.F.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      int a = g.F(f, k), b = g.F(f, (k + 1) % 3);
      edge_set.insert({std::min(a, b), std::max(a, b)});
    }
  std::vector<std::pair<int, int>> edges(edge_set.begin(), edge_set.end());
  std::vector<double> rest;
  for (auto [a, b] : edges) rest.push_back(double((g.V.row(a) - g.V.row(b)).norm()));
  Eigen::Matrix<S, Eigen::Dynamic, 1> w = Eigen::Matrix<S, Eigen::Dynamic, 1>::Ones(nv);
  std::vector<int> left, right;
  for (int j = 0; j <= n; ++j) left.push_back(j * (n + 1)), right.push_back(j * (n + 1) + n);
  for (int v : left) w[v] = 0;
  for (int v : right) w[v] = 0;
  Vertices<S> x = g.V, xprev = g.V;
  ClothCollisionOptions<S> opt;
  opt.thickness = S(h);
  opt.zone_method = method;
  opt.threads = threads;
  ClothCollisionWorkspace<S> ws;
  TwistResult res;
  for (int s = 1; s <= steps; ++s) {
    const double frac = double(s) / steps;
    const double angle = 2 * M_PI * turns * frac, push = 0.4 * std::min(1.0, 2 * frac);
    Vertices<S> x1 = x + S(0.98) * (x - xprev);
    x1.col(2).array() -= S(9.8 * dt * dt);
    for (int v : left) x1.row(v) = g.V.row(v);
    for (int v : right) {
      const double y = double(g.V(v, 1));
      x1.row(v) << S(0.5 - push), S(y * std::cos(angle)), S(y * std::sin(angle));
    }
    for (int it = 0; it < 20; ++it)
      for (std::size_t e = 0; e < edges.size(); ++e) {
        const auto [a, b] = edges[e];
        const double wa = double(w[a]), wb = double(w[b]);
        if (wa + wb == 0) continue;
        const Vec3<double> d = (x1.row(a) - x1.row(b)).transpose().template cast<double>();
        const double len = d.norm();
        if (len == 0) continue;
        const Vec3<double> corr = (len - rest[e]) / (len * (wa + wb)) * d;
        x1.row(a) -= (wa * corr).cast<S>().transpose();
        x1.row(b) += (wb * corr).cast<S>().transpose();
      }
    if (walk_from_root) ws.system.front.clear();  // the swept tree's self-walk starts from the root
    res.front_steps += ws.system.front.empty() ? 0 : 1;
    const auto st = cloth_collision_step(g.F, w, x, x1, ClothObstacles<S>{}, opt, &ws);
    res.not_collision_free += st.collision_free ? 0 : 1;
    res.zones += st.zone_count;
    res.failsafe_steps += st.failsafe_used ? 1 : 0;
    res.ccd_tests += st.ccd_tests;
    res.collisions += st.proximity.collisions + st.impulses.collisions + st.zones.collisions + st.failsafe.collisions;
    xprev = x;
    x = x1;
    res.steps_run = s;
    if (s % verify_every == 0 || s == steps) {
      const auto rep = verify_cloth_state(g.F, x, ClothObstacles<S>{}, ObstacleTime::End, ClothVerifyOptions{2 * h, 4});
      res.intersections_seen += rep.intersections;
      res.min_distance = rep.min_distance;
      if (rep.min_distance < h || rep.intersections) ADD_FAILURE() << "step " << s << ": " << rep.intersections << " intersections, min distance " << rep.min_distance;
    }
  }
  for (Eigen::Index i = 0; i < x.rows(); ++i)
    for (int k = 0; k < 3; ++k) res.final_x.push_back(double(x(i, k)));
  return res;
}

}  // namespace cloth_test
