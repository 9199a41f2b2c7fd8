// SPDX-License-Identifier: MIT
// Decoding of fuzzer input bytes into small values, and the failure report of the fuzz targets.
// A target that finds a disagreement prints it and aborts, which libFuzzer records as a crash and
// the replay test (replay_main.cpp) as a failed test.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

namespace impact::fuzz {

/// Reads bytes from the front of the input; past the end it yields zeros.
class Input {
 public:
  Input(const std::uint8_t* data, std::size_t size) : p_(data), end_(data + size) {}
  std::uint8_t byte() { return p_ < end_ ? *p_++ : 0; }
  std::uint16_t u16() { return static_cast<std::uint16_t>(byte() | (byte() << 8)); }
  std::uint32_t u32() { return static_cast<std::uint32_t>(u16()) | (static_cast<std::uint32_t>(u16()) << 16); }
  /// An integer in [lo, hi] (hi - lo < 2^32).
  std::int64_t range(std::int64_t lo, std::int64_t hi) {
    const std::uint64_t span = static_cast<std::uint64_t>(hi - lo) + 1;
    const std::uint64_t x = span <= 256 ? byte() : span <= 65536 ? u16() : u32();
    return lo + static_cast<std::int64_t>(x % span);
  }
  bool flag() { return (byte() & 1u) != 0; }
  std::size_t left() const { return static_cast<std::size_t>(end_ - p_); }

 private:
  const std::uint8_t* p_;
  const std::uint8_t* end_;
};

/// Reports a disagreement and aborts (a crash for libFuzzer, a failure for the replay test).
[[noreturn]] inline void fail(const std::string& what) {
  std::fprintf(stderr, "impact fuzz: %s\n", what.c_str());
  std::fflush(stderr);
  std::abort();
}

}  // namespace impact::fuzz
