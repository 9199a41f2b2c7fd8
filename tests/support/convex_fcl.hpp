// SPDX-License-Identifier: MIT
// The convex shapes as FCL geometries (the oracle of tests/convex and the peer of
// impact-convex-bench), set up as FCL's users do: fcl::Sphere, fcl::Capsule, fcl::Cylinder,
// fcl::Cone, fcl::Box, fcl::Convex (full lengths where impact takes halves), queried with
// fcl::collide and fcl::distance on CollisionGeometry + Transform3 and default requests (FCL's
// default narrow-phase solver is its libccd one, GST_LIBCCD).
#pragma once

#include "impact/convex/convex_hull.hpp"
#include "impact/convex/shapes.hpp"
#include "support/fcl_oracle.hpp"

#include <fcl/geometry/shape/box.h>
#include <fcl/geometry/shape/capsule.h>
#include <fcl/geometry/shape/cone.h>
#include <fcl/geometry/shape/convex.h>
#include <fcl/geometry/shape/cylinder.h>
#include <fcl/geometry/shape/sphere.h>
#include <fcl/narrowphase/collision.h>
#include <fcl/narrowphase/distance.h>

#include <memory>

namespace impact::test {

inline std::shared_ptr<fcl::CollisionGeometryd> to_fcl_shape(const Sphere<double>& s) {
  return std::make_shared<fcl::Sphered>(s.radius);  // (the tests' spheres are centred)
}
inline std::shared_ptr<fcl::CollisionGeometryd> to_fcl_shape(const Capsule<double>& s) {
  return std::make_shared<fcl::Capsuled>(s.radius, 2 * s.half_length);
}
inline std::shared_ptr<fcl::CollisionGeometryd> to_fcl_shape(const Cylinder<double>& s) {
  return std::make_shared<fcl::Cylinderd>(s.radius, 2 * s.half_length);
}
inline std::shared_ptr<fcl::CollisionGeometryd> to_fcl_shape(const Cone<double>& s) {
  return std::make_shared<fcl::Coned>(s.radius, 2 * s.half_length);
}
inline std::shared_ptr<fcl::CollisionGeometryd> to_fcl_shape(const Box<double>& s) {
  return std::make_shared<fcl::Boxd>(2 * s.half.x(), 2 * s.half.y(), 2 * s.half.z());
}
inline std::shared_ptr<fcl::CollisionGeometryd> to_fcl_shape(const ConvexHull<double>& h) {
  auto verts = std::make_shared<std::vector<fcl::Vector3d>>();
  for (Eigen::Index i = 0; i < h.vertices.rows(); ++i) verts->push_back(h.vertices.row(i).transpose());
  auto faces = std::make_shared<std::vector<int>>();
  for (const auto& f : h.faces) {
    faces->push_back(static_cast<int>(f.vertices.size()));
    for (int v : f.vertices) faces->push_back(v);
  }
  return std::make_shared<fcl::Convexd>(verts, static_cast<int>(h.faces.size()), faces);
}

struct FclShapePair {
  std::shared_ptr<fcl::CollisionGeometryd> a, b;

  bool collide(const RigidTransform<double>& pa, const RigidTransform<double>& pb) const {
    fcl::CollisionRequestd req;
    fcl::CollisionResultd res;
    fcl::collide(a.get(), to_fcl(pa), b.get(), to_fcl(pb), req, res);
    return res.isCollision();
  }
  /// Penetration: false when not colliding; else depth and normal (FCL: from a towards b).
  bool penetration(const RigidTransform<double>& pa, const RigidTransform<double>& pb, double& depth, Eigen::Vector3d& normal,
                   Eigen::Vector3d& point) const {
    fcl::CollisionRequestd req(1, true);
    fcl::CollisionResultd res;
    fcl::collide(a.get(), to_fcl(pa), b.get(), to_fcl(pb), req, res);
    if (!res.isCollision() || res.numContacts() == 0) return false;
    const auto& c = res.getContact(0);
    depth = c.penetration_depth;
    normal = c.normal;
    point = c.pos;
    return true;
  }
  /// Distance with nearest points (FCL returns a negative or zero value when colliding).
  double distance(const RigidTransform<double>& pa, const RigidTransform<double>& pb, Eigen::Vector3d* pa_out = nullptr,
                  Eigen::Vector3d* pb_out = nullptr) const {
    fcl::DistanceRequestd req(pa_out != nullptr);
    fcl::DistanceResultd res;
    fcl::distance(a.get(), to_fcl(pa), b.get(), to_fcl(pb), req, res);
    if (pa_out) *pa_out = res.nearest_points[0];
    if (pb_out) *pb_out = res.nearest_points[1];
    return res.min_distance;
  }
};

}  // namespace impact::test
