// SPDX-License-Identifier: MIT
/// \file
/// The bit spreading of Morton (Z-order) codes, three coordinates of up to 21 bits each (63 bits):
/// shared by the bottom-up BVH build (bvh/build_bottom_up.hpp), the particles' spatial order
/// (response/particle_step.hpp) and the broad phase's query order (broad/static_candidates.hpp,
/// 10 bits per coordinate). Each caller quantises its coordinates its own way and interleaves
/// them as spread_bits_3(q_x) | spread_bits_3(q_y) << 1 | spread_bits_3(q_z) << 2.
#pragma once

#include <cstdint>

namespace impact::detail {

/// Spreads the low 21 bits of x to every third bit of a 64-bit word (bit i goes to bit 3 i); the
/// higher bits of x are ignored. Exact integer arithmetic, five shift-and-mask rounds.
inline std::uint64_t spread_bits_3(std::uint64_t x) {
  x &= 0x1fffff;
  x = (x | x << 32) & 0x1f00000000ffffull;
  x = (x | x << 16) & 0x1f0000ff0000ffull;
  x = (x | x << 8) & 0x100f00f00f00f00full;
  x = (x | x << 4) & 0x10c30c30c30c30c3ull;
  x = (x | x << 2) & 0x1249249249249249ull;
  return x;
}

}  // namespace impact::detail
