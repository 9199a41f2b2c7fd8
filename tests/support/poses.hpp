// SPDX-License-Identifier: MIT
// The pose distribution shared by the FCL cross-checks and impact-collide-bench: mesh A stays at
// the origin; mesh B gets a uniformly random rotation about its own bounding-box centre and a
// translation uniform in A's bounding box grown by B's bounding radius, so that a good share of
// the poses collide and the rest come close.
#pragma once

#include "impact/geometry/aabb.hpp"
#include "impact/geometry/triangle_mesh.hpp"
#include "support/random.hpp"

#include <vector>

namespace impact::test {

template <class S> Aabb<S> bounds(const TriangleMesh<S>& m) {
  Aabb<S> b;
  for (Eigen::Index i = 0; i < m.V.rows(); ++i) b.extend(m.V.row(i).transpose());
  return b;
}

inline std::vector<RigidTransform<double>> random_poses_around(const TriangleMesh<double>& A, const TriangleMesh<double>& B, int n,
                                                              std::uint64_t seed) {
  const Aabb<double> box_a = bounds(A), box_b = bounds(B);
  const double rb = (box_b.max - box_b.center()).norm();
  Rng rng(seed);
  std::vector<RigidTransform<double>> poses;
  poses.reserve(static_cast<std::size_t>(n));
  for (int k = 0; k < n; ++k) {
    RigidTransform<double> p = random_pose(rng, box_a.min.array() - rb, box_a.max.array() + rb);
    p.t -= p.R * box_b.center();
    poses.push_back(p);
  }
  return poses;
}

}  // namespace impact::test
