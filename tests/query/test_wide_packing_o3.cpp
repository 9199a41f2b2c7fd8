// SPDX-License-Identifier: MIT
// The WideBvh's choice of float triangle blocks, compiled at -O3 (its own executable: the other
// tests compile at -O1, where the optimizer transforms less): a double mesh is stored as floats
// only when every coordinate is exactly a float (detail::is_float_exact, decided on the bits),
// checked against closed forms at the edges of float's range and against a round trip through a
// volatile float, and on meshes with one coordinate off the float grid in each of the nine slots
// of a triangle: the tree must keep those in double, with the mesh's own coordinates.
#include "impact/bvh/wide_bvh.hpp"
#include "impact/geometry/mesh_generators.hpp"

#include <gtest/gtest.h>

#include <cfloat>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>

namespace impact {
namespace {

// the reference: a store to a volatile float rounds to float whatever the optimizer keeps in
// registers, and the load back is exact
bool packing_round_trip(double x) {
  volatile float f = static_cast<float>(x);
  const double back = f;
  return back == x;
}

TEST(WidePackingO3, FloatExactnessClosedForms) {
  using detail::is_float_exact;
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_TRUE(is_float_exact(0.0));
  EXPECT_TRUE(is_float_exact(-0.0));
  EXPECT_TRUE(is_float_exact(1.0));
  EXPECT_TRUE(is_float_exact(1.0 + 0x1p-23));
  EXPECT_FALSE(is_float_exact(1.0 + 0x1p-24));
  EXPECT_FALSE(is_float_exact(1.0 + 0x1p-52));
  EXPECT_FALSE(is_float_exact(0.1));
  EXPECT_TRUE(is_float_exact(double(0.1f)));
  EXPECT_TRUE(is_float_exact(-double(0.1f)));
  EXPECT_TRUE(is_float_exact(double(FLT_MAX)));
  EXPECT_FALSE(is_float_exact(std::nextafter(double(FLT_MAX), inf)));
  EXPECT_FALSE(is_float_exact(0x1p128));
  EXPECT_TRUE(is_float_exact(double(FLT_MIN)));               // 2^-126, the smallest normal
  EXPECT_TRUE(is_float_exact(0x1p-149));                      // the smallest subnormal
  EXPECT_TRUE(is_float_exact(3 * 0x1p-149));
  EXPECT_FALSE(is_float_exact(0x1p-150));
  EXPECT_FALSE(is_float_exact(3 * 0x1p-150));
  EXPECT_TRUE(is_float_exact(0x1p-127 + 0x1p-149));            // subnormal, lowest bit set
  EXPECT_FALSE(is_float_exact(0x1p-127 + 0x1p-150));
  EXPECT_FALSE(is_float_exact(std::numeric_limits<double>::denorm_min()));
  EXPECT_FALSE(is_float_exact(std::numeric_limits<double>::min()));
  EXPECT_TRUE(is_float_exact(inf));
  EXPECT_TRUE(is_float_exact(-inf));
  EXPECT_FALSE(is_float_exact(std::numeric_limits<double>::quiet_NaN()));
}

TEST(WidePackingO3, FloatExactnessMatchesRoundTrip) {
  std::mt19937_64 gen(7);
  long floats = 0;
  for (int i = 0; i < 200000; ++i) {
    double x;
    switch (i % 4) {
      case 0: {  // any bits (NaN included)
        const std::uint64_t b = gen();
        std::memcpy(&x, &b, sizeof x);
        break;
      }
      case 1:  // floats of every exponent, and their neighbours
        x = double(std::ldexp(float(gen() >> 40), int(gen() % 300) - 170));
        if (gen() % 2) x = std::nextafter(x, (gen() % 2) ? 1e300 : -1e300);
        break;
      case 2:  // floats' midpoints and quarter points (off the float grid by less than an ulp)
        x = std::ldexp(double((gen() >> 38) | 1) / 4, int(gen() % 280) - 160);
        break;
      default:  // ordinary coordinates
        x = std::ldexp(double(gen() >> 11) * 0x1p-53 - 0.5, int(gen() % 40) - 20);
    }
    const bool ref = packing_round_trip(x);
    floats += ref ? 1 : 0;
    ASSERT_EQ(detail::is_float_exact(x), ref) << std::hexfloat << x;
  }
  EXPECT_GT(floats, 30000);  // both answers are exercised
  EXPECT_LT(floats, 160000);
}

TEST(WidePackingO3, OffGridCoordinateKeepsDoubleBlocks) {
  TriangleMesh<double> mesh = make_torus<double>(1.0, 0.4, 8, 5);
  for (int i = 0; i < mesh.num_vertices(); ++i)
    for (int c = 0; c < 3; ++c) mesh.V(i, c) = double(float(mesh.V(i, c)));
  const WideBvh<double, 8> on_grid(mesh);
  EXPECT_TRUE(on_grid.packed());
  // one coordinate off the float grid (by a double ulp, or half a float ulp) in each slot of
  // the triangles of several vertices, first and last in leaf order included
  int cases = 0;
  for (int v = 0; v < mesh.num_vertices(); v += 7) {
    for (int c = 0; c < 3; ++c) {
      for (int how = 0; how < 2; ++how) {
        TriangleMesh<double> off = mesh;
        const double x = off.V(v, c);
        const double step = how == 0 ? std::abs(x) * 0x1p-52 : std::abs(x) * 0x1p-25;
        off.V(v, c) = x == 0.0 ? 0x1p-60 * (1.0 + 0x1p-40) : x + step;
        ASSERT_FALSE(detail::is_float_exact(off.V(v, c)));
        const WideBvh<double, 8> w(off);
        EXPECT_FALSE(w.packed()) << v << " " << c << " " << how;
        for (std::int32_t k = 0; k < w.num_triangles(); ++k) {
          const Triangle<double> t = off.triangle(w.triangle_id(k));
          const Triangle<double> s = w.triangle(k);
          ASSERT_TRUE(s.a == t.a && s.b == t.b && s.c == t.c) << v << " " << c << " " << k;
        }
        ++cases;
      }
    }
  }
  EXPECT_GE(cases, 30);
}

}  // namespace
}  // namespace impact
