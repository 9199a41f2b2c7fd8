// SPDX-License-Identifier: MIT
/// \file
/// ObbPairFrame: the oriented-box test of a pair traversal, where the boxes of tree B live in B's
/// frame and are tested against boxes of tree A under the relative transform x -> X x + t. X is
/// the product of two validated poses, so it may be off orthonormal by up to rotation_tolerance,
/// and the narrow phase moves B's vertices by that very X: the test bounds the image of each box
/// under X (a slightly stretched or skewed box), with the defect of X bounded once per frame.
#pragma once

#include "impact/core/types.hpp"
#include "impact/geometry/obb.hpp"
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

  /// What the test needs of box b (of B's frame) whatever box a is: its axes and centre moved by
  /// X and t, and its part of the rounding bound. A traversal that tests one box b against
  /// several boxes of A in a row computes it once (MeshNodeOverlap does).
  struct Image {
    Mat3<S> axes = Mat3<S>::Zero();    ///< fl(X B)
    Vec3<S> center = Vec3<S>::Zero();  ///< fl(X c_b + t)
    Vec3<S> half = Vec3<S>::Zero();    ///< b's half extents
    S radius = 0;                      ///< b's ball radius stretched by X's defect (infinite: no ball)
    S m = 0;                           ///< |X c_b + t| + |t| + |c_b| (max norms)
  };
  Image image(const Obb<S>& b) const {
    Image im;
    im.axes = x_ * b.axes;
    im.center = x_ * b.center + t_;
    im.half = b.half;
    im.radius = b.radius * (S(1) + defect_);
    im.m = im.center.cwiseAbs().maxCoeff() + t_.cwiseAbs().maxCoeff() + b.center.cwiseAbs().maxCoeff();
    return im;
  }

  /// May box a (of A's frame) and the image of box b (of B's frame) share a point?
  bool overlaps(const Obb<S>& a, const Obb<S>& b) const { return overlaps(a, image(b)); }

  /// The same test with b's image computed beforehand (image(b)).
  bool overlaps(const Obb<S>& a, const Image& b) const {
    constexpr S eps = std::numeric_limits<S>::epsilon();
    const Vec3<S> d = b.center - a.center;
    const S M = a.center.cwiseAbs().maxCoeff() + b.m;
    {
      // the balls first (a few operations, and most pairs far apart fail here)
      const S r = a.radius + b.radius + S(64) * eps * (S(3) * M + a.radius + b.radius);
      if (d.squaredNorm() > r * r * (S(1) + S(16) * eps)) return false;
    }
    // R = A^T (X B) and tb = A^T (X c_b + t - c_a), written out (fewer instructions than Eigen's
    // packets on 3-vectors)
    Mat3<S> R;
    Vec3<S> tb;
    for (int i = 0; i < 3; ++i) {
      const S u = a.axes(0, i), v = a.axes(1, i), w = a.axes(2, i);
      for (int j = 0; j < 3; ++j) R(i, j) = u * b.axes(0, j) + v * b.axes(1, j) + w * b.axes(2, j);
      tb[i] = u * d[0] + v * d[1] + w * d[2];
    }
    const S E = tb.cwiseAbs().sum() + a.half.sum() + b.half.sum();
    const S slack = S(64) * eps * (S(3) * M + E) + S(2) * defect_ * E + std::numeric_limits<S>::denorm_min();
    return obb_overlap<S>(a.half, R, tb, b.half, slack, defect_);
  }

 private:
  Mat3<S> x_;
  Vec3<S> t_;
  S defect_;  ///< >= |X^T X - I|_2, rounded up
};

}  // namespace impact
