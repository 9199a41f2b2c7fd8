// SPDX-License-Identifier: MIT
// Bad input to every CCD entry point (issue 12, D12): out-of-range options, NaN/Inf coordinates
// (and, for the mesh CCD, coordinates beyond 1e100), trees built for a smaller minimum separation
// or for another mesh. Each throws InvalidInput with the reason in every build (before, release
// builds answered hit == false for real contacts), and the boundary values of each range are
// accepted.
#include "impact/ccd/edge_edge.hpp"
#include "impact/ccd/mesh_ccd.hpp"
#include "impact/ccd/vertex_face.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <string>

namespace {

using Vd = impact::Vec3<double>;
const double kNaN = std::numeric_limits<double>::quiet_NaN();
const double kInf = std::numeric_limits<double>::infinity();

// A point falling through the middle of a static triangle at t = 1/2 (a real contact), and two
// edges crossing at t = 1/4.
impact::CcdResult<double> crossing_vf(const impact::CcdOptions& o, int bad_point = -1, double bad = 0.0) {
  Vd p[8] = {Vd(0.25, 0.25, 1), Vd(0, 0, 0), Vd(1, 0, 0), Vd(0, 1, 0), Vd(0.25, 0.25, -1), Vd(0, 0, 0), Vd(1, 0, 0), Vd(0, 1, 0)};
  if (bad_point >= 0) p[bad_point][bad_point % 3] = bad;
  return impact::vertex_face_ccd(p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7], o);
}
impact::CcdResult<double> crossing_ee(const impact::CcdOptions& o, int bad_point = -1, double bad = 0.0) {
  Vd p[8] = {Vd(-1, 0, 0), Vd(1, 0, 0), Vd(0.5, -1, 0.25), Vd(0.5, 1, 0.25), Vd(-1, 0, 0), Vd(1, 0, 0), Vd(0.5, -1, -0.75), Vd(0.5, 1, -0.75)};
  if (bad_point >= 0) p[bad_point][(bad_point + 1) % 3] = bad;
  return impact::edge_edge_ccd(p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7], o);
}

// Expects InvalidInput whose message contains `reason`.
void expect_invalid(const std::function<void()>& f, const std::string& reason) {
  try {
    f();
    ADD_FAILURE() << "no InvalidInput; expected one about " << reason;
  } catch (const impact::InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find(reason), std::string::npos) << e.what();
  }
}

struct BadOption {
  const char* field;
  std::function<void(impact::CcdOptions&)> set;
};

TEST(CcdValidation, BadOptionsThrow) {
  const BadOption bad[] = {
      {"t_max", [](auto& o) { o.t_max = kNaN; }},
      {"t_max", [](auto& o) { o.t_max = 0.0; }},
      {"t_max", [](auto& o) { o.t_max = -0.5; }},
      {"t_max", [](auto& o) { o.t_max = 1.0 + 1e-15; }},
      {"t_max", [](auto& o) { o.t_max = kInf; }},
      {"min_separation", [](auto& o) { o.min_separation = -1e-9; }},
      {"min_separation", [](auto& o) { o.min_separation = kNaN; }},
      {"min_separation", [](auto& o) { o.min_separation = kInf; }},
      {"tolerance", [](auto& o) { o.tolerance = kNaN; }},
      {"tolerance", [](auto& o) { o.tolerance = -1e-6; }},
      {"tolerance", [](auto& o) { o.tolerance = kInf; }},
      {"max_iterations", [](auto& o) { o.max_iterations = 0; }},
      {"max_iterations", [](auto& o) { o.max_iterations = -3; }},
      {"max_iterations", [](auto& o) { o.max_iterations = (std::int64_t(1) << 22) + 1; }},
      {"max_iterations", [](auto& o) { o.max_iterations = std::numeric_limits<std::int64_t>::max(); }},
      {"recheck_iterations", [](auto& o) { o.recheck_iterations = -1; }},
      {"recheck_iterations", [](auto& o) { o.recheck_iterations = (std::int64_t(1) << 22) + 1; }},
  };
  for (const auto& b : bad) {
    impact::CcdOptions o;
    b.set(o);
    expect_invalid([&] { crossing_vf(o); }, std::string("vertex_face_ccd: CcdOptions::") + b.field);
    expect_invalid([&] { crossing_ee(o); }, std::string("edge_edge_ccd: CcdOptions::") + b.field);
    // float inputs go through the same check
    const impact::Vec3<float> z(0, 0, 0), x(1, 0, 0), y(0, 1, 0);
    expect_invalid([&] { impact::vertex_face_ccd(z, z, x, y, z, z, x, y, o); }, b.field);
  }
}

TEST(CcdValidation, BoundaryOptionsAccepted) {
  // The ends of each range are valid and the crossing stays a hit.
  impact::CcdOptions o;
  o.t_max = 1.0;
  o.min_separation = 0.0;
  o.tolerance = 0.0;
  o.recheck_iterations = 0;
  EXPECT_TRUE(crossing_vf(o).hit);
  EXPECT_TRUE(crossing_ee(o).hit);
  o = {};
  o.max_iterations = 1;  // smallest budget: a conservative hit
  EXPECT_TRUE(crossing_vf(o).hit);
  o.max_iterations = std::int64_t(1) << 22;
  o.recheck_iterations = std::int64_t(1) << 22;
  EXPECT_TRUE(crossing_vf(o).hit);
  EXPECT_TRUE(crossing_ee(o).hit);
  o = {};
  o.min_separation = std::numeric_limits<double>::max();
  EXPECT_TRUE(crossing_vf(o).hit);
  EXPECT_EQ(crossing_vf(o).toi, 0.0);
  o = {};
  o.t_max = std::numeric_limits<double>::denorm_min();
  EXPECT_FALSE(crossing_vf(o).hit);  // the contact is at t = 1/2
}

TEST(CcdValidation, BadCoordinatesThrow) {
  const impact::CcdOptions o;
  for (int k = 0; k < 8; ++k)
    for (double bad : {kNaN, kInf, -kInf}) {
      expect_invalid([&] { crossing_vf(o, k, bad); }, "vertex_face_ccd: point " + std::to_string(k));
      expect_invalid([&] { crossing_ee(o, k, bad); }, "edge_edge_ccd: point " + std::to_string(k));
    }
  // float: NaN and Inf
  const float fnan = std::numeric_limits<float>::quiet_NaN();
  const impact::Vec3<float> z(0, 0, 0), x(1, 0, 0), y(0, 1, 0), n(0, fnan, 0);
  expect_invalid([&] { impact::edge_edge_ccd(z, x, z, y, z, x, n, y); }, "point 6");
  // any finite magnitude is in range (the tests are scale-free)
  EXPECT_NO_THROW(crossing_vf(o, 5, std::numeric_limits<double>::max()));
  EXPECT_NO_THROW(crossing_ee(o, 5, -std::numeric_limits<double>::max()));
  EXPECT_NO_THROW(crossing_ee(o, 2, std::numeric_limits<double>::denorm_min()));
}

// A 3 x 3 grid sheet in z = z0 moving by dz.
struct Sheet {
  impact::Vertices<double> V0, V1;
  impact::Faces F;
  Sheet(double z0, double dz) {
    V0.resize(9, 3);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) V0.row(3 * i + j) << 0.5 * i, 0.5 * j, z0;
    V1 = V0;
    V1.col(2).array() += dz;
    F.resize(8, 3);
    int f = 0;
    for (int i = 0; i < 2; ++i)
      for (int j = 0; j < 2; ++j) {
        const int a = 3 * i + j, b = a + 1, c = a + 3, d = c + 1;
        F.row(f++) << a, c, b;
        F.row(f++) << b, c, d;
      }
  }
};

TEST(CcdValidation, MeshEntryPointsThrow) {
  // Two parallel sheets 0.1 apart, still: within d = 0.2, not within 0.05.
  const Sheet A(0.0, 0.0), B(0.1, 0.0);
  const auto ma = impact::make_mesh_motion(A.V0, A.V1, A.F), mb = impact::make_mesh_motion(B.V0, B.V1, B.F);
  for (double d : {kNaN, -1.0, kInf, 1e101})
    expect_invalid([&] { impact::SweptMeshBvh<double>::build(ma, d); }, "SweptMeshBvh::build: min_separation");

  impact::CcdOptions o;
  o.min_separation = 0.2;
  const auto ta0 = impact::SweptMeshBvh<double>::build(ma), tb0 = impact::SweptMeshBvh<double>::build(mb);
  const auto ta = impact::SweptMeshBvh<double>::build(ma, 0.2), tb = impact::SweptMeshBvh<double>::build(mb, 0.2);
  EXPECT_TRUE(impact::mesh_ccd(ma, ta, mb, tb, o).hit);  // the contact the thin trees would hide
  expect_invalid([&] { impact::mesh_ccd(ma, ta0, mb, tb, o); }, "mesh_ccd: the tree of mesh a was built for a minimum separation");
  expect_invalid([&] { impact::mesh_ccd(ma, ta, mb, tb0, o); }, "mesh_ccd: the tree of mesh b was built for a minimum separation");
  expect_invalid([&] { impact::mesh_self_ccd(ma, ta0, o); }, "mesh_self_ccd: the tree of the mesh was built");
  // an inflation set by hand to NaN
  auto tn = ta;
  tn.inflate = kNaN;
  expect_invalid([&] { impact::mesh_self_ccd(ma, tn, o); }, "minimum separation");
  // bad options
  o.t_max = kNaN;
  expect_invalid([&] { impact::mesh_ccd(ma, ta, mb, tb, o); }, "mesh_ccd: CcdOptions::t_max");
  expect_invalid([&] { impact::mesh_self_ccd(ma, ta, o); }, "mesh_self_ccd: CcdOptions::t_max");
  o = {};
  o.max_iterations = 0;
  expect_invalid([&] { impact::mesh_ccd(ma, ta, mb, tb, o); }, "mesh_ccd: CcdOptions::max_iterations");
  // a tree of another mesh
  const Sheet C(0.0, 0.0);
  impact::Faces F2 = C.F.topRows(4);
  const auto mc = impact::make_mesh_motion(C.V0, C.V1, F2);
  expect_invalid([&] { impact::mesh_ccd(mc, ta, mb, tb, {}); }, "mesh_ccd: the tree of mesh a has 8 triangles, the mesh 4");
  // an empty motion
  expect_invalid([&] { impact::mesh_self_ccd(impact::MeshMotion<double>{}, ta, {}); }, "empty mesh motion");
  expect_invalid([&] { impact::SweptMeshBvh<double>::build(impact::MeshMotion<double>{}); }, "empty mesh motion");
  // coordinates out of range
  impact::Vertices<double> far = A.V1;
  far(4, 1) = 1e100;
  expect_invalid([&] { impact::make_mesh_motion(A.V0, far, A.F); }, "mesh motion (end): vertex 4");  // named by the mesh validation's range check
  far(4, 1) = kNaN;
  expect_invalid([&] { impact::make_mesh_motion(far, A.V1, A.F); }, "mesh motion (start): vertex 4");
}

}  // namespace
