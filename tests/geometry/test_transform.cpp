// SPDX-License-Identifier: MIT
// relative_transform (pose_a^-1 * pose_b, computed without the temporary inverse for the mesh
// queries' fixed cost): its rotation is the same bits as the product of the inverse and the pose;
// its translation Ra^T (tb - ta) is within the rounding of one subtraction and one product of the
// exact value, computed here in long double from the same inputs, also for two poses far from the
// origin and near each other (where the inverse's two large products lose the digits); products
// with the identity are exact. Float and double.
#include "impact/geometry/transform.hpp"
#include "support/random.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <limits>

using namespace impact;

namespace {

template <class S> bool same_bits(const Mat3<S>& x, const Mat3<S>& y) { return std::memcmp(x.data(), y.data(), 9 * sizeof(S)) == 0; }
template <class S> bool same_bits(const Vec3<S>& x, const Vec3<S>& y) { return std::memcmp(x.data(), y.data(), 3 * sizeof(S)) == 0; }

template <class S> void check_relative_transform(std::uint64_t seed) {
  using L = long double;
  constexpr S u = std::numeric_limits<S>::epsilon() / 2;
  test::Rng rng(seed);
  for (int k = 0; k < 2000; ++k) {
    // every third pair: both poses about 1e6 from the origin and within 1 of each other
    const bool far = k % 3 == 0;
    const Eigen::Vector3d base = far ? rng.vec(-1e6, 1e6) : Eigen::Vector3d::Zero();
    const RigidTransform<S> pa = RigidTransform<double>(rng.rotation(), base + rng.vec(-1, 1)).cast<S>();
    const RigidTransform<S> pb = RigidTransform<double>(rng.rotation(), base + rng.vec(-1, 1)).cast<S>();
    const RigidTransform<S> x = relative_transform(pa, pb);
    const RigidTransform<S> product = pa.inverse() * pb;
    ASSERT_TRUE(same_bits(x.R, product.R)) << "pose pair " << k;
    // t against Ra^T (tb - ta) in long double from the same (rounded) inputs: fl(tb - ta) is within
    // u of it a component, then a 3-term dot product adds gamma_3; 8u of |Ra|^T |tb - ta| covers both
    const Vec3<S> d = pb.t - pa.t;
    for (int i = 0; i < 3; ++i) {
      L exact = 0, scale = 0;
      for (int j = 0; j < 3; ++j) {
        exact += L(pa.R(j, i)) * (L(pb.t[j]) - L(pa.t[j]));
        scale += std::abs(L(pa.R(j, i))) * std::abs(L(d[j]));
      }
      ASSERT_LE(std::abs(L(x.t[i]) - exact), L(8) * L(u) * scale) << "pose pair " << k << " component " << i;
    }
  }
  const RigidTransform<S> id;
  const RigidTransform<S> p = RigidTransform<double>(rng.rotation(), rng.vec(-5, 5)).cast<S>();
  const RigidTransform<S> x = relative_transform(id, p);
  EXPECT_TRUE(same_bits(x.R, p.R));  // products with I are exact
  EXPECT_TRUE(same_bits(x.t, p.t));
  const RigidTransform<S> y = relative_transform(p, p);
  EXPECT_TRUE((y.t.array() == S(0)).all());  // one pose against itself: no translation at all (signed zeros)
  EXPECT_LE((y.R - Mat3<S>::Identity()).cwiseAbs().maxCoeff(), S(8) * u);
}

}  // namespace

TEST(RelativeTransform, MatchesInverseTimesPoseDouble) { check_relative_transform<double>(13101); }
TEST(RelativeTransform, MatchesInverseTimesPoseFloat) { check_relative_transform<float>(13102); }
