// SPDX-License-Identifier: MIT
// FCL as the oracle (tests) and the peer (benches): BVHModel built from an impact mesh, and the
// boolean and all-pairs collide calls with FCL's default request. FCL appears only in tests/ and
// benches/, never in include/impact.
#pragma once

#include "impact/geometry/transform.hpp"
#include "impact/geometry/triangle_mesh.hpp"

#include <fcl/narrowphase/collision.h>
#include <fcl/geometry/bvh/BVH_model.h>

#include <memory>
#include <vector>

namespace impact::test {

template <class BV> std::shared_ptr<fcl::BVHModel<BV>> make_fcl_model(const TriangleMesh<double>& m) {
  auto model = std::make_shared<fcl::BVHModel<BV>>();
  std::vector<fcl::Vector3d> pts(static_cast<std::size_t>(m.V.rows()));
  for (Eigen::Index i = 0; i < m.V.rows(); ++i) pts[static_cast<std::size_t>(i)] = m.V.row(i).transpose();
  std::vector<fcl::Triangle> tris(static_cast<std::size_t>(m.F.rows()));
  for (Eigen::Index t = 0; t < m.F.rows(); ++t)
    tris[static_cast<std::size_t>(t)] = fcl::Triangle(static_cast<std::size_t>(m.F(t, 0)), static_cast<std::size_t>(m.F(t, 1)),
                                                       static_cast<std::size_t>(m.F(t, 2)));
  model->beginModel();
  model->addSubModel(pts, tris);
  model->endModel();
  return model;
}

inline fcl::Transform3d to_fcl(const RigidTransform<double>& x) {
  fcl::Transform3d t = fcl::Transform3d::Identity();
  t.linear() = x.R;
  t.translation() = x.t;
  return t;
}

/// A pair of FCL collision objects made once and re-posed per query, so that timing a query does
/// not include FCL's object set-up (which scans every vertex to compute a local AABB).
template <class BV> struct FclPair {
  fcl::CollisionObjectd a, b;
  FclPair(const std::shared_ptr<fcl::BVHModel<BV>>& ma, const std::shared_ptr<fcl::BVHModel<BV>>& mb) : a(ma), b(mb) {}
  void set_poses(const RigidTransform<double>& pa, const RigidTransform<double>& pb) {
    a.setTransform(to_fcl(pa));
    a.computeAABB();
    b.setTransform(to_fcl(pb));
    b.computeAABB();
  }
  bool collides() {
    fcl::CollisionRequestd req;
    fcl::CollisionResultd res;
    fcl::collide(&a, &b, req, res);
    return res.isCollision();
  }
  std::vector<std::pair<int, int>> all_pairs(std::size_t max_contacts = 100000000) {
    fcl::CollisionRequestd req(max_contacts, false);
    fcl::CollisionResultd res;
    fcl::collide(&a, &b, req, res);
    std::vector<std::pair<int, int>> out;
    for (std::size_t i = 0; i < res.numContacts(); ++i) out.emplace_back(res.getContact(i).b1, res.getContact(i).b2);
    return out;
  }
};

/// FCL's boolean answer with the default request (num_max_contacts = 1, no contacts).
template <class BV>
bool fcl_collides(const std::shared_ptr<fcl::BVHModel<BV>>& a, const RigidTransform<double>& pa, const std::shared_ptr<fcl::BVHModel<BV>>& b,
                  const RigidTransform<double>& pb) {
  fcl::CollisionObjectd oa(a, to_fcl(pa)), ob(b, to_fcl(pb));
  fcl::CollisionRequestd req;
  fcl::CollisionResultd res;
  fcl::collide(&oa, &ob, req, res);
  return res.isCollision();
}

/// FCL's colliding triangle pairs (up to max_contacts).
template <class BV>
std::vector<std::pair<int, int>> fcl_all_pairs(const std::shared_ptr<fcl::BVHModel<BV>>& a, const RigidTransform<double>& pa,
                                               const std::shared_ptr<fcl::BVHModel<BV>>& b, const RigidTransform<double>& pb,
                                               std::size_t max_contacts = 100000000) {
  fcl::CollisionObjectd oa(a, to_fcl(pa)), ob(b, to_fcl(pb));
  fcl::CollisionRequestd req(max_contacts, false);
  fcl::CollisionResultd res;
  fcl::collide(&oa, &ob, req, res);
  std::vector<std::pair<int, int>> out;
  for (std::size_t i = 0; i < res.numContacts(); ++i) out.emplace_back(res.getContact(i).b1, res.getContact(i).b2);
  return out;
}

}  // namespace impact::test
