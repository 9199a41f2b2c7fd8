// SPDX-License-Identifier: MIT
// The scenes of impact-cloth-bench (and nothing else): a cloth (one mesh, one or many components)
// with the reference mass-spring model, its scripted vertices, and the obstacles of each step
// (rigid meshes with a pose at every time, the ground as a large quad). Units: metres, seconds,
// kilograms; gravity along -z.
//
//  drape:  a 1 m square cloth falls from just above a sphere (radius 0.25 m on the ground), or
//          above the mesh given with --obstacle (scaled so its largest side is 0.6 m, standing on
//          the ground), onto it and the ground.
//  twist:  a 1 m square cloth pinned along its edges x = -0.5 and x = +0.5; the edges turn about
//          the x axis against each other at half a turn per second each (one relative turn per
//          second) and move 0.3 m closer over the first 4 s.
//  layers: K square cloths of 1 m, 2 cm apart, each turned by 7 degrees against the one below,
//          fall on the sphere and the ground.
//  spin:   a 1 m square cloth falls on a sphere that turns about the vertical axis at one turn per
//          second, and on the ground; friction drags the cloth round.
//  shot:   a 1 m square cloth hangs from its top edge in the plane y = 0; a sphere of radius 5 cm
//          starts 0.5 m in front of it and moves through the cloth's plane along +y at the given
//          speed, stopping 0.5 m behind the plane (the cloth cannot tear: it must wrap the sphere).
#pragma once

#include "impact/cloth/cloth_model.hpp"
#include "impact/cloth/step_options.hpp"
#include "impact/geometry/mesh_generators.hpp"

#include <cmath>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace impact::bench {

struct ClothSceneConfig {
  std::string scene = "drape";
  int resolution = 32;   ///< cells along each side of a cloth
  int layers = 4;        ///< cloths in the layers scene
  double speed = 1000;   ///< m/s, shot scene
  const TriangleMesh<double>* obstacle = nullptr;  ///< drape: replaces the sphere (any scale)
};

/// A rigid obstacle of the scene: its mesh in its own frame and its pose at time t.
struct SceneRigid {
  std::string name;
  TriangleMesh<double> mesh;
  std::function<RigidTransform<double>(double)> pose;
};

struct ClothScene {
  std::string name;
  TriangleMesh<double> rest;     ///< every cloth, one mesh
  int components = 1;            ///< cloths in `rest` (equal vertex counts, consecutive)
  MassSpringCloth<double> model;
  Vertices<double> x, v;         ///< current state
  std::vector<SceneRigid> rigid;
  /// Scripted cloth vertices at time t (empty ids: none).
  std::function<void(double, ScriptedVertices<double>&)> script;
  double friction = 0.3;

  /// The obstacles of the step [t0, t1] (pointers into this scene).
  ClothObstacles<double> obstacles(double t0, double t1) const {
    ClothObstacles<double> o;
    for (const auto& r : rigid) o.rigid.push_back({&r.mesh, r.pose(t0), r.pose(t1)});
    return o;
  }
};

namespace detail_scene {

inline constexpr double pi = 3.14159265358979323846;

inline Mat3<double> rot_z(double a) { return Eigen::AngleAxisd(a, Vec3<double>::UnitZ()).toRotationMatrix(); }
inline Mat3<double> rot_x(double a) { return Eigen::AngleAxisd(a, Vec3<double>::UnitX()).toRotationMatrix(); }

/// A square of 20 m at z = 0 (two triangles, normal +z).
inline TriangleMesh<double> ground_quad() {
  TriangleMesh<double> g;
  g.V.resize(4, 3);
  g.V << -10, -10, 0, 10, -10, 0, 10, 10, 0, -10, 10, 0;
  g.F.resize(2, 3);
  g.F << 0, 1, 2, 0, 2, 3;
  return g;
}

inline SceneRigid fixed(std::string name, TriangleMesh<double> m) {
  return {std::move(name), std::move(m), [](double) { return RigidTransform<double>(); }};
}

/// Appends the grid cloth (n x n cells of 1 m) placed by rotation R and translation t.
inline void append_cloth(TriangleMesh<double>& all, int n, const Mat3<double>& R, const Vec3<double>& t) {
  const TriangleMesh<double> g = make_grid<double>(n, n, 1.0);
  const Eigen::Index v0 = all.V.rows(), f0 = all.F.rows();
  all.V.conservativeResize(v0 + g.V.rows(), 3);
  all.F.conservativeResize(f0 + g.F.rows(), 3);
  for (Eigen::Index i = 0; i < g.V.rows(); ++i) all.V.row(v0 + i) = (R * g.V.row(i).transpose() + t).transpose();
  all.F.bottomRows(g.F.rows()) = g.F.array() + static_cast<int>(v0);
}

}  // namespace detail_scene

/// Cloth material of the scenes: light cotton-like, soft bending.
inline MassSpringParams<double> scene_material() {
  MassSpringParams<double> p;
  p.density = 0.15;
  p.stretch_stiffness = 3000;
  p.shear_stiffness = 300;
  p.bend_stiffness = 3;
  p.damping_time = 0.002;
  p.air_damping = 0.1;
  return p;
}

/// Builds a scene. Throws InvalidInput on an unknown name or bad numbers.
inline std::unique_ptr<ClothScene> make_cloth_scene(const ClothSceneConfig& c) {
  using namespace detail_scene;
  if (c.resolution < 1 || c.resolution > 2000) throw InvalidInput("cloth scene: resolution must be in [1, 2000]");
  if (c.layers < 1 || c.layers > 1000) throw InvalidInput("cloth scene: layers must be in [1, 1000]");
  // (resolution + 1)^2 vertices a cloth: the product of the two largest values would be 4e9, past
  // an int's vertex index and tens of GB; 10^7 vertices is a hundred times the largest scene.
  const std::int64_t cloth_vertices = std::int64_t(c.resolution + 1) * (c.resolution + 1) * (c.scene == "layers" ? c.layers : 1);
  if (cloth_vertices > 10000000)
    throw InvalidInput("cloth scene: (resolution + 1)^2 x layers must be at most 10^7 vertices, is " + std::to_string(cloth_vertices));
  auto s = std::make_unique<ClothScene>();
  s->name = c.scene;
  const int n = c.resolution;
  const Mat3<double> I = Mat3<double>::Identity();
  const double sphere_r = 0.25;
  auto sphere = [&](double r, int sub) { return make_icosphere<double>(r, sub); };
  if (c.scene == "drape" || c.scene == "spin" || c.scene == "layers") {
    double top = 2 * sphere_r;
    if (c.scene == "drape" && c.obstacle) {
      TriangleMesh<double> m = *c.obstacle;
      validate_mesh(m, "drape obstacle");
      const Vec3<double> lo = m.V.colwise().minCoeff().transpose(), hi = m.V.colwise().maxCoeff().transpose();
      const double extent = (hi - lo).maxCoeff();
      if (!(extent > 0)) throw InvalidInput("drape obstacle: the mesh has no extent");
      const double scale = 0.6 / extent;
      const Vec3<double> centre(0.5 * (lo.x() + hi.x()), 0.5 * (lo.y() + hi.y()), lo.z());
      for (Eigen::Index i = 0; i < m.V.rows(); ++i) m.V.row(i) = (scale * (m.V.row(i).transpose() - centre)).transpose();
      top = scale * (hi.z() - lo.z());
      s->rigid.push_back(fixed("obstacle", std::move(m)));
    } else if (c.scene == "spin") {
      const Vec3<double> centre(0, 0, sphere_r);
      const double omega = 2 * pi;  // one turn per second
      s->rigid.push_back({"sphere", sphere(sphere_r, 3), [centre, omega](double t) {
                            const Mat3<double> R = rot_z(omega * t);
                            return RigidTransform<double>(R, centre);
                          }});
      s->friction = 0.5;
    } else {
      TriangleMesh<double> m = sphere(sphere_r, 3);
      m.V.col(2).array() += sphere_r;
      s->rigid.push_back(fixed("sphere", std::move(m)));
    }
    s->rigid.push_back(fixed("ground", ground_quad()));
    const int k = c.scene == "layers" ? c.layers : 1;
    for (int i = 0; i < k; ++i) append_cloth(s->rest, n, rot_z(i * 7.0 * pi / 180.0), Vec3<double>(0, 0, top + 0.05 + 0.02 * i));
    s->components = k;
    s->model = make_mass_spring_cloth(s->rest, scene_material());
  } else if (c.scene == "twist") {
    append_cloth(s->rest, n, I, Vec3<double>(0, 0, 0.5));
    s->model = make_mass_spring_cloth(s->rest, scene_material());
    std::vector<int> left, right;
    for (int j = 0; j <= n; ++j) {
      left.push_back(j * (n + 1));
      right.push_back(n + j * (n + 1));
    }
    for (int v : left) s->model.pin(v);
    for (int v : right) s->model.pin(v);
    const Vertices<double> rest = s->rest.V;
    s->script = [left, right, rest](double t, ScriptedVertices<double>& sc) {
      const double turn = pi * t;  // half a turn per second each
      const double in = 0.3 * std::min(1.0, t / 4);
      sc.ids.clear();
      sc.positions.resize(static_cast<Eigen::Index>(left.size() + right.size()), 3);
      Eigen::Index k = 0;
      for (int side = 0; side < 2; ++side) {
        const auto& ids = side ? right : left;
        const Mat3<double> R = rot_x(side ? -turn : turn);
        for (int v : ids) {
          Vec3<double> p = rest.row(v).transpose();
          const Vec3<double> axis(0, 0, 0.5);
          p = axis + R * (p - axis);
          p.x() += side ? -in : in;
          sc.ids.push_back(v);
          sc.positions.row(k++) = p.transpose();
        }
      }
    };
  } else if (c.scene == "shot") {
    if (!(c.speed > 0) || !std::isfinite(c.speed)) throw InvalidInput("cloth scene: speed must be positive");
    append_cloth(s->rest, n, rot_x(pi / 2), Vec3<double>(0, 0, 1.0));  // grid y -> z: plane y = 0, z in [0.5, 1.5]
    s->model = make_mass_spring_cloth(s->rest, scene_material());
    for (int i = 0; i < s->rest.num_vertices(); ++i)
      if (s->rest.V(i, 2) > 1.5 - 1e-9) s->model.pin(i);
    const double speed = c.speed;
    s->rigid.push_back({"bullet", sphere(0.05, 2), [speed](double t) {
                          const double y = std::min(0.5, -0.5 + speed * t);
                          return RigidTransform<double>(Mat3<double>::Identity(), Vec3<double>(0.1, y, 1.03));
                        }});
  } else {
    throw InvalidInput("cloth scene: unknown scene '" + c.scene + "' (drape, twist, layers, spin, shot)");
  }
  s->x = s->rest.V;
  s->v = Vertices<double>::Zero(s->x.rows(), 3);
  return s;
}

}  // namespace impact::bench
