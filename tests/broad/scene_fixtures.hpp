// SPDX-License-Identifier: MIT
// Pieces shared by the scene tests (test_scene.cpp and its concurrent twin test_scene_threads.cpp):
// a small sphere-tree octahedron, a pose from double values, and a sorted pair list.
#pragma once

#include "impact/broad/scene.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <memory>
#include <vector>

namespace impact::test {

/// The octahedron with vertices at distance r on the axes, as a sphere tree.
template <class S>
std::unique_ptr<MeshBvh<Sphere<S>>> octahedron(S r) {
  Vertices<S> V(6, 3);
  V << r, 0, 0, -r, 0, 0, 0, r, 0, 0, -r, 0, 0, 0, r, 0, 0, -r;
  Faces F(8, 3);
  F << 0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5;
  return std::make_unique<MeshBvh<Sphere<S>>>(V, F);
}

/// The pose (R, t) in scalar S; R is orthonormalised after the cast so that float poses pass the
/// rotation check.
template <class S>
RigidTransform<S> pose_at(const Eigen::Vector3d& t, const Eigen::Matrix3d& R = Eigen::Matrix3d::Identity()) {
  Eigen::Quaternion<S> q(R.cast<S>());
  q.normalize();
  return {q.toRotationMatrix(), t.cast<S>()};
}

inline std::vector<ObjectPair> sorted_pairs(std::vector<ObjectPair> v) {
  std::sort(v.begin(), v.end());
  return v;
}

}  // namespace impact::test
