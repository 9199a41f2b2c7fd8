// SPDX-License-Identifier: MIT
/// \file
/// ObbPairFrame: the oriented-box test of a pair traversal, where the boxes of tree B live in B's
/// frame and are tested against boxes of tree A under the relative transform x -> X x + t. X is
/// the product of two validated poses, so it may be off orthonormal by up to rotation_tolerance,
/// and the narrow phase moves B's vertices by that very X: the test bounds the image of each box
/// under X (a slightly stretched or skewed box), with the defect of X bounded once per frame.
#pragma once

#include "impact/core/config.hpp"
#include "impact/core/types.hpp"
#include "impact/geometry/obb.hpp"
#include "impact/geometry/obb_slabs.hpp"
#include "impact/geometry/rotation_defect.hpp"
#include "impact/geometry/transform.hpp"

#include <cmath>
#include <limits>

namespace impact {

/// Conservative: overlaps(a, b) is never false when box a and the image X b + t of box b share a
/// point, for X exactly as given, and under the rounding of every product.
///  - Defect: with X = U (I + F), U orthonormal, |F|_2 <= g (rotation_defect_bound), the image of
///    b's offsets s from its centre lies within g |s| <= g sum(half_b) of U s, so it is inside the
///    box with axes U b_k and half extents half_b + g sum(half_b), centred at X c_b + t. The test
///    runs with R = A^T X B, whose entries are within g of those of A^T U B: a pad of g on every
///    |R_ij| and 2 g E on every axis (E = |t_b|_1 + sum(half_a) + sum(half_b)) cover both the
///    larger box and the centre's projections on the axes built from R.
///  - Balls (Obb::radius, infinite when absent): the image of b's ball lies in the ball of radius
///    |X|_2 r_b <= (1 + g) r_b about X c_b + t; the centres' distance is rounded by at most a few
///    tens of ulps of M per coordinate and B's moved vertices by less (the narrow phase's
///    rounding), so the balls are padded by 64 ulps of 3 M + r_a + r_b. Infinite radii never reject.
///  - Rounding: R = fl(A^T fl(X B)) and t_b = fl(A^T fl(fl(X c_b + t) - c_a)) are within a few
///    tens of ulps of 1 and of M = |c_a| + |X c_b + t| + |t| + |c_b| (max norms), so 64 ulps of
///    3 M + E on every axis, with obb_overlap's own pad of |R|, cover them.
/// Tested against the exact brute force with poses stretched to the tolerance
/// (MeshCollideExact.NearlyRigidPosesKeepEveryContact).
template <class S> class ObbPairFrame {
 public:
  /// Both boxes in one frame (X = I exactly: no defect, and products with X exact).
  ObbPairFrame() : x_(Mat3<S>::Identity()), t_(Vec3<S>::Zero()), defect_(0) {}
  explicit ObbPairFrame(const RigidTransform<S>& b_to_a)
      : x_(b_to_a.R), t_(b_to_a.t), defect_(rotation_defect_bound(b_to_a.R) * (S(1) + S(8) * std::numeric_limits<S>::epsilon())) {}
  /// The same with a bound of X's defect known beforehand: `defect` >= |X^T X - I|_2 (for example
  /// validated_product_defect() for X = relative_transform of two poses that passed validate_pose:
  /// the mesh queries do not measure X then, about 80 instructions a query).
  ObbPairFrame(const RigidTransform<S>& b_to_a, S defect) : x_(b_to_a.R), t_(b_to_a.t), defect_(defect) {}

  /// A bound of |X^T X - I|_2 for X = fl(Ra^T Rb), the rotation of relative_transform(pose_a,
  /// pose_b), whatever the two poses that passed validate_pose. With tol = rotation_tolerance and
  /// u the unit roundoff: validate_pose bounds every computed entry of fl(R^T R) - I by tol, so
  /// every exact entry by tol + 3.2u (the dot products' rounding, the subtraction exact), and
  /// |R^T R - I|_2 <= |.|_F <= g1 := 3 tol + 10u for each pose. Ra Ra^T - I has the same 2-norm, so
  /// X_exact = Ra^T Rb has |X^T X - I|_2 <= g1 (1 + g1) + g1 (= Rb^T (Ra Ra^T - I) Rb + Rb^T Rb -
  /// I). The rounding E of the product has |E|_F <= 3 gamma_3 (1 + g1) <= 9.5u, adding at most
  /// 2 |X|_2 |E| + |E|^2 <= 20u. In all g <= 6 tol + 9 tol^2 + 40u <= 7 tol + 64u for tol <= 1e-2
  /// (tol is 1e-6 in double, 3.5e-4 in float). Looser than the measured bound (about 1e-15 for
  /// exact rotations): every volume grows by about 2 g of its size, so the node tests may accept a
  /// few pairs more; no answer changes.
  static S validated_product_defect() {
    return S(7) * rotation_tolerance<S>() + S(64) * std::numeric_limits<S>::epsilon();
  }

  /// What the test needs of box b (of B's frame) whatever box a is: its axes and centre moved by
  /// X and t, and its part of the rounding bound. A traversal that tests one box b against
  /// several boxes of A in a row computes it once (MeshNodeOverlap does). The axes are computed
  /// only when a test needs them (most pairs are rejected by the balls first): image_centre(b)
  /// leaves them out, and overlaps(a, im, b) fills them in on first use.
  struct Image {
    Mat3<S> axes;                      ///< fl(X B), when has_axes (not set up before: most tests end at the balls)
    Vec3<S> center = Vec3<S>::Zero();  ///< fl(X c_b + t)
    Vec3<S> half = Vec3<S>::Zero();    ///< b's half extents
    S radius = 0;                      ///< b's ball radius stretched by X's defect (infinite: no ball)
    S m = 0;                           ///< |X c_b + t| + |t| + |c_b| (max norms)
    bool has_axes = false;
  };
  Image image_centre(const Obb<S>& b) const {
    Image im;
    im.center = x_ * b.center + t_;
    im.half = b.half;
    im.radius = b.radius * (S(1) + defect_);
    im.m = im.center.cwiseAbs().maxCoeff() + t_.cwiseAbs().maxCoeff() + b.center.cwiseAbs().maxCoeff();
    return im;
  }
  Image image(const Obb<S>& b) const {
    Image im = image_centre(b);
    im.axes = x_ * b.axes;
    im.has_axes = true;
    return im;
  }

  /// Both boxes in one frame (self-collision; BvTraits<Obb>::overlap without a transform): the
  /// answer of ObbPairFrame().overlaps(a, b), decision for decision, without forming b's image by
  /// X = I (its centre, radius and axes are b's own: the products with I are exact, and the
  /// rounding bound's M = |c_b| + 0 + |c_b| the same). In a self-collision walk about 3 in 4 node
  /// pairs overlap and reach the 15 axes; skipping the 36 products cut the bunny's and the
  /// armadillo's self_collide by a quarter (docs/hierarchies.md).
  static bool overlaps_in_one_frame(const Obb<S>& a, const Obb<S>& b) {
    Image im;
    im.center = b.center;
    im.half = b.half;
    im.radius = b.radius;
    im.m = S(2) * b.center.cwiseAbs().maxCoeff();
    im.axes = b.axes;
    im.has_axes = true;
    return ObbPairFrame().overlaps(a, im, b);
  }

  /// May box a (of A's frame) and the image of box b (of B's frame) share a point?
  bool overlaps(const Obb<S>& a, const Obb<S>& b) const {
    Image im = image_centre(b);
    return overlaps(a, im, b);
  }

  /// The same test with b's image computed beforehand (image_centre(b) or image(b)); its axes are
  /// computed here if it has none yet. Three stages, each conservative on its own: the two balls;
  /// A's three face axes against b's ball (its image lies within radius of its centre, so its
  /// extent along any unit axis is at most the radius: no product with b's axes needed yet); then
  /// the 15 axes, with each volume's extent on an axis the lesser of its box's and its ball's (each
  /// node bounds the box cut by the ball). `EdgeAxes` as for obb_overlap: the edge axes a_i x b_j
  /// tried are those with i, j < EdgeAxes (the walks of the mesh queries take 2).
  template <int EdgeAxes = 3> bool overlaps(const Obb<S>& a, Image& b, const Obb<S>& b_box) const {
    constexpr S eps = std::numeric_limits<S>::epsilon();
    const Vec3<S> d = b.center - a.center;
    const S M = a.center.cwiseAbs().maxCoeff() + b.m;
    const S ball_pad = S(64) * eps * (S(3) * M + a.radius + b.radius);
    {
      // the balls first (a few operations, and most pairs far apart fail here)
      const S r = a.radius + b.radius + ball_pad;
      if (d.squaredNorm() > r * r * (S(1) + S(16) * eps)) return false;
    }
    const S g = defect_;
    // tb = A^T (X c_b + t - c_a), written out (fewer instructions than Eigen's packets)
    Vec3<S> tb;
    for (int i = 0; i < 3; ++i) tb[i] = a.axes(0, i) * d[0] + a.axes(1, i) * d[1] + a.axes(2, i) * d[2];
    const S E = std::abs(tb[0]) + std::abs(tb[1]) + std::abs(tb[2]) + a.half.sum() + b.half.sum();
    const S slack = S(64) * eps * (S(3) * M + E) + S(2) * g * E + std::numeric_limits<S>::denorm_min();
    {
      // A's faces against b's ball: the rounding of tb is within slack (as for the box axes), the
      // ball's own (its centre, the narrow phase's moved vertices) within ball_pad
      const S rb = b.radius + ball_pad + slack;
      if (std::abs(tb[0]) > a.half[0] + rb || std::abs(tb[1]) > a.half[1] + rb || std::abs(tb[2]) > a.half[2] + rb) return false;
    }
    if (!b.has_axes) {
      b.axes = x_ * b_box.axes;
      b.has_axes = true;
    }
    // R = A^T (X B), written out
    Mat3<S> R;
    for (int i = 0; i < 3; ++i) {
      const S u = a.axes(0, i), v = a.axes(1, i), w = a.axes(2, i);
      for (int j = 0; j < 3; ++j) R(i, j) = u * b.axes(0, j) + v * b.axes(1, j) + w * b.axes(2, j);
    }
    // a's ball caps its extent on b's face axes (at most 1 + 2g long: X B's columns are within g
    // of unit length, A's axes orthonormal within rounding); b's ball on A's face axes was the
    // stage above
    const S stretch = S(1) + S(2) * g + S(64) * eps;
    return obb_overlap<S, EdgeAxes>(a.half, R, tb, b.half, slack, g, (a.radius + ball_pad) * stretch);
  }

  /// overlaps(a, b, b_box), then, when it finds no separation, a fourth stage with `slabs_a` (the
  /// slabs of the points box a bounds, measured in a's frame) or `slabs_b` (those of b's points, in
  /// b_box's frame): their ten diagonal directions each (obb_slabs_separate), with the bounds of
  /// the rounding and of X's defect taken once per term of a direction, and the points' spread by
  /// X's defect (at most g sum(half_b) from a rigid image) on b's. Its terms (R, tb and the
  /// bounds) are those of overlaps(), formed again (about 60 instructions): the stage runs once per
  /// query at most, and the walk's node test keeps its code as it was (with the stage folded into
  /// it, GCC 12 left obb_overlap out of line and the test's code changed on every node pair).
  IMPACT_NOINLINE bool overlaps_with_slabs(const Obb<S>& a, Image& b, const Obb<S>& b_box, const ObbSlabs<S>* slabs_a,
                                           const ObbSlabs<S>* slabs_b) const {
    if (!overlaps(a, b, b_box)) return false;
    if (!slabs_a && !slabs_b) return true;
    constexpr S eps = std::numeric_limits<S>::epsilon();
    const Vec3<S> d = b.center - a.center;
    const S M = a.center.cwiseAbs().maxCoeff() + b.m;
    const S ball_pad = S(64) * eps * (S(3) * M + a.radius + b.radius);
    const S g = defect_;
    Vec3<S> tb;
    for (int i = 0; i < 3; ++i) tb[i] = a.axes(0, i) * d[0] + a.axes(1, i) * d[1] + a.axes(2, i) * d[2];
    const S E = std::abs(tb[0]) + std::abs(tb[1]) + std::abs(tb[2]) + a.half.sum() + b.half.sum();
    const S slack = S(64) * eps * (S(3) * M + E) + S(2) * g * E + std::numeric_limits<S>::denorm_min();
    Mat3<S> R;  // b's axes were formed by overlaps(): it got past the balls
    for (int i = 0; i < 3; ++i) {
      const S u = a.axes(0, i), v = a.axes(1, i), w = a.axes(2, i);
      for (int j = 0; j < 3; ++j) R(i, j) = u * b.axes(0, j) + v * b.axes(1, j) + w * b.axes(2, j);
    }
    const S stretch = S(1) + S(2) * g + S(64) * eps;
    return !obb_slabs_separate<S>(a.half, R, tb, b.half, slack, g, (a.radius + ball_pad) * stretch, b.radius + ball_pad,
                                  g * b.half.sum() * (S(1) + S(8) * eps), slabs_a, slabs_b);
  }

 private:
  Mat3<S> x_;
  Vec3<S> t_;
  S defect_;  ///< >= |X^T X - I|_2, rounded up
};

}  // namespace impact
