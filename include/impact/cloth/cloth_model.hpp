// SPDX-License-Identifier: MIT
/// \file
/// The reference cloth model: a small mass–spring cloth with a backward Euler integrator, so that
/// the collision step (collision_step.hpp) has scenes to work on without another simulator. It is
/// secondary to the collision handling: a plain, documented Baraff–Witkin style step, not a
/// production cloth solver (no strain limiting, no anisotropic material, no continuum bending).
///
/// Model (built once from a triangle mesh at rest, one or many components):
///  - masses lumped from the rest triangle areas (density x area / 3 per corner);
///  - stretch springs on every edge of the mesh;
///  - across every interior edge (i, j) with opposite vertices k and l of the two triangles, a
///    spring k–l: a *shear* spring when (i, j) is the longest rest edge of both triangles (on a
///    grid split into triangles this is the other diagonal of the quad), a *bending* spring
///    otherwise (a flap spring, as Provot's "flexion" springs on triangle meshes);
///  - spring forces f_a = -k (|d| - L) d/|d| - c (d/|d| . (v_a - v_b)) d/|d| with d = x_a - x_b,
///    stiffness k (N/m) and damping c = damping_time * k (N s/m) per spring; air drag -air m v;
///    gravity m g;
///  - vertices of infinite mass are kinematic: pinned at x0, or moved to positions given for the
///    step (scripted). The collision step sees the same infinite masses.
///
/// Integrator (Baraff & Witkin 1998, "Large steps in cloth simulation", section 3): one Newton
/// step of backward Euler,
///   (M - dt df/dv - dt^2 df/dx) dv = dt (f0 + dt df/dx v0),  v1 = v0 + dv,  x1 = x0 + dt v1,
/// with each spring's stiffness matrix made positive semi-definite by dropping the transverse
/// term of compressed springs (Choi & Ko 2002), so the system is symmetric positive definite.
/// It is solved matrix-free (the system never exists as a sparse matrix: 9 (n + 2 springs)
/// entries would be hundreds of MB at 10^5 vertices) by conjugate gradients with a block-Jacobi
/// preconditioner, warm-started at dv = dt g. Backward Euler damps: the step is stable at
/// dt = 1/60..1/240 s and beyond for any stiffness, at the price of numerical damping.
///
/// Candidate end positions x1 go through the collision step, which returns x1'; the velocity of
/// the next step is (x1' - x0) / dt, exactly backward Euler's v1 when nothing collided.
///
/// Thread safety: a MassSpringCloth is a plain value; the step functions read it (const) and
/// return their results, so steps of different cloths, or reads of one cloth, may run at once;
/// changing a cloth is not concurrent with anything else on it.
#pragma once

#include "impact/core/error.hpp"
#include "impact/core/types.hpp"
#include "impact/geometry/triangle_mesh.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <type_traits>
#include <vector>

namespace impact {

/// What a spring resists (they differ only in their stiffness).
enum class SpringKind : std::uint8_t { stretch, shear, bend };

/// One spring between vertices a and b.
template <class S> struct Spring {
  int a = 0, b = 0;
  S rest_length = S(0);  ///< m
  S stiffness = S(0);    ///< k, N/m
  S damping = S(0);      ///< c, N s/m, along the spring
  SpringKind kind = SpringKind::stretch;
};

/// Material of the mass–spring cloth. Stiffnesses are per spring: on a regular grid the sheet's
/// in-plane response does not depend on the resolution (springs in series and in parallel scale
/// alike); the flap springs' bending resistance does.
template <class S> struct MassSpringParams {
  S density = S(0.1);              ///< kg/m^2 (light cotton is about 0.1)
  S stretch_stiffness = S(2000);   ///< N/m, every mesh edge
  S shear_stiffness = S(200);      ///< N/m, across quad diagonals
  S bend_stiffness = S(2);         ///< N/m, flap springs
  S damping_time = S(0.002);       ///< s: each spring's damping coefficient is damping_time x stiffness
  S air_damping = S(0.05);         ///< 1/s: drag force -air_damping m v on every free vertex
  Vec3<S> gravity = Vec3<S>(S(0), S(0), S(-9.81));  ///< m/s^2
};

/// A mass–spring cloth built from a triangle mesh at rest. Plain data: the springs and masses may
/// be edited after construction (set a mass to +infinity, or call pin(), to make a vertex
/// kinematic).
template <class S> struct MassSpringCloth {
  Faces F;                                ///< the triangles (for the collision step and output)
  std::vector<Spring<S>> springs;         ///< every spring, stretch first
  Eigen::Matrix<S, Eigen::Dynamic, 1> mass;  ///< kg per vertex; +infinity = kinematic
  Vec3<S> gravity = Vec3<S>::Zero();      ///< m/s^2
  S air_damping = S(0);                   ///< 1/s

  int num_vertices() const { return static_cast<int>(mass.size()); }
  bool kinematic(int v) const { return !(mass(v) < std::numeric_limits<S>::infinity()); }
  /// Makes vertex v kinematic (infinite mass): it stays where it is unless scripted.
  void pin(int v) {
    if (v < 0 || v >= num_vertices()) throw InvalidInput("MassSpringCloth::pin: vertex " + std::to_string(v) + " out of range");
    mass(v) = std::numeric_limits<S>::infinity();
  }
  /// Number of springs of one kind.
  int count(SpringKind k) const {
    return static_cast<int>(std::count_if(springs.begin(), springs.end(), [k](const Spring<S>& s) { return s.kind == k; }));
  }
};

namespace detail {

inline void cloth_require(bool ok, const std::string& what) {
  if (!ok) throw InvalidInput(what);
}

template <class S> bool finite_nonnegative(S x) { return std::isfinite(x) && x >= S(0); }

}  // namespace detail

/// Builds the springs and lumped masses of a cloth whose rest shape is (V, F). Throws InvalidInput
/// on an invalid mesh (see validate_mesh), negative or non-finite parameters, a non-positive
/// density, or a vertex of zero mass (in no triangle of positive area).
/// Cost: O(m log m) for m triangles.
template <class S>
MassSpringCloth<S> make_mass_spring_cloth(const Vertices<S>& V, const Faces& F, const MassSpringParams<S>& p = {}) {
  static_assert(is_supported_scalar_v<S>, "float or double");
  validate_mesh(V, F, "make_mass_spring_cloth");
  detail::cloth_require(std::isfinite(p.density) && p.density > S(0), "make_mass_spring_cloth: density must be positive and finite");
  detail::cloth_require(detail::finite_nonnegative(p.stretch_stiffness) && detail::finite_nonnegative(p.shear_stiffness) &&
                            detail::finite_nonnegative(p.bend_stiffness) && detail::finite_nonnegative(p.damping_time) &&
                            detail::finite_nonnegative(p.air_damping),
                        "make_mass_spring_cloth: stiffness, damping_time and air_damping must be finite and >= 0");
  detail::cloth_require(all_finite(p.gravity), "make_mass_spring_cloth: gravity must be finite");
  const int n = static_cast<int>(V.rows()), m = static_cast<int>(F.rows());
  MassSpringCloth<S> c;
  c.F = F;
  c.gravity = p.gravity;
  c.air_damping = p.air_damping;
  c.mass = Eigen::Matrix<S, Eigen::Dynamic, 1>::Zero(n);
  auto pos = [&V](int i) -> Vec3<S> { return V.row(i).transpose(); };
  for (int t = 0; t < m; ++t) {
    const S area = (pos(F(t, 1)) - pos(F(t, 0))).cross(pos(F(t, 2)) - pos(F(t, 0))).norm() / S(2);
    for (int k = 0; k < 3; ++k) c.mass(F(t, k)) += p.density * area / S(3);
  }
  for (int i = 0; i < n; ++i)
    detail::cloth_require(c.mass(i) > S(0), "make_mass_spring_cloth: vertex " + std::to_string(i) +
                                                 " has zero mass (it is in no triangle of positive area)");

  // Half-edges sorted by their undirected edge: (min, max, opposite vertex, triangle).
  struct HalfEdge {
    int lo, hi, opposite, tri;
  };
  std::vector<HalfEdge> he;
  he.reserve(3 * static_cast<std::size_t>(m));
  for (int t = 0; t < m; ++t)
    for (int k = 0; k < 3; ++k) {
      const int a = F(t, k), b = F(t, (k + 1) % 3), o = F(t, (k + 2) % 3);
      if (a == b) continue;  // degenerate index triangle: no edge
      he.push_back({std::min(a, b), std::max(a, b), o, t});
    }
  std::sort(he.begin(), he.end(), [](const HalfEdge& x, const HalfEdge& y) { return x.lo != y.lo ? x.lo < y.lo : x.hi < y.hi; });
  auto spring = [&](int a, int b, S k, SpringKind kind) {
    Spring<S> s;
    s.a = a;
    s.b = b;
    s.rest_length = (pos(a) - pos(b)).norm();
    s.stiffness = k;
    s.damping = p.damping_time * k;
    s.kind = kind;
    return s;
  };
  // Longest rest edge test: is (lo, hi) at least as long as the other two edges of triangle t?
  auto longest = [&](const HalfEdge& h) {
    const S l = (pos(h.lo) - pos(h.hi)).squaredNorm();
    return l >= (pos(h.lo) - pos(h.opposite)).squaredNorm() && l >= (pos(h.hi) - pos(h.opposite)).squaredNorm();
  };
  std::vector<Spring<S>> flaps;
  for (std::size_t i = 0; i < he.size();) {
    std::size_t j = i;
    while (j < he.size() && he[j].lo == he[i].lo && he[j].hi == he[i].hi) ++j;
    c.springs.push_back(spring(he[i].lo, he[i].hi, p.stretch_stiffness, SpringKind::stretch));
    for (std::size_t x = i; x < j; ++x)
      for (std::size_t y = x + 1; y < j; ++y) {
        const int k = he[x].opposite, l = he[y].opposite;
        if (k == l) continue;  // two triangles on the same three vertices
        const bool shear = longest(he[x]) && longest(he[y]);
        flaps.push_back(spring(std::min(k, l), std::max(k, l), shear ? p.shear_stiffness : p.bend_stiffness,
                               shear ? SpringKind::shear : SpringKind::bend));
      }
    i = j;
  }
  c.springs.insert(c.springs.end(), flaps.begin(), flaps.end());
  return c;
}

/// Builds the cloth from a TriangleMesh at rest.
template <class S> MassSpringCloth<S> make_mass_spring_cloth(const TriangleMesh<S>& rest, const MassSpringParams<S>& p = {}) {
  return make_mass_spring_cloth(rest.V, rest.F, p);
}

/// Options of one implicit step.
template <class S> struct ImplicitStepOptions {
  S dt = S(1) / S(60);  ///< s, > 0
  /// Conjugate gradients stop when |residual| <= tolerance |right-hand side| (preconditioned
  /// norms are not used: the plain 2-norm of the force residual) or after max_iterations.
  S tolerance = std::is_same_v<S, float> ? S(1e-5) : S(1e-6);
  int max_iterations = 200;
};

/// End positions of some kinematic vertices for this step (scripted motion). Vertices not listed
/// that have infinite mass stay at x0.
template <class S> struct ScriptedVertices {
  std::vector<int> ids;   ///< vertex indices, each of infinite mass
  Vertices<S> positions;  ///< ids.size() x 3 end positions
};

/// Result of one implicit step.
template <class S> struct ImplicitStepResult {
  Vertices<S> x1;  ///< candidate end positions, x0 + dt v1 (kinematic vertices at their targets)
  Vertices<S> v1;  ///< end velocities
  int iterations = 0;   ///< conjugate-gradient iterations
  S residual = S(0);    ///< final |residual| / |right-hand side| (0 when the right-hand side is 0)
  bool converged = false;
};

namespace detail {

template <class S> inline Mat3<S> inverse_spd3(const Mat3<S>& A) {
  return A.inverse();  // 3x3 closed form (cofactors); A is SPD with a positive mass term
}

}  // namespace detail

/// Kinetic energy sum m |v|^2 / 2 over the vertices of finite mass (J).
template <class S> S cloth_kinetic_energy(const MassSpringCloth<S>& c, const Vertices<S>& v) {
  S e = S(0);
  for (int i = 0; i < c.num_vertices(); ++i)
    if (!c.kinematic(i)) e += c.mass(i) * v.row(i).squaredNorm() / S(2);
  return e;
}

/// Potential energy: springs sum k (|d| - L)^2 / 2 plus gravity -sum m g . x over the vertices
/// of finite mass (J, zero at height 0 for gravity along -z).
template <class S> S cloth_potential_energy(const MassSpringCloth<S>& c, const Vertices<S>& x) {
  S e = S(0);
  for (const Spring<S>& s : c.springs) {
    const S ext = (x.row(s.a) - x.row(s.b)).norm() - s.rest_length;
    e += s.stiffness * ext * ext / S(2);
  }
  for (int i = 0; i < c.num_vertices(); ++i)
    if (!c.kinematic(i)) e -= c.mass(i) * c.gravity.dot(x.row(i).transpose());
  return e;
}

/// One backward Euler step (one Newton iteration, see the file comment) from positions x0 and
/// velocities v0 (n x 3 each). Kinematic vertices move to their scripted positions or stay at x0;
/// their velocity is (target - x0) / dt. Throws InvalidInput, before any work, on mismatched
/// sizes, non-finite positions or velocities, dt <= 0 or non-finite, a non-positive tolerance or
/// iteration budget, or a scripted id that is out of range or not kinematic, or a non-finite
/// scripted position. Cost per CG iteration: O(vertices + springs).
template <class S>
ImplicitStepResult<S> implicit_euler_step(const MassSpringCloth<S>& c, const Vertices<S>& x0, const Vertices<S>& v0,
                                          const ImplicitStepOptions<S>& o = {}, const ScriptedVertices<S>* scripted = nullptr) {
  const int n = c.num_vertices();
  detail::cloth_require(x0.rows() == n && v0.rows() == n,
                        "implicit_euler_step: x0 and v0 must have " + std::to_string(n) + " rows (one per vertex)");
  detail::cloth_require(all_finite(x0) && all_finite(v0), "implicit_euler_step: x0 or v0 has a NaN or infinite value");
  detail::cloth_require(std::isfinite(o.dt) && o.dt > S(0), "implicit_euler_step: dt must be positive and finite");
  detail::cloth_require(std::isfinite(o.tolerance) && o.tolerance > S(0) && o.max_iterations >= 1,
                        "implicit_euler_step: tolerance must be positive and max_iterations >= 1");
  for (const Spring<S>& s : c.springs)
    detail::cloth_require(s.a >= 0 && s.a < n && s.b >= 0 && s.b < n, "implicit_euler_step: a spring has a vertex out of range");
  if (scripted) {
    detail::cloth_require(scripted->positions.rows() == static_cast<Eigen::Index>(scripted->ids.size()),
                          "implicit_euler_step: scripted positions must have one row per scripted id");
    detail::cloth_require(all_finite(scripted->positions), "implicit_euler_step: a scripted position is NaN or infinite");
    for (int id : scripted->ids) {
      detail::cloth_require(id >= 0 && id < n, "implicit_euler_step: scripted vertex " + std::to_string(id) + " out of range");
      detail::cloth_require(c.kinematic(id), "implicit_euler_step: scripted vertex " + std::to_string(id) +
                                                 " has finite mass (make it kinematic first)");
    }
  }
  const S h = o.dt;
  ImplicitStepResult<S> r;
  r.v1 = v0;
  r.x1 = x0;

  // Known velocity changes of kinematic vertices; free vertices start at the free-fall guess.
  Vertices<S> dv(n, 3), rhs = Vertices<S>::Zero(n, 3);
  std::vector<char> is_free(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    is_free[static_cast<std::size_t>(i)] = !c.kinematic(i);
    if (is_free[static_cast<std::size_t>(i)]) dv.row(i) = (h * c.gravity).transpose();
    else dv.row(i) = -v0.row(i);  // pinned: v1 = 0
  }
  if (scripted)
    for (std::size_t k = 0; k < scripted->ids.size(); ++k) {
      const int id = scripted->ids[k];
      dv.row(id) = (scripted->positions.row(static_cast<Eigen::Index>(k)) - x0.row(id)) / h - v0.row(id);
    }

  // Spring blocks and the right-hand side dt (f0 + dt df/dx v0) - A_fk dv_k.
  std::vector<Mat3<S>> B(c.springs.size());
  std::vector<Mat3<S>> diag(static_cast<std::size_t>(n), Mat3<S>::Zero());
  for (int i = 0; i < n; ++i) {
    if (!is_free[static_cast<std::size_t>(i)]) continue;
    const S mi = c.mass(i);
    rhs.row(i) = h * mi * (c.gravity - c.air_damping * v0.row(i).transpose()).transpose();
    diag[static_cast<std::size_t>(i)] = mi * (S(1) + h * c.air_damping) * Mat3<S>::Identity();
  }
  for (std::size_t k = 0; k < c.springs.size(); ++k) {
    const Spring<S>& s = c.springs[k];
    const Vec3<S> d = (x0.row(s.a) - x0.row(s.b)).transpose();
    const S l = d.norm();
    if (!(l > S(0))) {
      B[k].setZero();  // coincident ends: no direction, no force
      continue;
    }
    const Vec3<S> u = d / l;
    const Mat3<S> uu = u * u.transpose();
    const S transverse = std::max(S(0), S(1) - s.rest_length / l);
    const Mat3<S> K = s.stiffness * (uu + transverse * (Mat3<S>::Identity() - uu));
    B[k] = h * h * K + h * s.damping * uu;
    const Vec3<S> vab = (v0.row(s.a) - v0.row(s.b)).transpose();
    const Vec3<S> f = -s.stiffness * (l - s.rest_length) * u - s.damping * u.dot(vab) * u - h * (K * vab);
    const bool fa = is_free[static_cast<std::size_t>(s.a)] != 0, fb = is_free[static_cast<std::size_t>(s.b)] != 0;
    if (fa) {
      rhs.row(s.a) += h * f.transpose();
      diag[static_cast<std::size_t>(s.a)] += B[k];
      if (!fb) rhs.row(s.a) += (B[k] * dv.row(s.b).transpose()).transpose();
    }
    if (fb) {
      rhs.row(s.b) -= h * f.transpose();
      diag[static_cast<std::size_t>(s.b)] += B[k];
      if (!fa) rhs.row(s.b) += (B[k] * dv.row(s.a).transpose()).transpose();
    }
  }
  std::vector<Mat3<S>> precond(static_cast<std::size_t>(n), Mat3<S>::Zero());
  for (int i = 0; i < n; ++i)
    if (is_free[static_cast<std::size_t>(i)]) precond[static_cast<std::size_t>(i)] = detail::inverse_spd3(diag[static_cast<std::size_t>(i)]);

  // y = A x on the free vertices (x is read on free vertices only).
  auto apply = [&](const Vertices<S>& x, Vertices<S>& y) {
    for (int i = 0; i < n; ++i) {
      if (is_free[static_cast<std::size_t>(i)]) y.row(i) = c.mass(i) * (S(1) + h * c.air_damping) * x.row(i);
      else y.row(i).setZero();
    }
    for (std::size_t k = 0; k < c.springs.size(); ++k) {
      const Spring<S>& s = c.springs[k];
      const bool fa = is_free[static_cast<std::size_t>(s.a)] != 0, fb = is_free[static_cast<std::size_t>(s.b)] != 0;
      const Vec3<S> xa = fa ? Vec3<S>(x.row(s.a).transpose()) : Vec3<S>::Zero();
      const Vec3<S> xb = fb ? Vec3<S>(x.row(s.b).transpose()) : Vec3<S>::Zero();
      const Vec3<S> q = B[k] * (xa - xb);
      if (fa) y.row(s.a) += q.transpose();
      if (fb) y.row(s.b) -= q.transpose();
    }
  };
  auto dot = [&](const Vertices<S>& a, const Vertices<S>& b) {
    S sum = S(0);
    for (int i = 0; i < n; ++i)
      if (is_free[static_cast<std::size_t>(i)]) sum += a.row(i).dot(b.row(i));
    return sum;
  };
  auto precondition = [&](const Vertices<S>& a, Vertices<S>& z) {
    for (int i = 0; i < n; ++i) {
      if (is_free[static_cast<std::size_t>(i)]) z.row(i) = (precond[static_cast<std::size_t>(i)] * a.row(i).transpose()).transpose();
      else z.row(i).setZero();
    }
  };

  // Preconditioned conjugate gradients on the free vertices.
  Vertices<S> res(n, 3), z(n, 3), pdir(n, 3), Ap(n, 3);
  apply(dv, Ap);
  res = rhs - Ap;
  for (int i = 0; i < n; ++i)
    if (!is_free[static_cast<std::size_t>(i)]) res.row(i).setZero();
  const S bnorm = std::sqrt(dot(rhs, rhs));
  S rnorm = std::sqrt(dot(res, res));
  precondition(res, z);
  pdir = z;
  S rz = dot(res, z);
  int it = 0;
  while (rnorm > o.tolerance * bnorm && it < o.max_iterations) {
    apply(pdir, Ap);
    const S pAp = dot(pdir, Ap);
    if (!(pAp > S(0))) break;  // exact solution reached (p = 0) or lost to rounding
    const S alpha = rz / pAp;
    for (int i = 0; i < n; ++i)
      if (is_free[static_cast<std::size_t>(i)]) {
        dv.row(i) += alpha * pdir.row(i);
        res.row(i) -= alpha * Ap.row(i);
      }
    ++it;
    rnorm = std::sqrt(dot(res, res));
    precondition(res, z);
    const S rz_next = dot(res, z);
    const S beta = rz_next / rz;
    rz = rz_next;
    for (int i = 0; i < n; ++i)
      if (is_free[static_cast<std::size_t>(i)]) pdir.row(i) = z.row(i) + beta * pdir.row(i);
  }
  r.iterations = it;
  r.residual = bnorm > S(0) ? rnorm / bnorm : S(0);
  r.converged = rnorm <= o.tolerance * bnorm;
  r.v1 = v0 + dv;
  r.x1 = x0 + h * r.v1;
  std::vector<char> moved(static_cast<std::size_t>(n), 0);
  if (scripted)  // exactly on target, whatever the rounding of x0 + dt (target - x0) / dt
    for (std::size_t k = 0; k < scripted->ids.size(); ++k) {
      r.x1.row(scripted->ids[k]) = scripted->positions.row(static_cast<Eigen::Index>(k));
      moved[static_cast<std::size_t>(scripted->ids[k])] = 1;
    }
  for (int i = 0; i < n; ++i)
    if (!is_free[static_cast<std::size_t>(i)] && !moved[static_cast<std::size_t>(i)]) {
      r.x1.row(i) = x0.row(i);
      r.v1.row(i).setZero();
    }
  return r;
}

}  // namespace impact
