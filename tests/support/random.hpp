// SPDX-License-Identifier: MIT
// Seeded, platform-independent random numbers for tests and benches: std::mt19937_64's output is
// fixed by the standard, but the standard distributions are not, so uniform reals are made here.
#pragma once

#include "impact/geometry/transform.hpp"

#include <cmath>
#include <cstdint>
#include <random>

namespace impact::test {

class Rng {
 public:
  explicit Rng(std::uint64_t seed) : gen_(seed) {}
  /// Uniform in [0, 1) with 53 random bits.
  double uniform() { return double(gen_() >> 11) * 0x1.0p-53; }
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  /// Uniform integer in [0, n).
  std::uint64_t index(std::uint64_t n) { return gen_() % n; }
  /// Uniform integer in [-r, r].
  std::int64_t integer(std::int64_t r) { return std::int64_t(index(std::uint64_t(2 * r + 1))) - r; }
  Eigen::Vector3d vec(double lo, double hi) { return {uniform(lo, hi), uniform(lo, hi), uniform(lo, hi)}; }
  Eigen::Vector3d in_box(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
    return {uniform(lo.x(), hi.x()), uniform(lo.y(), hi.y()), uniform(lo.z(), hi.z())};
  }
  /// Uniformly distributed rotation (Shoemake's method on unit quaternions).
  Eigen::Matrix3d rotation() {
    const double u1 = uniform(), u2 = uniform() * 2 * M_PI, u3 = uniform() * 2 * M_PI;
    const double a = std::sqrt(1 - u1), b = std::sqrt(u1);
    Eigen::Quaterniond q(b * std::cos(u3), a * std::sin(u2), a * std::cos(u2), b * std::sin(u3));
    return q.normalized().toRotationMatrix();
  }
  std::uint64_t raw() { return gen_(); }

 private:
  std::mt19937_64 gen_;
};

/// A random rigid pose: uniform rotation, translation uniform in the box [lo, hi].
inline RigidTransform<double> random_pose(Rng& rng, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  return {rng.rotation(), rng.in_box(lo, hi)};
}

}  // namespace impact::test
