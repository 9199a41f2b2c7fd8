// SPDX-License-Identifier: MIT
/// \file
/// Revision stamps: process-wide unique 64-bit numbers that an editable structure takes on
/// construction and on every edit (MeshBvh::revision), so that a cache keyed to it (the
/// particles' free balls, response/detail/particle_step_context.hpp) sees an edit made in place, at the same
/// address, without comparing contents.
#pragma once

#include <atomic>
#include <cstdint>

namespace impact::detail {

/// A number no earlier call returned in this process (never 0): one relaxed atomic increment, safe
/// from any number of threads. 2^64 stamps do not wrap in practice.
inline std::uint64_t next_revision() {
  static std::atomic<std::uint64_t> counter{0};
  return counter.fetch_add(1, std::memory_order_relaxed) + 1;
}

}  // namespace impact::detail
