// SPDX-License-Identifier: MIT
/// \file
/// ConvexHull<S>: the convex hull of a point set (or of a mesh's vertices) as a convex shape of the
/// convex layer: its vertices, outward triangles, and its faces merged into convex polygons (the
/// flat faces contact manifolds clip against). Built by quickhull (Barber, Dobkin & Huhdanpaa,
/// "The Quickhull algorithm for convex hulls", ACM TOMS 1996): a first tetrahedron of extreme
/// points, then repeatedly the farthest point outside a face is added, the faces it sees removed
/// and the horizon coned to it; points inside are dropped with their face's conflict list.
///
/// Numerical contract: the hull is EXACTLY convex, and holds the input points within a tolerance.
/// Which faces a new point sees is decided by the exact orient3d predicate (narrow/predicates.hpp)
/// on the input coordinates, so the triangles form a closed surface on which every hull vertex is
/// on or below every triangle's plane, exactly (near-duplicate and near-collinear points included:
/// a sliver triangle is a true face, never a fold). A point is dropped as inside only when it is
/// certainly (by a rounding bound per face, exactly for slivers) within eps of the planes of the
/// hull at that step (eps = options.relative_tolerance times the extent, the default 1000 machine
/// epsilons) and, if it is above a plane at all, within eps of that face's triangle (near a sharp
/// edge a point can lie in the planes around it yet beyond the edge's end); the hull then only
/// grows, and on about 78,000 sets of random, near-duplicate
/// (relative offsets 1e-12 to 1e-3) and near-collinear points (the tests and two drivers) every
/// input point was within 2 eps of every triangle's plane (worst 1.8 eps; not a proven bound).
/// The vertices are input points.
/// Cost of the exactness: one filtered orient3d per visibility test and per eye, the exact stage
/// only in near-degenerate cases (measured in docs/convex.md, "Hull builds"). Faces whose normals
/// differ by less than options.merge_angle are merged into one polygon; each polygon's offset is
/// the hull's support value along its normal (a climb over the vertex graph), so every face plane
/// is a supporting plane of the hull up to the rounding of a dot product, even where a sliver's
/// normal is tilted (the pair tests take the offsets as the hull's extent along the normals).
/// `tests/fuzz/fuzz_hull.cpp` checks this contract on float and double point sets.
///
/// Degenerate input throws impact::InvalidInput (never a silent flat hull): fewer than 4 points,
/// NaN or infinite coordinates, coordinates outside CoordinateRange, all points coincident,
/// collinear or coplanar within eps or exactly (the message says which). Expected cost O(n log n), worst
/// O(n^2) (n = point count).
#pragma once

#include "impact/convex/shapes.hpp"
#include "impact/core/types.hpp"
#include "impact/core/validate.hpp"
#include "impact/narrow/closest_point.hpp"
#include "impact/narrow/predicates.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <string>
#include <type_traits>
#include <vector>

namespace impact {

struct ConvexHullOptions {
  /// Points within relative_tolerance * extent of a face count as on it (extent: the largest
  /// coordinate magnitude of the centred point set). <= 0 means the default, 1e3 machine epsilons.
  double relative_tolerance = 0;
  /// Adjacent triangles whose unit normals differ by less than this (radians) form one polygon.
  double merge_angle = 1e-6;
};

/// A polygonal face of a hull: its vertex indices in counter-clockwise order seen from outside,
/// its outward unit normal and offset (n . x = offset on the face).
template <class S>
struct HullFace {
  std::vector<int> vertices;
  Vec3<S> normal = Vec3<S>::UnitZ();
  S offset = S(0);
};

/// An edge between two faces of a hull (edges inside a merged polygon are left out): its vertices,
/// v0 -> v1 counter-clockwise in face f0 (so v1 -> v0 in f1). The separating-axis test
/// (convex/polytope_sat.hpp) reads the arc from f0's normal to f1's on the Gauss map.
struct HullEdge {
  int v0 = 0, v1 = 0;
  int f0 = 0, f1 = 0;
};

/// A convex hull, in its own frame (a RigidTransform places it). Build with convex_hull().
template <class S>
struct ConvexHull {
  Vertices<S> vertices;           ///< the hull's vertices (input points), one per row
  Faces triangles;                ///< outward (counter-clockwise seen from outside) triangles
  std::vector<HullFace<S>> faces; ///< the triangles merged into convex polygons
  std::vector<HullEdge> edges;    ///< each edge between two different faces once
  /// The faces' planes by component, for loops over every face: normal x of each face, then
  /// normal y, normal z, offset (4 blocks of faces.size() values).
  std::vector<S> face_planes;
  Vec3<S> centroid = Vec3<S>::Zero();  ///< mean of the vertices (an interior point)
  S size = S(0);                  ///< largest distance from centroid to a vertex
  /// The hull's edges as vertex adjacency in compressed rows, for support()'s hill climb: the
  /// neighbours of vertex v are neighbors[neighbor_start[v] .. neighbor_start[v + 1]). Empty for
  /// hulls of fewer than kHullClimbMinVertices vertices (support() scans those).
  std::vector<int> neighbor_start, neighbors;
  /// Where the climb starts, per octant of the direction (bit 0: x > 0, bit 1: y > 0, bit 2:
  /// z > 0): the vertex farthest along that octant's diagonal (+-1, +-1, +-1).
  std::array<int, 8> octant_vertex{};
};

/// Hulls of at least this many vertices answer support() by hill climbing on their edges; smaller
/// ones by scanning every vertex (cheaper below it; measured on the convex bench's pairs).
inline constexpr int kHullClimbMinVertices = 12;

/// Calls fn(u) for each neighbour u of vertex v of h on its edge graph, or for every vertex of h
/// (v too) when h has none (hulls of fewer than kHullClimbMinVertices vertices): the vertices a
/// step from v can reach, for the local searches that start at a support vertex.
template <class S, class Fn>
inline void for_each_neighbor(const ConvexHull<S>& h, int v, Fn&& fn) {
  if (h.neighbors.empty()) {
    for (int u = 0, n = static_cast<int>(h.vertices.rows()); u < n; ++u) fn(u);
    return;
  }
  for (int k = h.neighbor_start[static_cast<std::size_t>(v)], end = h.neighbor_start[static_cast<std::size_t>(v) + 1]; k < end; ++k)
    fn(h.neighbors[static_cast<std::size_t>(k)]);
}

/// The index of the vertex of h farthest along d. Hulls with an edge graph (convex_hull() builds
/// one from kHullClimbMinVertices vertices) climb it: from the octant's start vertex to the
/// neighbour farthest along d, until no neighbour is farther (on a convex polytope a vertex no
/// neighbour beats is a farthest vertex; quickhull's triangles are convex up to its tolerance, so
/// the value is the largest within that tolerance times |d|). Smaller hulls scan every vertex.
template <class S>
inline int support_vertex(const ConvexHull<S>& h, const Vec3<S>& d) {
  const S* p = h.vertices.data();
  const auto along = [&](int v) { return p[3 * v] * d.x() + p[3 * v + 1] * d.y() + p[3 * v + 2] * d.z(); };
  if (h.neighbors.empty()) {
    int best = 0;
    S best_dot = along(0);
    const int n = static_cast<int>(h.vertices.rows());
    for (int i = 1; i < n; ++i) {
      const S x = along(i);
      if (x > best_dot) {
        best_dot = x;
        best = i;
      }
    }
    return best;
  }
  const int octant = int(d.x() > S(0)) | (int(d.y() > S(0)) << 1) | (int(d.z() > S(0)) << 2);
  int v = h.octant_vertex[static_cast<std::size_t>(octant)];
  S best_dot = along(v);
  const int* start = h.neighbor_start.data();
  const int* nb = h.neighbors.data();
  for (;;) {
    int next = v;
    for (int k = start[v], end = start[v + 1]; k < end; ++k) {
      const S x = along(nb[k]);
      if (x > best_dot) {
        best_dot = x;
        next = nb[k];
      }
    }
    if (next == v) break;  // the value strictly grows each step: no vertex is visited twice
    v = next;
  }
  return v;
}

/// The vertex of h farthest along d (support_vertex).
template <class S>
inline Vec3<S> support(const ConvexHull<S>& h, const Vec3<S>& d) {
  return h.vertices.row(support_vertex(h, d)).transpose();
}
template <class S>
inline Vec3<S> interior_point(const ConvexHull<S>& h) {
  return h.centroid;
}
template <class S>
inline S shape_size(const ConvexHull<S>& h) {
  return h.size;
}
/// A hull is valid when built by convex_hull(); this checks only that it was built.
template <class S>
void validate_shape(const ConvexHull<S>& h, const char* where) {
  if (h.vertices.rows() < 4 || h.triangles.rows() < 4) throw InvalidInput(std::string(where) + ": convex hull is empty (build it with convex_hull())");
}

namespace detail {

/// support()'s edge graph and start vertices for h (its vertices and triangles set); nothing for
/// hulls under kHullClimbMinVertices vertices. Each undirected edge u-v is the directed edge u->v
/// of one triangle and v->u of the other, so each triangle's directed edges list every neighbour
/// once.
template <class S>
void build_hull_climb(ConvexHull<S>& h) {
  h.neighbor_start.clear();
  h.neighbors.clear();
  const int nv = static_cast<int>(h.vertices.rows());
  if (nv < kHullClimbMinVertices) return;
  std::vector<int> count(static_cast<std::size_t>(nv) + 1, 0);
  for (Eigen::Index t = 0; t < h.triangles.rows(); ++t)
    for (int k = 0; k < 3; ++k) ++count[static_cast<std::size_t>(h.triangles(t, k)) + 1];
  for (int v = 0; v < nv; ++v) count[static_cast<std::size_t>(v) + 1] += count[static_cast<std::size_t>(v)];
  h.neighbor_start = count;
  h.neighbors.resize(static_cast<std::size_t>(count.back()));
  for (Eigen::Index t = 0; t < h.triangles.rows(); ++t)
    for (int k = 0; k < 3; ++k)
      h.neighbors[static_cast<std::size_t>(count[static_cast<std::size_t>(h.triangles(t, k))]++)] = h.triangles(t, (k + 1) % 3);
  for (int o = 0; o < 8; ++o) {
    const Vec3<S> d((o & 1) ? S(1) : S(-1), (o & 2) ? S(1) : S(-1), (o & 4) ? S(1) : S(-1));
    Eigen::Index best = 0;
    (h.vertices * d).maxCoeff(&best);
    h.octant_vertex[static_cast<std::size_t>(o)] = static_cast<int>(best);
  }
}

template <class S>
class QuickHull {
 public:
  /// p: the points (centred) for the distances; x: the same points uncentred, in double, row by
  /// row (n x 3), for the exact visibility test; eps: the tolerance; extent: the points' extent.
  QuickHull(const Vertices<S>& p, const double* x, S eps, S extent) : p_(p), x_(x), eps_(eps), extent_(extent) {}

  /// The hull's triangles (point indices, outward) and, for each, the triangle across its edge
  /// k -> k + 1 (an index into the same list).
  struct Triangles {
    std::vector<std::array<int, 3>> vertices, across;
  };
  /// Runs quickhull from the tetrahedron (i0, i1, i2, i3).
  Triangles run(int i0, int i1, int i2, int i3) {
    // Orient the tetrahedron so that its faces point outwards.
    if (orient3d_double(xp(i0), xp(i1), xp(i2), xp(i3)) > 0) std::swap(i1, i2);
    add_face(i0, i1, i2);
    add_face(i0, i3, i1);
    add_face(i1, i3, i2);
    add_face(i2, i3, i0);
    for (int f = 0; f < 4; ++f)  // each directed edge of one face runs backwards in its neighbour
      for (int k = 0; k < 3; ++k)
        for (int g = 0; g < 4; ++g)
          for (int j = 0; j < 3; ++j)
            if (faces_[g].v[j] == faces_[f].v[(k + 1) % 3] && faces_[g].v[(j + 1) % 3] == faces_[f].v[k]) faces_[f].nb[k] = g;
    // Initial conflict lists.
    const int n = static_cast<int>(p_.rows());
    start_face_.assign(static_cast<std::size_t>(n), -1);
    for (int i = 0; i < n; ++i) {
      if (i == i0 || i == i1 || i == i2 || i == i3) continue;
      assign(i, 0, 4);
    }
    std::vector<int> visible, stack, orphans;
    std::vector<std::array<int, 3>> horizon;  // edge u -> w of a visible face, the hidden face across it
    int round = 0;  // faces met by this step's flood fill carry its number (no per-step clearing)
    for (std::size_t f = 0; f < faces_.size(); ++f) {
      if (!faces_[f].alive || faces_[f].outside.empty()) continue;
      // The farthest point of this face's conflict list: assign() puts a point only on a face it
      // is above (by the rounding bound or exactly); the exact test here, one per step, keeps the
      // flood fill's start visible even if that bound were wrong.
      int eye = farthest(faces_[f]);
      while (!above(faces_[f], eye)) {
        auto& out = faces_[f].outside;
        out.erase(std::find(out.begin(), out.end(), eye));
        if (out.empty()) break;
        eye = farthest(faces_[f]);
      }
      if (faces_[f].outside.empty()) continue;
      // Visible faces: flood fill from f across edges.
      visible.clear();
      stack.assign(1, static_cast<int>(f));
      ++round;
      faces_[f].seen = round;
      horizon.clear();
      while (!stack.empty()) {
        const int g = stack.back();
        stack.pop_back();
        visible.push_back(g);
        for (int k = 0; k < 3; ++k) {
          const int u = faces_[g].v[k], w = faces_[g].v[(k + 1) % 3];
          const int h = faces_[g].nb[k];
          if (h < 0 || !faces_[h].alive) continue;  // cannot happen on a closed hull
          if (faces_[h].seen == round) continue;
          if (above(faces_[h], eye)) {
            faces_[h].seen = round;
            stack.push_back(h);
          } else {
            horizon.push_back({u, w, h});
          }
        }
      }
      orphans.clear();
      for (int g : visible) {
        Face& fg = faces_[g];
        fg.alive = false;
        for (int q : fg.outside)
          if (q != eye) orphans.push_back(q);
        fg.outside.clear();
        // A short list's storage goes to a later face (on a sphere nearly every list is short
        // and allocating them was a third of the build); a long one is freed.
        if (fg.outside.capacity() <= kSpareCapacity) spare_.push_back(std::move(fg.outside));
        std::vector<int>().swap(fg.outside);
      }
      const int first_new = static_cast<int>(faces_.size());
      // The cone from the horizon to the eye: new face (u, w, eye) borders the hidden face across
      // u -> w, and across w -> eye the new face that starts at w (the horizon is a loop, each of
      // its vertices starts one edge).
      for (const auto& he : horizon) {
        const int id = add_face(he[0], he[1], eye);
        Face& hidden = faces_[static_cast<std::size_t>(he[2])];
        for (int j = 0; j < 3; ++j)
          if (hidden.v[j] == he[1] && hidden.v[(j + 1) % 3] == he[0]) hidden.nb[j] = id;
        faces_[static_cast<std::size_t>(id)].nb[0] = he[2];
        start_face_[static_cast<std::size_t>(he[0])] = id;
      }
      for (int id = first_new; id < static_cast<int>(faces_.size()); ++id) {
        // The horizon is a simple loop (exact visibility), so the face starting at this face's
        // second vertex was made in this step; a stale entry from an earlier step is never used.
        const int next = start_face_[static_cast<std::size_t>(faces_[static_cast<std::size_t>(id)].v[1])];
        IMPACT_ASSERT(next >= first_new);
        if (next < first_new) continue;
        faces_[static_cast<std::size_t>(id)].nb[1] = next;
        faces_[static_cast<std::size_t>(next)].nb[2] = id;
      }
      for (int q : orphans) assign(q, first_new, static_cast<int>(faces_.size()));
    }
    Triangles out;
    std::vector<int> index(faces_.size(), -1);
    for (std::size_t f = 0; f < faces_.size(); ++f)
      if (faces_[f].alive) {
        index[f] = static_cast<int>(out.vertices.size());
        out.vertices.push_back({faces_[f].v[0], faces_[f].v[1], faces_[f].v[2]});
      }
    out.across.reserve(out.vertices.size());
    for (const Face& f : faces_)
      if (f.alive) {
        std::array<int, 3> a{-1, -1, -1};
        for (int k = 0; k < 3; ++k)
          if (f.nb[k] >= 0) a[static_cast<std::size_t>(k)] = index[static_cast<std::size_t>(f.nb[k])];
        out.across.push_back(a);
      }
    return out;
  }

 private:
  struct Face {
    int v[3];
    Vec3<S> n;
    S d;
    S err;         ///< the rounding bound of distance()
    S drop_below;  ///< eps - err: a point whose distance() is not above this is within eps of the plane
    bool alive = true;
    int seen = 0;  ///< the last step whose flood fill met this face
    int nb[3] = {-1, -1, -1};  ///< the face across edge v[k] -> v[k + 1]
    std::vector<int> outside;
  };
  Vec3<S> pt(int i) const { return p_.row(i).transpose(); }
  const double* xp(int i) const { return x_ + 3 * static_cast<std::ptrdiff_t>(i); }
  /// Whether point q lies strictly above f's plane, decided exactly on the uncentred points: the
  /// faces a new point sees are exactly those, so every step keeps the hull exactly convex. The
  /// distance decides when it is farther from 0 than twice its rounding bound; orient3d (itself
  /// filtered, exact when it must be) decides the rest.
  bool above(const Face& f, int q) const {
    const S dist = distance(f, q);
    if (dist > 2 * f.err) return true;
    if (dist < -2 * f.err) return false;
    return orient3d_double(xp(f.v[0]), xp(f.v[1]), xp(f.v[2]), xp(q)) > 0;
  }
  S distance(const Face& f, int q) const { return f.n.dot(pt(q)) - f.d; }
  int add_face(int a, int b, int c) {
    Face f;
    if (!spare_.empty()) {
      f.outside = std::move(spare_.back());
      spare_.pop_back();
    }
    f.v[0] = a;
    f.v[1] = b;
    f.v[2] = c;
    // The normal from the uncentred points' differences (the difference of two nearby points is
    // exact, where centring rounds each point by up to an ulp of its coordinates: a relative 1e-4
    // of a 1e-12 edge), across the two shorter edges: a sliver's two long edges are nearly
    // parallel, their cross product rounding noise (a relative 1e-7 for a 1e-9 short edge).
    const Eigen::Vector3d xa(xp(a)), xb(xp(b)), xc(xp(c));
    const Eigen::Vector3d ab = xb - xa, bc = xc - xb, ca = xa - xc;
    const double lab = ab.squaredNorm(), lbc = bc.squaredNorm(), lca = ca.squaredNorm();
    // (b - a) x (c - a) = bc x ca = ca x ab: the cross product at the vertex opposite the longest edge
    const bool ab_longest = lab >= lbc && lab >= lca, bc_longest = !ab_longest && lbc >= lca;
    const Eigen::Vector3d n = ab_longest ? bc.cross(ca) : (bc_longest ? ca.cross(ab) : ab.cross(bc));
    const double len = n.norm();
    f.n = len > 0 ? Vec3<S>((n / len).template cast<S>()) : Vec3<S>::Zero();
    f.d = f.n.dot(pt(a));
    // A point is dropped only when it is certainly within eps of the plane: the threshold is eps
    // less the rounding bound of distance(), 16 machine epsilons of the extent times (cond + 1),
    // cond = |e1| |e2| / |e1 x e2| for the two edges used (1 / the sine of their angle): the
    // normal's direction error grows with it, the dot products' rounding and the centring are
    // the + 1.
    const double e1e2 = std::sqrt(ab_longest ? lbc * lca : (bc_longest ? lca * lab : lab * lbc));
    const double cond = len > 0 ? e1e2 / len : std::numeric_limits<double>::infinity();
    f.err = S(std::min(16 * double(std::numeric_limits<S>::epsilon()) * double(extent_) * (cond + 1), double(std::numeric_limits<S>::max()) / 4));
    f.drop_below = eps_ - f.err;
    faces_.push_back(std::move(f));
    return static_cast<int>(faces_.size()) - 1;
  }
  /// The point of f's (non-empty) conflict list farthest from its plane.
  int farthest(const Face& f) const {
    int eye = f.outside.front();
    S best = distance(f, eye);
    for (int q : f.outside) {
      const S dist = distance(f, q);
      if (dist > best) {
        best = dist;
        eye = q;
      }
    }
    return eye;
  }
  /// Puts point q in the conflict list of the face among [lo, hi) it is farthest outside of, if
  /// it may be more than eps outside one (distance() above drop_below). When that face's rounding
  /// bound cannot tell whether q is above it at all (a sliver: err above the distance), the
  /// exact test decides, and q goes to the face it is exactly above with the largest distance
  /// less rounding; it is dropped when there is none (it is then below or within eps of each).
  void assign(int q, int lo, int hi) {
    int best = -1;
    S best_d = -std::numeric_limits<S>::infinity();
    bool near = false;  // q within rounding of a plane or above it: keep_if_beyond may keep it
    for (int g = lo; g < hi; ++g) {
      if (!faces_[g].alive) continue;
      const S dist = distance(faces_[g], q);
      near = near || dist >= -2 * faces_[g].err;
      if (dist > faces_[g].drop_below && dist > best_d) {
        best_d = dist;
        best = g;
      }
    }
    // Below every plane by more than its rounding bound (most interior points): keep_if_beyond
    // would skip every face, so it is not called to compute the same distances again.
    if (best < 0) {
      if (near) keep_if_beyond(q, lo, hi);
      return;
    }
    if (best_d <= faces_[best].err && !above(faces_[best], q)) {
      best = -1;
      best_d = -std::numeric_limits<S>::infinity();
      for (int g = lo; g < hi; ++g) {
        if (!faces_[g].alive) continue;
        const S dist = distance(faces_[g], q);
        if (dist > faces_[g].drop_below && dist - faces_[g].err > best_d && above(faces_[g], q)) {
          best_d = dist - faces_[g].err;
          best = g;
        }
      }
      if (best < 0) return keep_if_beyond(q, lo, hi);
    }
    faces_[best].outside.push_back(q);
  }
  /// Point q is below, on or within eps of the plane of every face in [lo, hi). It is dropped only
  /// when it is also within eps of the hull: near a sharp edge a point can lie in or just above the
  /// planes of the faces around it and still be far beyond them (on the edge's line, past its end:
  /// a float set of 5 points left one 0.1 extents outside this way). Its distance to the hull is
  /// its distance to the nearest triangle it is above, so it is kept, on the face it is farthest
  /// above, unless a triangle it is exactly above is within eps of it (less that face's rounding
  /// bound). It then becomes an eye of a later step. (An orphan is tested against the step's new
  /// faces only: the nearest triangle may be an older one, so it may be kept where it could have
  /// been dropped, a vertex more, never the other way round.)
  void keep_if_beyond(int q, int lo, int hi) {
    int keep = -1;
    S keep_d = -std::numeric_limits<S>::infinity();
    const Vec3<S> x = pt(q);
    for (int g = lo; g < hi; ++g) {
      const Face& f = faces_[static_cast<std::size_t>(g)];
      if (!f.alive) continue;
      const S dist = distance(f, q);
      if (dist < -2 * f.err || !above(f, q)) continue;
      const Triangle<S> tri(pt(f.v[0]), pt(f.v[1]), pt(f.v[2]));
      if ((closest_point_on_triangle(x, tri).point - x).norm() <= f.drop_below) return;  // within eps of the hull
      if (dist > keep_d) {
        keep_d = dist;
        keep = g;
      }
    }
    if (keep >= 0) faces_[static_cast<std::size_t>(keep)].outside.push_back(q);
  }

  const Vertices<S>& p_;
  const double* x_;
  S eps_, extent_;
  std::vector<Face> faces_;
  static constexpr std::size_t kSpareCapacity = 64;
  std::vector<std::vector<int>> spare_;  ///< emptied conflict lists' storage, reused by add_face
  std::vector<int> start_face_;  ///< per point: the newest cone face whose first vertex it is
};

}  // namespace detail

/// The convex hull of the rows of `points` (n x 3). Throws InvalidInput on degenerate input (see
/// the file comment); `points` is not modified.
template <class S>
ConvexHull<S> convex_hull(const Vertices<S>& points, const ConvexHullOptions& options = {}) {
  static_assert(is_supported_scalar_v<S>, "convex_hull: S must be float or double");
  const char* where = "convex_hull";
  if (!(options.merge_angle >= 0) || !std::isfinite(options.merge_angle)) throw InvalidInput("convex_hull: options.merge_angle must be finite and >= 0");
  if (!std::isfinite(options.relative_tolerance)) throw InvalidInput("convex_hull: options.relative_tolerance must be finite");
  const Eigen::Index n = points.rows();
  if (n < 4) throw InvalidInput("convex_hull: needs at least 4 points, has " + std::to_string(n));
  if (n > Eigen::Index(std::numeric_limits<int>::max() / 2)) throw InvalidInput("convex_hull: too many points");
  validate_coordinates(points, where, "points");

  // Work on points centred on their bounding box: the tolerance is relative to their extent.
  const Vec3<S> lo = points.colwise().minCoeff().transpose(), hi = points.colwise().maxCoeff().transpose();
  const Vec3<S> mid = (lo + hi) / S(2);
  Vertices<S> p = points.rowwise() - mid.transpose();
  const S extent = (hi - lo).maxCoeff() / S(2);
  const S rel = options.relative_tolerance > 0 ? S(options.relative_tolerance) : S(1000) * std::numeric_limits<S>::epsilon();
  const S eps = rel * extent;
  if (!(extent > S(0)) || !(extent > eps)) throw InvalidInput("convex_hull: all points are coincident");

  // First tetrahedron: the two extreme points along the widest axis, the point farthest from
  // their line, the point farthest from their plane.
  int axis;
  (hi - lo).maxCoeff(&axis);
  Eigen::Index i0 = 0, i1 = 0;
  p.col(axis).minCoeff(&i0);
  p.col(axis).maxCoeff(&i1);
  const Vec3<S> a = p.row(i0).transpose(), b = p.row(i1).transpose();
  const Vec3<S> ab = (b - a).normalized();
  Eigen::Index i2 = -1;
  S best = -1;
  for (Eigen::Index i = 0; i < n; ++i) {
    const Vec3<S> x = p.row(i).transpose() - a;
    const S dist = (x - ab * ab.dot(x)).norm();
    if (dist > best) {
      best = dist;
      i2 = i;
    }
  }
  if (!(best > eps)) throw InvalidInput("convex_hull: all points are collinear (within the tolerance)");
  const Vec3<S> nrm = (b - a).cross(Vec3<S>(p.row(i2).transpose()) - a).normalized();
  Eigen::Index i3 = -1;
  best = -1;
  for (Eigen::Index i = 0; i < n; ++i) {
    const S dist = std::abs(nrm.dot(Vec3<S>(p.row(i).transpose()) - a));
    if (dist > best) {
      best = dist;
      i3 = i;
    }
  }
  if (!(best > eps)) throw InvalidInput("convex_hull: all points are coplanar (within the tolerance)");

  Vertices<double> exact_copy;
  const double* exact = nullptr;
  if constexpr (std::is_same_v<S, double>) {
    exact = points.data();
  } else {
    exact_copy = points.template cast<double>();
    exact = exact_copy.data();
  }
  // The first tetrahedron must be solid exactly too: with a tolerance below the rounding of S the
  // distance tests above can pass on points that are exactly coplanar (three distinct points and
  // copies of them), where quickhull has no solid start.
  if (detail::orient3d_double(exact + 3 * i0, exact + 3 * i1, exact + 3 * i2, exact + 3 * i3) == 0)
    throw InvalidInput("convex_hull: all points are collinear or coplanar (within the rounding of the coordinates)");
  detail::QuickHull<S> qh(p, exact, eps, extent);
  const auto run = qh.run(static_cast<int>(i0), static_cast<int>(i1), static_cast<int>(i2), static_cast<int>(i3));
  const auto& tris = run.vertices;
  // (the triangle across each edge, from quickhull's face links: a closed hull has one at each)
  const auto across = [&run](Eigen::Index t, int k) { return run.across[static_cast<std::size_t>(t)][static_cast<std::size_t>(k)]; };

  // Keep only the vertices used, in input order.
  std::vector<int> remap(static_cast<std::size_t>(n), -1);
  for (const auto& t : tris)
    for (int v : t) remap[static_cast<std::size_t>(v)] = 0;
  ConvexHull<S> h;
  int nv = 0;
  for (Eigen::Index i = 0; i < n; ++i)
    if (remap[static_cast<std::size_t>(i)] == 0) remap[static_cast<std::size_t>(i)] = nv++;
  h.vertices.resize(nv, 3);
  for (Eigen::Index i = 0; i < n; ++i)
    if (remap[static_cast<std::size_t>(i)] >= 0) h.vertices.row(remap[static_cast<std::size_t>(i)]) = points.row(i);
  h.triangles.resize(static_cast<Eigen::Index>(tris.size()), 3);
  for (std::size_t t = 0; t < tris.size(); ++t)
    for (int k = 0; k < 3; ++k) h.triangles(static_cast<Eigen::Index>(t), k) = remap[static_cast<std::size_t>(tris[t][static_cast<std::size_t>(k)])];
  h.centroid = h.vertices.colwise().mean().transpose();
  h.size = (h.vertices.rowwise() - h.centroid.transpose()).rowwise().norm().maxCoeff();
  detail::build_hull_climb(h);

  // Merge adjacent triangles with (nearly) parallel normals into polygons (union–find over edges).
  const Eigen::Index nt = h.triangles.rows();
  // Each triangle's area vector, in double across its two shorter edges (as quickhull's faces: a
  // sliver's two long edges are nearly parallel, their cross product in float rounding noise).
  std::vector<Eigen::Vector3d> area(static_cast<std::size_t>(nt));
  std::vector<Vec3<S>> tn(static_cast<std::size_t>(nt));
  for (Eigen::Index t = 0; t < nt; ++t) {
    const Eigen::Vector3d x = h.vertices.row(h.triangles(t, 0)).transpose().template cast<double>(),
                          y = h.vertices.row(h.triangles(t, 1)).transpose().template cast<double>(),
                          z = h.vertices.row(h.triangles(t, 2)).transpose().template cast<double>();
    const Eigen::Vector3d xy = y - x, yz = z - y, zx = x - z;
    const double lxy = xy.squaredNorm(), lyz = yz.squaredNorm(), lzx = zx.squaredNorm();
    area[static_cast<std::size_t>(t)] = lxy >= lyz && lxy >= lzx ? yz.cross(zx) : (lyz >= lzx ? zx.cross(xy) : xy.cross(yz));
    tn[static_cast<std::size_t>(t)] = area[static_cast<std::size_t>(t)].normalized().template cast<S>();
  }
  std::vector<int> parent(static_cast<std::size_t>(nt));
  std::iota(parent.begin(), parent.end(), 0);
  const auto find = [&](int x) {
    while (parent[static_cast<std::size_t>(x)] != x) x = parent[static_cast<std::size_t>(x)] = parent[static_cast<std::size_t>(parent[static_cast<std::size_t>(x)])];
    return x;
  };
  const S cos_merge = S(std::cos(options.merge_angle));
  for (Eigen::Index t = 0; t < nt; ++t)
    for (int k = 0; k < 3; ++k) {
      const int o = across(t, k);
      if (o < 0) continue;
      if (tn[static_cast<std::size_t>(t)].dot(tn[static_cast<std::size_t>(o)]) >= cos_merge)
        parent[static_cast<std::size_t>(find(static_cast<int>(t)))] = find(o);
    }
  const auto support_value = [&h](const Vec3<S>& dir, int v) {
    const auto along = [&](int u) { return dir.dot(h.vertices.row(u).transpose()); };
    S top = along(v);
    for (bool moved = true; moved;) {  // each round scans the neighbours of the vertex it starts at
      moved = false;
      for_each_neighbor(h, v, [&](int u) {
        const S x = along(u);
        if (x > top) {
          top = x;
          v = u;
          moved = true;
        }
      });
    }
    return top;
  };
  std::vector<int> group_face(static_cast<std::size_t>(nt), -1);  // per union-find root: its face
  std::vector<Eigen::Vector3d> normal_sum;
  for (Eigen::Index t = 0; t < nt; ++t) {
    int& face = group_face[static_cast<std::size_t>(find(static_cast<int>(t)))];
    if (face < 0) {
      face = static_cast<int>(h.faces.size());
      h.faces.emplace_back();
      h.faces.back().vertices.reserve(3);
      normal_sum.push_back(Eigen::Vector3d::Zero());
    }
    HullFace<S>& f = h.faces[static_cast<std::size_t>(face)];
    normal_sum[static_cast<std::size_t>(face)] += area[static_cast<std::size_t>(t)];
    for (int k = 0; k < 3; ++k)
      if (std::find(f.vertices.begin(), f.vertices.end(), h.triangles(t, k)) == f.vertices.end()) f.vertices.push_back(h.triangles(t, k));
  }
  std::vector<std::pair<S, int>> ang;
  for (std::size_t i = 0; i < h.faces.size(); ++i) {
    HullFace<S>& f = h.faces[i];
    Vec3<S> c = Vec3<S>::Zero();
    for (int v : f.vertices) c += h.vertices.row(v).transpose();
    c /= S(f.vertices.size());
    const double len = normal_sum[i].norm();
    // (a zero or unrepresentable sum: a needle whose area vector rounds away; the direction from
    // the interior centroid to the face's centre is outward on a solid hull)
    f.normal = len > 0 && std::isfinite(len) ? Vec3<S>((normal_sum[i] / len).template cast<S>()) : Vec3<S>((c - h.centroid).normalized());
    // Counter-clockwise order about the normal, from the vertex at the least angle in (-pi, pi]
    // measured from the first one. A face of one triangle (three vertices) is in its outward
    // order already: its last vertex is the one below the first.
    if (f.vertices.size() == 3) {
      std::rotate(f.vertices.begin(), f.vertices.begin() + 2, f.vertices.end());
    } else {
      const Vec3<S> u = (Vec3<S>(h.vertices.row(f.vertices[0]).transpose()) - c).normalized();
      const Vec3<S> w = f.normal.cross(u);
      ang.clear();
      for (int v : f.vertices) {
        const Vec3<S> x = h.vertices.row(v).transpose() - c;
        ang.push_back({std::atan2(x.dot(w), x.dot(u)), v});
      }
      std::sort(ang.begin(), ang.end());
      for (std::size_t k = 0; k < ang.size(); ++k) f.vertices[k] = ang[k].second;
    }
    // The offset is the hull's support value along the normal, not only the face's own vertices'
    // largest: the pair tests (separating axes, the particle colliders) take it as the hull's
    // extent along the normal, and a sliver's normal can tilt away from the plane of the hull's
    // other vertices by more than the tolerance. The hull is exactly convex, so the climb over
    // its vertex graph from the face's first vertex (a few steps: the face's vertices are nearly
    // the farthest already) ends at a farthest vertex; small hulls are scanned.
    f.offset = support_value(f.normal, f.vertices.front());
  }
  const std::size_t nf = h.faces.size();
  h.face_planes.resize(4 * nf);
  for (std::size_t i = 0; i < nf; ++i) {
    for (int k = 0; k < 3; ++k) h.face_planes[static_cast<std::size_t>(k) * nf + i] = h.faces[i].normal[k];
    h.face_planes[3 * nf + i] = h.faces[i].offset;
  }
  // The edges between two faces, each once (from the triangle where it runs upwards in index).
  for (Eigen::Index t = 0; t < nt; ++t)
    for (int k = 0; k < 3; ++k) {
      const int u = h.triangles(t, k), v = h.triangles(t, (k + 1) % 3);
      const int o = across(t, k);
      if (u > v || o < 0) continue;
      const int f0 = group_face[static_cast<std::size_t>(find(static_cast<int>(t)))], f1 = group_face[static_cast<std::size_t>(find(o))];
      if (f0 != f1) h.edges.push_back(HullEdge{u, v, f0, f1});
    }
  return h;
}

/// The convex hull of a mesh's vertices (its faces are not used).
template <class S>
ConvexHull<S> convex_hull_of_mesh(const Vertices<S>& V, const Faces& /*F*/, const ConvexHullOptions& options = {}) {
  return convex_hull(V, options);
}

}  // namespace impact
