// SPDX-License-Identifier: MIT
// Fuzz target: MeshBvh trees (sphere and AABB) built on small random meshes decoded from the input
// (3-16 vertices on a small integer grid, 1-24 triangles with any indices: duplicates, shared
// edges, zero-area and coincident triangles are all common), under exact poses (a signed axis
// permutation and an integer translation); or, mixed-scale, a mesh of big triangles (vertices up
// to 2^18) against a cluster of small ones next to one of its vertices. Checked against brute
// force written here:
//  - collide (all pairs) and collides against every triangle pair decided by the exact integer
//    separating-axis test (tests/narrow/int_oracle.hpp) on the posed integer vertices;
//  - self_collide against every non-adjacent pair of the mesh, decided the same way;
//  - ray_mesh_first_hit and ray_mesh_any_hit against a loop over every triangle with the narrow
//    phase's ray test (this checks that the traversal never loses a hit: the same t, exactly, and
//    a reported triangle that the ray crosses at that t), through the MeshBvh and through the
//    wide trees of the ray casts (WideBvh 4-wide, and 8-wide in double: its AVX node test), posed
//    and in the mesh's frame.
// Every tree type (sphere, AABB, oriented box) is built with the default configuration and with
// one more, chosen by a hash of the input (bottom-up or incremental, another split rule, larger
// leaves), so the inputs of the corpus and the regressions keep their meaning.
#include "fuzz_input.hpp"
#include "impact/bvh/mesh_bvh.hpp"
#include "impact/query/mesh_collide.hpp"
#include "impact/query/ray_mesh.hpp"
#include "impact/query/ray_wide_bvh.hpp"
#include "narrow/int_oracle.hpp"

#include <algorithm>
#include <cstdio>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace {

using impact::test::IPoint;
using Pairs = std::vector<std::pair<std::int32_t, std::int32_t>>;

struct IntMesh {
  std::vector<IPoint> V;
  std::vector<std::array<int, 3>> F;
};

/// A rotation that permutes and flips axes (det +1) and an integer translation: exact in floats.
struct IntPose {
  int perm[3] = {0, 1, 2};
  int sign[3] = {1, 1, 1};
  IPoint t{0, 0, 0};
  IPoint apply(const IPoint& p) const {
    IPoint q;
    for (int i = 0; i < 3; ++i) q[std::size_t(i)] = sign[i] * p[std::size_t(perm[i])] + t[std::size_t(i)];
    return q;
  }
  template <class S> impact::RigidTransform<S> transform() const {
    impact::Mat3<S> R = impact::Mat3<S>::Zero();
    for (int i = 0; i < 3; ++i) R(i, perm[i]) = S(sign[i]);
    return impact::RigidTransform<S>(R, impact::Vec3<S>(S(t[0]), S(t[1]), S(t[2])));
  }
};

IntMesh read_mesh(impact::fuzz::Input& in, std::int64_t r) {
  IntMesh m;
  const int n = 3 + int(in.byte() % 14), f = 1 + int(in.byte() % 24);
  for (int i = 0; i < n; ++i) m.V.push_back({in.range(-r, r), in.range(-r, r), in.range(-r, r)});
  for (int i = 0; i < f; ++i) m.F.push_back({int(in.byte()) % n, int(in.byte()) % n, int(in.byte()) % n});
  return m;
}

IntPose read_pose(impact::fuzz::Input& in, std::int64_t r) {
  static const int perms[6][3] = {{0, 1, 2}, {1, 2, 0}, {2, 0, 1}, {1, 0, 2}, {0, 2, 1}, {2, 1, 0}};
  IntPose p;
  const std::uint8_t b = in.byte();
  const int k = b % 6;
  for (int i = 0; i < 3; ++i) p.perm[i] = perms[k][i];
  p.sign[0] = (b & 8u) ? -1 : 1;
  p.sign[1] = (b & 16u) ? -1 : 1;
  // det = parity(perm) * product of signs must be +1
  const int parity = k < 3 ? 1 : -1;
  p.sign[2] = parity * p.sign[0] * p.sign[1];
  for (auto& x : p.t) x = in.range(-r, r);
  return p;
}

std::array<IPoint, 3> posed(const IntMesh& m, int t, const IntPose& pose) {
  return {pose.apply(m.V[std::size_t(m.F[std::size_t(t)][0])]), pose.apply(m.V[std::size_t(m.F[std::size_t(t)][1])]),
          pose.apply(m.V[std::size_t(m.F[std::size_t(t)][2])])};
}

template <class S> impact::TriangleMesh<S> to_mesh(const IntMesh& m) {
  impact::TriangleMesh<S> out;
  out.V.resize(Eigen::Index(m.V.size()), 3);
  out.F.resize(Eigen::Index(m.F.size()), 3);
  for (std::size_t i = 0; i < m.V.size(); ++i)
    for (int d = 0; d < 3; ++d) out.V(Eigen::Index(i), d) = S(m.V[i][std::size_t(d)]);
  for (std::size_t i = 0; i < m.F.size(); ++i)
    for (int d = 0; d < 3; ++d) out.F(Eigen::Index(i), d) = m.F[i][std::size_t(d)];
  return out;
}

/// A ray parameter to the last bit (%a), so that two values one ulp apart print differently.
template <class S> std::string hex(S x) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%a", double(x));
  return buf;
}

std::string pairs_text(const Pairs& p) {
  std::string s;
  for (const auto& [a, b] : p) s += " (" + std::to_string(a) + "," + std::to_string(b) + ")";
  return s.empty() ? " none" : s;
}

/// The first hit of the local ray (lo, ld) over every triangle of m with the narrow phase's test.
template <class S> std::optional<S> brute_force_first_hit(const impact::TriangleMesh<S>& m, const impact::Vec3<S>& lo,
                                                          const impact::Vec3<S>& ld, S t_max) {
  std::optional<S> best;
  if (ld.squaredNorm() == S(0)) return best;
  for (int i = 0; i < m.num_triangles(); ++i) {
    const impact::PreparedRay<S> pr(impact::Ray<S>(lo, ld, best ? *best : t_max));
    const auto h = impact::detail::ray_mesh_triangle_hit(pr, m.triangle(i));
    if (h && (!best || h->t < *best)) best = h->t;
  }
  return best;
}

/// A hit agrees with brute force: both none, or the same t and a triangle the ray crosses at it.
template <class S> void check_hit(const std::optional<impact::RayMeshHit<S>>& hit, const std::optional<S>& best,
                                  const impact::TriangleMesh<S>& m, const impact::Vec3<S>& lo, const impact::Vec3<S>& ld, S t_max,
                                  const std::string& where) {
  if (hit.has_value() != best.has_value() || (hit && hit->t != *best))
    impact::fuzz::fail(where + ": first hit " + (hit ? hex(hit->t) : "none") + ", brute force " + (best ? hex(*best) : "none"));
  if (!hit) return;
  if (hit->triangle < 0 || hit->triangle >= m.num_triangles())
    impact::fuzz::fail(where + ": hit triangle " + std::to_string(hit->triangle) + " out of range");
  const auto h = impact::detail::ray_mesh_triangle_hit(impact::PreparedRay<S>(impact::Ray<S>(lo, ld, t_max)), m.triangle(hit->triangle));
  if (!h || h->t != hit->t)
    impact::fuzz::fail(where + ": triangle " + std::to_string(hit->triangle) + " is not crossed at " + hex(hit->t));
}

std::string ray_text(const char* name, const IPoint& o, const IPoint& d) {
  return std::string(name) + " ray (" + std::to_string(o[0]) + "," + std::to_string(o[1]) + "," + std::to_string(o[2]) + ") dir (" +
         std::to_string(d[0]) + "," + std::to_string(d[1]) + "," + std::to_string(d[2]) + ")";
}

/// The wide trees of the ray casts on A, posed by pa and in A's frame, against brute force.
template <class S, int W> void check_wide(const IntMesh& A, const IntPose& pa, const std::vector<std::pair<IPoint, IPoint>>& rays,
                                          int leaf_size, const char* name) {
  const auto ma = to_mesh<S>(A);
  impact::WideBvhConfig cfg;
  cfg.leaf_size = leaf_size;
  const impact::WideBvh<S, W> wide(ma, cfg);
  const auto pose_a = pa.transform<S>();
  for (const auto& [o, d] : rays) {
    const impact::Ray<S> ray{impact::Vec3<S>(S(o[0]), S(o[1]), S(o[2])), impact::Vec3<S>(S(d[0]), S(d[1]), S(d[2]))};
    if (ray.direction == impact::Vec3<S>::Zero()) continue;  // rejected as in check()
    // the pose is exact (a signed permutation and an integer translation): so is the local ray
    const impact::Vec3<S> lo = pose_a.R.transpose() * (ray.origin - pose_a.t), ld = pose_a.R.transpose() * ray.direction;
    const std::optional<S> best = brute_force_first_hit(ma, lo, ld, ray.t_max);
    const std::string where = ray_text(name, o, d);
    check_hit(impact::ray_mesh_first_hit(wide, ray, pose_a), best, ma, lo, ld, ray.t_max, where + " posed");
    check_hit(impact::ray_mesh_first_hit(wide, impact::Ray<S>(lo, ld, ray.t_max)), best, ma, lo, ld, ray.t_max, where + " local");
  }
}

template <class BV, class S> void check(const IntMesh& A, const IntMesh& B, const IntPose& pa, const IntPose& pb,
                                        const std::vector<std::pair<IPoint, IPoint>>& rays, const impact::MeshBvhConfig& cfg,
                                        const char* name) {
  const auto ma = to_mesh<S>(A), mb = to_mesh<S>(B);
  const impact::MeshBvh<BV> ta(ma, cfg), tb(mb, cfg);
  const auto pose_a = pa.transform<S>(), pose_b = pb.transform<S>();

  // mesh against mesh
  Pairs want;
  for (int i = 0; i < int(A.F.size()); ++i)
    for (int j = 0; j < int(B.F.size()); ++j)
      if (impact::test::triangles_intersect_int(posed(A, i, pa), posed(B, j, pb))) want.emplace_back(i, j);
  impact::CollideOptions all;
  all.all_pairs = true;
  Pairs got = impact::collide(ta, pose_a, tb, pose_b, all).pairs;
  std::sort(got.begin(), got.end());
  if (got != want) impact::fuzz::fail(std::string(name) + " collide: pairs" + pairs_text(got) + ", exact" + pairs_text(want));
  if (impact::collides(ta, pose_a, tb, pose_b) != !want.empty())
    impact::fuzz::fail(std::string(name) + " collides disagrees with the exact pairs" + pairs_text(want));

  // self-collision of A (non-adjacent pairs: no shared vertex index)
  Pairs self_want;
  const IntPose identity;
  for (int i = 0; i < int(A.F.size()); ++i)
    for (int j = i + 1; j < int(A.F.size()); ++j) {
      bool adjacent = false;
      for (int x : A.F[std::size_t(i)])
        for (int y : A.F[std::size_t(j)]) adjacent = adjacent || x == y;
      if (!adjacent && impact::test::triangles_intersect_int(posed(A, i, identity), posed(A, j, identity))) self_want.emplace_back(i, j);
    }
  Pairs self_got = impact::self_collide(ta, all).pairs;
  std::sort(self_got.begin(), self_got.end());
  if (self_got != self_want)
    impact::fuzz::fail(std::string(name) + " self_collide: pairs" + pairs_text(self_got) + ", exact" + pairs_text(self_want));

  // rays against mesh A at pose_a: brute force over every triangle in A's frame
  for (const auto& [o, d] : rays) {
    const impact::Ray<S> ray{impact::Vec3<S>(S(o[0]), S(o[1]), S(o[2])), impact::Vec3<S>(S(d[0]), S(d[1]), S(d[2]))};
    if (ray.direction == impact::Vec3<S>::Zero()) {  // not a ray: the queries reject it (validate_ray)
      bool threw = false;
      try {
        (void)impact::ray_mesh_first_hit(ta, ray, pose_a);
      } catch (const impact::InvalidInput&) {
        threw = true;
      }
      if (!threw) impact::fuzz::fail(std::string(name) + " ray with a zero direction accepted");
      continue;
    }
    const impact::Vec3<S> lo = pose_a.R.transpose() * (ray.origin - pose_a.t), ld = pose_a.R.transpose() * ray.direction;
    const std::optional<S> best = brute_force_first_hit(ma, lo, ld, ray.t_max);
    const std::string where = ray_text(name, o, d);
    check_hit(impact::ray_mesh_first_hit(ta, ray, pose_a), best, ma, lo, ld, ray.t_max, where);
    if (impact::ray_mesh_any_hit(ta, ray, pose_a) != best.has_value())
      impact::fuzz::fail(where + ": any hit disagrees with brute force");
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  impact::fuzz::Input in(data, size);
  const std::uint8_t mode = in.byte();
  const std::int64_t r = std::int64_t(1) << (1 + mode % 6);  // grid [-r, r], r = 2 .. 64
  IntMesh A, B;
  IntPose pa, pb;
  if (mode & 128u) {
    // mixed scales: A's vertices anywhere in [-2^18, 2^18], B a cluster of small triangles within
    // r of one of A's vertices (big triangles touching small ones: the plane distances of the
    // culls are rounded at A's scale), B posed by a small integer translation only
    A = read_mesh(in, std::int64_t(1) << 18);
    B = read_mesh(in, r);
    const IPoint anchor = A.V[std::size_t(in.byte()) % A.V.size()];
    B.V[0] = {0, 0, 0};  // B's first vertex on the anchor: touching at a shared point is common
    for (auto& v : B.V)
      for (std::size_t i = 0; i < 3; ++i) v[i] += anchor[i];
    if (in.flag())
      for (auto& x : pb.t) x = in.range(-2, 2);
  } else {
    A = read_mesh(in, r);
    B = read_mesh(in, r);
    pa = read_pose(in, r);
    pb = read_pose(in, r);
  }
  std::vector<std::pair<IPoint, IPoint>> rays;
  for (int k = 0; k < 4 && in.left() > 0; ++k) {
    IPoint o{in.range(-2 * r, 2 * r), in.range(-2 * r, 2 * r), in.range(-2 * r, 2 * r)};
    IPoint d{in.range(-4, 4), in.range(-4, 4), in.range(-4, 4)};
    rays.emplace_back(o, d);
  }
  // A second build configuration from a hash of the whole input (not read from it: the inputs
  // kept in the corpus and the regressions decode as before)
  std::uint32_t hash = 2166136261u;
  for (std::size_t i = 0; i < size; ++i) hash = (hash ^ data[i]) * 16777619u;
  impact::MeshBvhConfig other;
  static const impact::BuildMethod methods[3] = {impact::BuildMethod::TopDown, impact::BuildMethod::BottomUp,
                                                 impact::BuildMethod::Incremental};
  static const impact::SplitRule splits[4] = {impact::SplitRule::Default, impact::SplitRule::SpatialMiddle,
                                              impact::SplitRule::CentroidMedian, impact::SplitRule::Sah};
  other.build.method = methods[hash % 3];
  other.build.split = splits[(hash / 3) % 4];
  other.build.leaf_size = 1 + int((hash / 12) % 4);
  other.build.sibling_search = (hash / 48) % 2 ? impact::SiblingSearch::Greedy : impact::SiblingSearch::BranchAndBound;
  other.build.rotations = (hash / 96) % 2 == 0;
  const int wide_leaf = 1 + int((hash / 192) % 4);
  // every generated mesh is valid input (finite, indices in range): the trees must not refuse it
  for (const impact::MeshBvhConfig& cfg : {impact::MeshBvhConfig{}, other}) {
    if (mode & 64u) {
      check<impact::Sphere<float>, float>(A, B, pa, pb, rays, cfg, "sphere float");
      check<impact::Aabb<float>, float>(A, B, pa, pb, rays, cfg, "aabb float");
      check<impact::Obb<float>, float>(A, B, pa, pb, rays, cfg, "obb float");
    } else {
      check<impact::Sphere<double>, double>(A, B, pa, pb, rays, cfg, "sphere double");
      check<impact::Aabb<double>, double>(A, B, pa, pb, rays, cfg, "aabb double");
      check<impact::Obb<double>, double>(A, B, pa, pb, rays, cfg, "obb double");
    }
  }
  if (mode & 64u) {
    check_wide<float, 4>(A, pa, rays, wide_leaf, "wide4 float");
  } else {
    check_wide<double, 4>(A, pa, rays, wide_leaf, "wide4 double");
    check_wide<double, 8>(A, pa, rays, wide_leaf, "wide8 double");
  }
  return 0;
}
