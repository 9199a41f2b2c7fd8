// SPDX-License-Identifier: MIT
/// \file
/// Penetration depth and normal of two intersecting convex sets given by their support functions:
/// the library's own expanding polytope algorithm (EPA, van den Bergen, "Proximity Queries and
/// Penetration Depth Computation on 3D Game Objects", GDC 2001) followed, for curved shapes, by a
/// local Newton refinement of the direction. Eigen only.
///
/// The penetration depth of A and B is the least overlap over unit directions n,
///   depth = min_n f(n),  f(n) = h_A(n) + h_B(-n) = h_D(n),  D = A - B (contains the origin),
/// the distance from the origin to the boundary of D. Two bounds are kept:
///   upper  f(n) at the best direction evaluated (translating B by f(n) n separates the sets);
///   lower  the distance from the origin to the boundary of EPA's polytope, the hull of support
///          points of D (inside D), so no direction can overlap less: a certified lower bound.
/// EPA grows the polytope towards its face closest to the origin (Kelley's cutting-plane method on
/// f). For polytopes (boxes, hulls, triangles) the support in a face's normal lies on the face
/// once that face is a face of D, so it stops exactly (upper - lower <= tolerance) after finitely
/// many steps. For curved shapes the gap closes geometrically on the shapes of this library
/// (cylinder–cylinder: 31.5 support calls per query on average for a gap of 1e-10 of the size,
/// 22.7 for 1e-6). With `refine` it stops at `coarse_tolerance` instead and the direction is
/// refined by Newton's method on f over the sphere: the tangential gradient of f at n
/// is the tangential part of the support point s_D(n), its Hessian P W P - f(n) I with W the
/// derivative of s_D, by central differences of the support. Where the support jumps (D has a flat
/// edge or face there: a ruling of a cylinder or cone, a flat cap), the jump's direction e is a
/// constraint n . e = 0 of the minimiser (its normal cone is a single direction) and the Newton
/// step is taken in the directions left (the edge checked to be a minimum across it: the origin
/// projects between its ends). A step is kept only when f does not increase; the refinement is
/// accepted when Newton's decrement g^T H^-1 g / 2 (the decrease of f still predicted) is within
/// the tolerance with H positive definite (the verifiable first- and second-order conditions of a
/// local minimum of f, in the basin EPA's bounds put it) and no support derivative was
/// near-singular; otherwise EPA goes on to the fine tolerance. Every loop is bounded (EPA by max_iterations support calls and its
/// fixed capacity, Newton by kNewtonSteps); a bound that ends the query is reported. The refinement
/// is off by default (ConvexQueryOptions::newton_refinement): the edges of cylinders and cones
/// (rulings, rims) are kinks of f near most minima, where it rarely verifies (10 of 130
/// cylinder–cylinder penetrations), so it cost more support calls than it saved.
///
/// Numerical contract: APPROXIMATE. depth is f(normal) (an upper bound up to rounding); `lower` is
/// certified; when refined, depth is the value of f at a verified local minimiser.
/// Thread safety: pure functions for the caller. The polytope (about 50 kB) is scratch storage of
/// the calling thread (detail::epa_scratch: allocated on the thread's first query, then reused, no
/// heap allocation per query), so queries on different threads never share it; the support
/// functions must not call epa_penetration themselves (none in this library does).
#pragma once

#include "impact/convex/gjk_distance.hpp"
#include "impact/convex/local_certificate.hpp"
#include "impact/core/types.hpp"
#include "impact/geometry/triangle.hpp"
#include "impact/narrow/closest_point.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <type_traits>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace impact {

/// Result of epa_penetration, in the coordinates of the support functions.
template <class S>
struct EpaPenetration {
  bool intersecting = false;  ///< the origin is in A - B (touching counts)
  bool failed = false;        ///< degenerate polytope (flat Minkowski difference): no answer, use another solver
  bool limit_reached = false; ///< an iteration or capacity bound ended the query before its tolerance
  bool refined = false;       ///< the Newton refinement gave the answer (depth is then below `lower` + the EPA gap)
  bool local_certificate = false;  ///< epa_penetration_local's certificate gave `lower` (EPA stopped early)
  S depth = S(0);             ///< f(normal): overlap of the supports along the normal
  S lower = S(0);             ///< certified lower bound of the depth (EPA's polytope)
  Vec3<S> normal = Vec3<S>::UnitZ();  ///< unit, from A towards B
  Vec3<S> point_a = Vec3<S>::Zero();  ///< deepest point of A (support of A along normal, or EPA's face point)
  Vec3<S> point_b = Vec3<S>::Zero();  ///< deepest point of B
  int iterations = 0;                 ///< support calls of each shape
};

/// Settings of epa_penetration; lengths are absolute (the caller scales them by the shapes' size).
template <class S>
struct EpaSettings {
  S tolerance = S(1e-12);         ///< final: upper - lower (EPA) or Newton's decrement (the predicted decrease of f)
  S coarse_tolerance = S(1e-3);   ///< EPA's gap at which the Newton refinement starts (when `refine`)
  S scale = S(1);                 ///< the shapes' size: FD steps and jump thresholds are relative to it
  int max_iterations = 128;       ///< support calls per shape in all
  bool refine = false;            ///< curved shapes: Newton after EPA's coarse stop (see the file comment)
  /// epa_penetration_local: evaluate f at the unit direction `seed` first (one support call), an
  /// upper bound to start from and the local certificate's first start (e.g. a candidate's normal)
  bool seeded = false;
  Vec3<S> seed = Vec3<S>::UnitZ();
};

namespace detail {

inline constexpr int kEpaMaxVertices = 1024;
inline constexpr int kEpaMaxFaces = 4 * kEpaMaxVertices;
inline constexpr int kNewtonSteps = 16;

template <class S>
struct EpaFace {
  int v[3];
  int adj[3];       // face across edge i (v[i] -> v[i+1])
  int adj_edge[3];  // that edge's index in the neighbour
  Vec3<S> n;        // outward normal, not normalised (EpaPolytope::unit_normal)
  S nn;             // n . n
  bool alive;
};

/// The expanding polytope: vertices (support points of D with their A and B parts) and faces.
template <class S>
struct EpaPolytope {
  SimplexPoint<S> vtx[kEpaMaxVertices];
  EpaFace<S> face[kEpaMaxFaces];
  /// A face's key while alive: its signed distance d from the origin as d |d| (the same order as d,
  /// without a square root; key_distance(key) is d), +infinity once removed: the scan for the
  /// closest face reads only this
  S key[kEpaMaxFaces];
  int nv = 0, nf = 0;
  int free_list[kEpaMaxFaces];
  int nfree = 0;
  // silhouette scratch
  int horizon_face[kEpaMaxFaces];
  int horizon_edge[kEpaMaxFaces];
  int nh = 0;
  int dead[kEpaMaxFaces];
  int ndead = 0;

  /// The signed distance of a face from its key (a square root: taken only for the faces EPA
  /// chooses, not for every face it makes).
  static S key_distance(S k) { return k < S(0) ? -std::sqrt(-k) : std::sqrt(k); }
  /// A face's outward unit normal.
  Vec3<S> unit_normal(int fi) const { return face[fi].n / std::sqrt(face[fi].nn); }

  /// A new face (a, b, c) counter-clockwise seen from outside: its id, -1 when full, -2 - id when
  /// degenerate. Written out in scalars (the Eigen expression executed about twice the instructions).
  /// Its normal stays unnormalised and its key is the signed square of its distance: one division
  /// per face, the square root only for the faces EPA expands (unit_normal, key_distance).
  int make_face(int a, int b, int c) {
    int id;
    if (nfree > 0) {
      id = free_list[--nfree];
    } else {
      if (nf >= kEpaMaxFaces) return -1;
      id = nf++;
    }
    EpaFace<S>& f = face[id];
    f.v[0] = a;
    f.v[1] = b;
    f.v[2] = c;
    const Vec3<S>& pa = vtx[a].w;
    const Vec3<S>& pb = vtx[b].w;
    const Vec3<S>& pc = vtx[c].w;
    const S ux = pb.x() - pa.x(), uy = pb.y() - pa.y(), uz = pb.z() - pa.z();
    const S vx = pc.x() - pa.x(), vy = pc.y() - pa.y(), vz = pc.z() - pa.z();
    const S mx = uy * vz - uz * vy, my = uz * vx - ux * vz, mz = ux * vy - uy * vx;
    const S nn = mx * mx + my * my + mz * mz;
    if (!(nn > S(0))) {  // degenerate
      key[id] = std::numeric_limits<S>::infinity();
      return -2 - id;
    }
    f.n = Vec3<S>(mx, my, mz);
    f.nn = nn;
    const S d = mx * pa.x() + my * pa.y() + mz * pa.z();  // the distance times |n|
    f.alive = true;
    key[id] = d / nn * std::abs(d);
    return id;
  }

  bool visible(int fi, const Vec3<S>& w) const { return face[fi].n.dot(w - vtx[face[fi].v[0]].w) > S(0); }

  /// Depth-first silhouette of the faces visible from w, entered through edge `e` of face fi.
  void silhouette(int fi, int e, const Vec3<S>& w, int depth) {
    if (!face[fi].alive) return;
    if (!visible(fi, w) || depth > kEpaMaxFaces) {
      horizon_face[nh] = fi;
      horizon_edge[nh] = e;
      ++nh;
      return;
    }
    face[fi].alive = false;
    key[fi] = std::numeric_limits<S>::infinity();
    if (ndead < kEpaMaxFaces) dead[ndead++] = fi;
    const EpaFace<S> f = face[fi];
    silhouette(f.adj[(e + 1) % 3], f.adj_edge[(e + 1) % 3], w, depth + 1);
    silhouette(f.adj[(e + 2) % 3], f.adj_edge[(e + 2) % 3], w, depth + 1);
  }
};

/// The index of the least key among key[0..n) (the first one on ties), -1 when none is below
/// +infinity; dmin := that key. Double precision with SSE2: the least value two lanes at a time,
/// then its first index (about half the instructions of the scalar scan on EPA's 50-110 faces).
template <class S>
inline int epa_closest_face(const S* key, int n, S& dmin) {
  int i = 0;
  S m = std::numeric_limits<S>::infinity();
#if defined(__SSE2__)
  if constexpr (std::is_same_v<S, double>) {
    __m128d m0 = _mm_set1_pd(m), m1 = m0;
    for (; i + 4 <= n; i += 4) {  // _mm_min_pd(x, m) keeps m when x is NaN
      m0 = _mm_min_pd(_mm_loadu_pd(key + i), m0);
      m1 = _mm_min_pd(_mm_loadu_pd(key + i + 2), m1);
    }
    m0 = _mm_min_pd(m0, m1);
    const double lo = _mm_cvtsd_f64(m0), hi = _mm_cvtsd_f64(_mm_unpackhi_pd(m0, m0));
    m = hi < lo ? hi : lo;
  }
#endif
  for (; i < n; ++i) m = key[i] < m ? key[i] : m;
  dmin = m;
  if (!(m < std::numeric_limits<S>::infinity())) return -1;
  int f = 0;
#if defined(__SSE2__)
  if constexpr (std::is_same_v<S, double>) {
    const __m128d mm = _mm_set1_pd(m);
    for (; f + 2 <= n; f += 2) {
      const int hit = _mm_movemask_pd(_mm_cmpeq_pd(_mm_loadu_pd(key + f), mm));
      if (hit) return f + ((hit & 1) ? 0 : 1);
    }
  }
#endif
  for (;; ++f)
    if (key[f] == m) return f;
}

/// The calling thread's polytope (about 50 kB for double), allocated on its first EPA query and
/// reused by every later one (no heap allocation per query); one per scalar type and thread, so
/// queries on different threads never share it.
template <class S>
EpaPolytope<S>& epa_scratch() {
  static thread_local std::unique_ptr<EpaPolytope<S>> polytope;
  if (!polytope) polytope.reset(new EpaPolytope<S>);  // default-initialised: no zeroing
  return *polytope;
}

template <class S>
inline void epa_link(EpaFace<S>* face, int f, int e, int g, int h) {
  face[f].adj[e] = g;
  face[f].adj_edge[e] = h;
  face[g].adj[h] = f;
  face[g].adj_edge[h] = e;
}

/// GJK from `first` until a tetrahedron of support points encloses the origin (true, simplex in
/// s[0..3]), a separating direction is found (false), or the bound stops it (false, limit set).
/// The simplex is completed to a tetrahedron when the origin lies on a lower-dimensional one (after
/// the distance solver confirms it, when GJK stalled farther than 1024 epsilons of `scale`).
template <class S, class SupportA, class SupportB>
bool gjk_enclose(const SupportA& support_a, const SupportB& support_b, Vec3<S> first, S scale, int max_iterations, SimplexPoint<S>* s,
                 int& iterations, bool& limit, bool& failed) {
  const auto supp = [&](const Vec3<S>& d) {
    ++iterations;
    return minkowski_support<S>(support_a, support_b, d);
  };
  if (!(first.squaredNorm() > S(0))) first = Vec3<S>::UnitX();
  int n = 1;
  S lambda[4] = {S(1), S(0), S(0), S(0)};
  s[0] = supp(Vec3<S>(-first));
  Vec3<S> v = s[0].w;
  const S tiny = std::numeric_limits<S>::epsilon() * S(16) * scale;
  bool inside = false;
  while (true) {
    if (iterations >= max_iterations) {
      limit = true;
      return false;
    }
    const S vv = v.squaredNorm();
    if (vv <= tiny * tiny) break;  // origin on the simplex: complete it below
    const SimplexPoint<S> p = supp(Vec3<S>(-v));
    if (v.dot(p.w) > S(0)) return false;  // -v separates
    // a repeated support point or no progress: the origin is within rounding of the simplex
    const GjkStep step = gjk_step(s, n, lambda, v, vv, p);
    if (step == GjkStep::Progress) continue;
    inside = step == GjkStep::Inside;
    break;
  }
  if (inside) return true;
  const S eps = std::numeric_limits<S>::epsilon() * S(1024) * scale;
  if (v.squaredNorm() > eps * eps) {
    if (iterations >= max_iterations) {  // nothing left of the bound for the distance solver
      limit = true;
      return false;
    }
    // Stalled farther from the origin than rounding explains (fuzzing: a float cylinder and cone
    // 0.11 apart, 2.5e-4 of the size, stalled there and were called touching): the distance
    // solver decides whether the shapes are apart; if not, the simplex is completed as below.
    const ConvexDistance<S> d = gjk_distance<S>(support_a, support_b, v, eps, max_iterations - iterations, eps);
    iterations += d.iterations;
    if (!d.intersecting && !d.limit_reached) {
      // Apart only if the plane normal to the witnesses' line separates them by more than
      // rounding: a distance solver that stalls on the same simplex reports its rounding as a
      // distance (fuzzing: a sphere centred on the axis of a cone 9,000 times longer than wide,
      // inside it by 5.5e-5 of the size; the triangle through the axis held the origin, its
      // closest point came out 2.8e-16 away along the axis, and the pair was called touching
      // with the depth of the sphere's radius along an arbitrary normal).
      const Vec3<S> gap = d.point_b - d.point_a;
      const S len = gap.norm();
      if (len > S(0)) {
        const Vec3<S> sep = gap / len;
        if (sep.dot(supp(sep).w) < -tiny) return false;
      }
    }
  }
  // Complete the simplex to a tetrahedron holding the origin (on its boundary).
  static const Vec3<S> axes[6] = {Vec3<S>::UnitX(), Vec3<S>::UnitY(), Vec3<S>::UnitZ(), -Vec3<S>::UnitX(), -Vec3<S>::UnitY(), -Vec3<S>::UnitZ()};
  if (n == 1) {
    for (int k = 0; k < 6 && n == 1; ++k) {
      const SimplexPoint<S> p = supp(axes[k]);
      if ((p.w - s[0].w).norm() > eps) s[n++] = p;
    }
  }
  if (n == 2) {
    const Vec3<S> e = (s[1].w - s[0].w).normalized();
    const Vec3<S> u = (std::abs(e.x()) < S(0.6) ? Vec3<S>::UnitX() : Vec3<S>::UnitY()).cross(e).normalized();
    const Vec3<S> u2 = e.cross(u);
    static const S cs[6][2] = {{S(1), S(0)}, {S(-0.5), S(0.8660254037844386)}, {S(-0.5), S(-0.8660254037844386)},
                               {S(-1), S(0)}, {S(0.5), S(-0.8660254037844386)}, {S(0.5), S(0.8660254037844386)}};
    for (int k = 0; k < 6 && n == 2; ++k) {
      const SimplexPoint<S> p = supp(Vec3<S>(cs[k][0] * u + cs[k][1] * u2));
      const Vec3<S> r = p.w - s[0].w;
      if ((r - r.dot(e) * e).norm() > eps) s[n++] = p;
    }
  }
  if (n == 3) {
    const Vec3<S> m = (s[1].w - s[0].w).cross(s[2].w - s[0].w);
    if (m.norm() > S(0)) {
      const Vec3<S> mu = m.normalized();
      SimplexPoint<S> p = supp(mu);
      if (mu.dot(p.w - s[0].w) <= eps) {
        p = supp(Vec3<S>(-mu));
        if (-mu.dot(p.w - s[0].w) > eps) s[n++] = p;
      } else {
        s[n++] = p;
      }
    }
  }
  if (n < 4) {
    failed = true;  // D is flat (or worse) here: no polytope to expand
    return false;
  }
  return true;
}

}  // namespace detail

namespace detail {
/// EPA's first polytope: the faces of the tetrahedron of vertices 0..3 (oriented so that 0, 1, 2
/// turn counter-clockwise seen from 3, outward normals), and across edge e of face f (from
/// v[e] to v[e + 1]) the neighbouring face and that edge's index in it: a table, since the faces
/// are always these (matching the reversed edges at run time took about 700 instructions a query).
inline constexpr int kEpaTetraFaces[4][3] = {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {0, 3, 2}};
inline constexpr int kEpaTetraAdjacency[4][3][2] = {
    {{3, 2}, {2, 0}, {1, 0}}, {{0, 2}, {2, 2}, {3, 0}}, {{0, 1}, {3, 1}, {1, 1}}, {{1, 2}, {2, 1}, {0, 0}}};

/// Whether kEpaTetraAdjacency is kEpaTetraFaces' (each edge meets its reversed edge across it).
constexpr bool epa_tetra_adjacency_matches() {
  for (int f = 0; f < 4; ++f)
    for (int e = 0; e < 3; ++e) {
      const int g = kEpaTetraAdjacency[f][e][0], h = kEpaTetraAdjacency[f][e][1];
      if (kEpaTetraFaces[f][e] != kEpaTetraFaces[g][(h + 1) % 3] || kEpaTetraFaces[f][(e + 1) % 3] != kEpaTetraFaces[g][h]) return false;
    }
  return true;
}
static_assert(epa_tetra_adjacency_matches(), "EPA's tetrahedron adjacency table");

/// No local certificate (epa_penetration_local's default).
struct NoLocalCertificate {};

/// Whether every face of P nearer than cert.lower lies in cert's cap in the sense of
/// convex/local_certificate.hpp: angle(m_F, normal) + acos(d_F / lower) <= cap (then no unit
/// direction overlaps less than cert.lower): -1; else the nearest face that does not (EPA expands
/// it next). fi is P's nearest face, at distance dmin.
template <class S>
int epa_face_outside_cap(const EpaPolytope<S>& P, int fi, S dmin, const LocalCertificate<S>& cert) {
  const S rho = cert.lower;
  if (dmin < rho * cert.cos_cap) return fi;  // the nearest face alone fails
  const S margin = S(64) * std::numeric_limits<S>::epsilon();
  const S rho_key = rho * std::abs(rho);  // keys are signed squares of the distances
  int worst = -1;
  S worst_key = std::numeric_limits<S>::infinity();
  for (int i = 0; i < P.nf; ++i) {
    const S k = P.key[i];
    if (!(k < rho_key) || k >= worst_key) continue;  // removed faces are +infinity
    const S d = EpaPolytope<S>::key_distance(k);
    const S ca = d / rho, cb = P.face[i].n.dot(cert.normal) / std::sqrt(P.face[i].nn);
    // cos(alpha + beta) >= cos(cap), alpha = acos(ca), beta = acos(cb), both below pi / 2
    const S sa = std::sqrt(std::max(S(1) - ca * ca, S(0))), sb = std::sqrt(std::max(S(1) - cb * cb, S(0)));
    if (ca > S(0) && cb > S(0) && ca * cb - sa * sb >= cert.cos_cap + margin) continue;
    worst = i;
    worst_key = k;
  }
  return worst;
}
}  // namespace detail

template <class S, class SupportA, class SupportB>
EpaPenetration<S> epa_penetration_from_simplex(const SupportA& support_a, const SupportB& support_b, const detail::SimplexPoint<S>* start,
                                               int iterations, const EpaSettings<S>& st);
template <class S, class SupportA, class SupportB, class Local>
EpaPenetration<S> epa_penetration_local(const SupportA& support_a, const SupportB& support_b, const detail::SimplexPoint<S>* start,
                                        int iterations, const EpaSettings<S>& st, const Local& local);

/// Penetration of A and B from world support functions support_a(d), support_b(d) (points
/// maximising the dot product with d) and a first direction (e.g. interior_a - interior_b).
template <class S, class SupportA, class SupportB>
EpaPenetration<S> epa_penetration(const SupportA& support_a, const SupportB& support_b, const Vec3<S>& first, const EpaSettings<S>& st) {
  detail::SimplexPoint<S> simplex[4];
  int its = 0;
  bool limit = false, failed = false;
  if (!detail::gjk_enclose(support_a, support_b, first, st.scale, st.max_iterations, simplex, its, limit, failed)) {
    EpaPenetration<S> out;
    out.iterations = its;
    out.limit_reached = limit;
    out.failed = failed;
    return out;
  }
  return epa_penetration_from_simplex(support_a, support_b, simplex, its, st);
}

/// EPA from a tetrahedron of support points of A - B (w = a - b, each point with its a and b
/// parts, of the same support functions) that holds the origin, as gjk_enclose leaves it, so a
/// caller that ran GJK already does not run it again; `iterations` is the support calls spent on
/// it (counted against st.max_iterations). A flat tetrahedron gives `failed`.
template <class S, class SupportA, class SupportB>
EpaPenetration<S> epa_penetration_from_simplex(const SupportA& support_a, const SupportB& support_b, const detail::SimplexPoint<S>* start,
                                               int iterations, const EpaSettings<S>& st) {
  return epa_penetration_local(support_a, support_b, start, iterations, st, detail::NoLocalCertificate{});
}

/// EPA from a tetrahedron as epa_penetration_from_simplex, with a local certificate:
/// local(n) (a detail::LocalCertificate<S> from a direction n, convex/local_certificate.hpp) is
/// called once EPA's gap is below 0.05 of the scale (again below 1e-4 if it failed), from EPA's
/// best normal; when it succeeds with upper - lower within the tolerance (upper: f at its normal,
/// from the supports), EPA stops as soon as every face nearer than its lower bound lies in its cap
/// (detail::epa_faces_in_cap). Otherwise EPA runs as without it.
template <class S, class SupportA, class SupportB, class Local>
EpaPenetration<S> epa_penetration_local(const SupportA& support_a, const SupportB& support_b, const detail::SimplexPoint<S>* start,
                                        int iterations, const EpaSettings<S>& st, const Local& local) {
  using detail::SimplexPoint;
  constexpr bool has_local = !std::is_same_v<Local, detail::NoLocalCertificate>;
  EpaPenetration<S> out;
  const int max_it = st.max_iterations;
  int its = iterations;
  SimplexPoint<S> simplex[4] = {start[0], start[1], start[2], start[3]};
  bool limit = false, failed = false;
  out.intersecting = true;
  const auto supp = [&](const Vec3<S>& d) {
    ++its;
    return detail::minkowski_support<S>(support_a, support_b, d);
  };

  detail::EpaPolytope<S>& P = detail::epa_scratch<S>();
  P.nv = P.nf = P.nfree = P.nh = P.ndead = 0;  // reset (only the counters need it)
  // the tetrahedron, faces outward
  {
    const Vec3<S> e1 = simplex[1].w - simplex[0].w, e2 = simplex[2].w - simplex[0].w, e3 = simplex[3].w - simplex[0].w;
    if (e1.cross(e2).dot(e3) < S(0)) std::swap(simplex[1], simplex[2]);
    for (int i = 0; i < 4; ++i) P.vtx[i] = simplex[i];
    P.nv = 4;
    for (int f = 0; f < 4; ++f)
      if (P.make_face(detail::kEpaTetraFaces[f][0], detail::kEpaTetraFaces[f][1], detail::kEpaTetraFaces[f][2]) != f) {
        out.failed = true;
        out.iterations = its;
        return out;
      }
    for (int f = 0; f < 4; ++f)  // the fixed adjacency of those faces
      for (int e = 0; e < 3; ++e) {
        P.face[f].adj[e] = detail::kEpaTetraAdjacency[f][e][0];
        P.face[f].adj_edge[e] = detail::kEpaTetraAdjacency[f][e][1];
      }
  }

  S upper = std::numeric_limits<S>::infinity(), lower = -std::numeric_limits<S>::infinity();
  Vec3<S> best_n = Vec3<S>::UnitZ();
  Vec3<S> best_a = Vec3<S>::Zero(), best_b = Vec3<S>::Zero();
  const S no_progress = std::numeric_limits<S>::epsilon() * S(8) * st.scale;
  bool best_on_face = false;  // the best normal is a face's whose support lies on it
  SimplexPoint<S> best_face[3];
  Vec3<S> best_foot = Vec3<S>::Zero();
  detail::LocalCertificate<S> cert;
  int cert_tries = 0;
  // the local certificate (has_local): tried at gaps below 0.05 and 1e-4 of the scale
  const auto try_local = [&](S stop_gap) {
    if constexpr (has_local) {
      const S trigger = cert_tries == 0 ? S(0.05) * st.scale : S(1e-4) * st.scale;
      if (cert_tries >= 2 || upper - lower > trigger || its >= max_it) return;
      ++cert_tries;
      cert = local(best_n);
      if (!cert.ok) return;
      const SimplexPoint<S> p = supp(cert.normal);
      const S up = cert.normal.dot(p.w);
      if (up < upper) {
        upper = up;
        best_n = cert.normal;
        best_a = p.a;
        best_b = p.b;
        best_on_face = false;
      }
      // a local minimum above an overlap already seen (cert.lower > upper) is not the global one
      if (!(upper - cert.lower <= stop_gap && cert.lower <= upper)) cert.ok = false;
    } else {
      (void)stop_gap;
    }
  };

  // a direction known to overlap little: its overlap is an upper bound to start from (when the
  // bound leaves a support call for it)
  if (st.seeded && its < max_it) {
    const SimplexPoint<S> p = supp(st.seed);
    upper = st.seed.dot(p.w);
    best_n = st.seed;
    best_a = p.a;
    best_b = p.b;
  }

  // EPA until upper - lower <= stop_gap; returns false when it ended without reaching it (bound,
  // capacity or a degenerate step: `limit` / `failed` say which; no progress possible counts as reached).
  const auto expand = [&](S stop_gap) -> bool {
    while (true) {
      S kmin;
      const int fi = detail::epa_closest_face(P.key, P.nf, kmin);
      if (fi < 0) {
        failed = true;
        return false;
      }
      const S dmin = detail::EpaPolytope<S>::key_distance(kmin);
      lower = std::max(lower, dmin);
      if (upper - lower <= stop_gap) return true;
      int fx = fi;  // the face to expand
      if constexpr (has_local) {
        // an overlap below the certificate's bound, seen since: its minimum is local, not global
        if (cert.ok && !(cert.lower <= upper)) cert.ok = false;
        if (!cert.ok) try_local(stop_gap);
        if (cert.ok) {
          fx = detail::epa_face_outside_cap(P, fi, dmin, cert);
          if (fx < 0) {
            lower = std::max(lower, cert.lower);
            out.local_certificate = true;
            return true;
          }
        }
      }
      if (its >= max_it || P.nv >= detail::kEpaMaxVertices) {
        limit = true;
        return false;
      }
      const Vec3<S> n = P.unit_normal(fx);
      const S dx = fx == fi ? dmin : detail::EpaPolytope<S>::key_distance(P.key[fx]);
      const SimplexPoint<S> p = supp(n);
      const S up = n.dot(p.w);
      if (up < upper) {
        upper = up;
        best_n = n;
        best_a = p.a;  // the supports are the deepest points,
        best_b = p.b;
        best_on_face = up - dx <= st.tolerance;
        if (best_on_face) {  // unless on a face of D: the face's point of the contact region (at the end)
          const detail::EpaFace<S>& f = P.face[fx];
          best_foot = dx * n;
          for (int i = 0; i < 3; ++i) best_face[i] = P.vtx[f.v[i]];
        }
      }
      if (upper - lower <= stop_gap) return true;
      if (!(up - dx > no_progress)) {  // the support is on the face within rounding
        if (fx == fi) return true;
        cert.ok = false;  // a face of D inside the certified bound: rounding; EPA alone from here
        continue;
      }
      // expand the polytope by p: remove the faces p sees, cone the horizon to p
      const int vi = P.nv++;
      P.vtx[vi] = p;
      P.nh = 0;
      P.ndead = 0;
      P.face[fx].alive = false;
      P.key[fx] = std::numeric_limits<S>::infinity();
      P.dead[P.ndead++] = fx;
      const detail::EpaFace<S> f0 = P.face[fx];
      for (int e = 0; e < 3; ++e) P.silhouette(f0.adj[e], f0.adj_edge[e], p.w, 0);
      int created[detail::kEpaMaxFaces];
      bool bad = P.nh < 3;
      for (int k = 0; k < P.nh && !bad; ++k) {
        const int hf = P.horizon_face[k], e = P.horizon_edge[k];
        const int id = P.make_face(P.face[hf].v[(e + 1) % 3], P.face[hf].v[e], vi);
        if (id < 0) {
          bad = true;
          break;
        }
        created[k] = id;
        detail::epa_link(P.face, id, 0, hf, e);
      }
      // edge 1 of new face k (v[1] -> p) meets edge 2 (p -> v[0]) of the new face whose v[0] is its v[1]
      for (int k = 0; k < P.nh && !bad; ++k) {
        // the depth-first walk lists the horizon as a ring, so the match is normally the next
        // face; the scan covers any other order
        const int want = P.face[created[k]].v[1];
        int match = k + 1 < P.nh ? k + 1 : 0;
        if (P.face[created[match]].v[0] != want) {
          match = -1;
          for (int j = 0; j < P.nh; ++j)
            if (P.face[created[j]].v[0] == want) {
              match = j;
              break;
            }
        }
        if (match < 0) {
          bad = true;
          break;
        }
        detail::epa_link(P.face, created[k], 1, created[match], 2);
      }
      if (bad) {
        failed = true;
        return false;
      }
      for (int k = 0; k < P.ndead; ++k) P.free_list[P.nfree++] = P.dead[k];
    }
  };

  bool done = expand(st.refine ? std::max(st.coarse_tolerance, st.tolerance) : st.tolerance);
  if (done && st.refine && upper - lower > st.tolerance) {
    // Newton refinement of the direction from the best one EPA found (see the file comment).
    Vec3<S> n = best_n;
    SimplexPoint<S> p0 = supp(n);
    S f0 = n.dot(p0.w);
    const S h = S(1e-5);                   // finite-difference angle
    const S jump = S(16) * st.scale * h;   // a support change over 2h above this is a jump, not curvature
    bool ok = false;
    // Central difference of the support along tangent t: false at a jump (the support set is then
    // an edge of D from wm to wp: the change does not shrink with the step, as curvature's would).
    Vec3<S> jump_p, jump_m;
    bool suspicious = false;
    const auto probe = [&](const Vec3<S>& t, Vec3<S>& d) -> bool {
      const Vec3<S> wp = supp(Vec3<S>((n + h * t).normalized())).w;
      const Vec3<S> wm = supp(Vec3<S>((n - h * t).normalized())).w;
      d = wp - wm;
      if (d.norm() > jump) {
        const Vec3<S> small = supp(Vec3<S>((n + h / S(16) * t).normalized())).w - supp(Vec3<S>((n - h / S(16) * t).normalized())).w;
        if (small.norm() > S(0.5) * d.norm()) {
          jump_p = wp;
          jump_m = wm;
          return false;
        }
      }
      d /= S(2) * h;
      // a derivative this large is a jump closer than h / 16 or a near-singular support: no
      // stopping test is trusted at this step
      if (d.norm() > S(1e3) * st.scale) suspicious = true;
      return true;
    };
    for (int step = 0; step < detail::kNewtonSteps && its + 8 < max_it; ++step) {
      suspicious = false;
      const Vec3<S> t1 = detail::any_orthogonal(n);
      Vec3<S> t2 = n.cross(t1);
      Vec3<S> d1, d2;
      const bool s1 = probe(t1, d1);
      bool s2 = true;
      // the constraint directions found: a jump along t1 is an edge e of D; the free direction is
      // then n x e (probed again: a second, non-parallel jump makes a face)
      if (!s1) {
        t2 = n.cross(d1);
        if (!(t2.norm() > S(0))) break;
        t2.normalize();
      }
      s2 = probe(t2, d2);
      // two edges: a face of D, which EPA finds exactly; leave it to EPA
      if (!s1 && !s2) break;
      Vec3<S> new_n;
      S decrement = S(0);  // Newton's predicted decrease of f
      if (!s1 || !s2) {  // an edge of D along e: the minimiser has n . e = 0; Newton along the rest
        const Vec3<S> e = (s1 ? d2 : d1).normalized();
        // the kink n . e = 0 is a minimum across the edge only if the origin projects between its
        // ends (the slopes on either side have opposite signs); else leave it to EPA
        if (e.dot(jump_p) * e.dot(jump_m) > S(0)) break;
        Vec3<S> t = n.cross(e);
        if (!(t.norm() > S(0))) break;
        t.normalize();
        Vec3<S> dt;
        bool smooth = true;
        if (!s1) {
          dt = d2;  // t2 = n x e already
          t = t2;
        } else {
          smooth = probe(t, dt);
        }
        Vec3<S> m = n - n.dot(e) * e;
        if (smooth) {
          const S g = t.dot(p0.w), H = t.dot(dt) - f0;
          if (!(H > S(0))) break;  // not locally convex: leave it to EPA
          m += (-g / H) * t;
          decrement = g * g / (S(2) * H);
        } else {
          break;
        }
        if (!(m.norm() > S(0))) break;
        new_n = m.normalized();
      } else {
        const S g1 = t1.dot(p0.w), g2 = t2.dot(p0.w);
        const S H11 = t1.dot(d1) - f0, H22 = t2.dot(d2) - f0, H12 = (t1.dot(d2) + t2.dot(d1)) / S(2);
        const S det = H11 * H22 - H12 * H12;
        if (!(H11 > S(0) && det > S(0))) break;  // not locally convex: leave it to EPA
        const S x1 = -(H22 * g1 - H12 * g2) / det, x2 = -(-H12 * g1 + H11 * g2) / det;
        decrement = -(g1 * x1 + g2 * x2) / S(2);
        if (decrement <= st.tolerance && !suspicious) {  // stationary within the tolerance, positive definite
          ok = true;
          break;
        }
        new_n = (n + x1 * t1 + x2 * t2).normalized();
      }
      // keep the step only if f does not increase (halving it up to three times)
      bool accepted = false;
      Vec3<S> trial = new_n;
      S moved = S(0);
      for (int half = 0; half < 4; ++half) {
        const SimplexPoint<S> pt = supp(trial);
        const S ft = trial.dot(pt.w);
        if (ft <= f0) {
          moved = (trial - n).norm();
          n = trial;
          p0 = pt;
          f0 = ft;
          accepted = true;
          break;
        }
        trial = (n + trial).normalized();
      }
      if (!accepted || moved <= S(16) * std::numeric_limits<S>::epsilon()) {
        // no step decreases f: on an edge or face (s1 or s2 jumped) that is its minimum within rounding
        ok = !(s1 && s2) && decrement <= st.tolerance && !suspicious;
        break;
      }
      if (!(s1 && s2) && decrement <= st.tolerance && moved <= h && !suspicious) {
        ok = true;
        break;
      }
    }
    if (f0 < upper) {
      upper = f0;
      best_n = n;
      best_a = p0.a;
      best_b = p0.b;
      best_on_face = false;
    }
    if (ok) {
      out.refined = true;
    } else {
      expand(st.tolerance);  // the refinement did not verify: EPA to the fine tolerance
    }
  }
  if (best_on_face) {
    const auto cp = closest_point_on_triangle(best_foot, Triangle<S>(best_face[0].w, best_face[1].w, best_face[2].w));
    best_a = cp.barycentric[0] * best_face[0].a + cp.barycentric[1] * best_face[1].a + cp.barycentric[2] * best_face[2].a;
    best_b = cp.barycentric[0] * best_face[0].b + cp.barycentric[1] * best_face[1].b + cp.barycentric[2] * best_face[2].b;
  }
  out.failed = failed || !(upper < std::numeric_limits<S>::infinity());
  out.limit_reached = limit;
  out.iterations = its;
  out.depth = std::max(upper, S(0));
  out.lower = std::max(lower, S(0));
  out.normal = best_n;
  out.point_a = best_a;
  out.point_b = best_b;
  return out;
}

}  // namespace impact
