// SPDX-License-Identifier: MIT
/// \file
/// TraversalStack: the explicit stack of the iterative traversals; a fixed array, with a heap
/// overflow or (for a caller that bounds its depth) without one, so the common case allocates
/// nothing per query.
#pragma once

#include "impact/core/config.hpp"

#include <cstddef>
#include <new>
#include <type_traits>
#include <vector>

namespace impact {

namespace detail {

/// Asks the processor to bring in the `bytes` bytes from p (a hint, one per cache line of 64
/// bytes; nothing where the compiler offers none). The pair traversals issue it for a node pair's
/// children while the pair's own test runs, so that a descent's misses overlap with its tests.
inline void prefetch_bytes(const void* p, std::size_t bytes) {
#if defined(__GNUC__) || defined(__clang__)
  const char* c = static_cast<const char*>(p);
  for (std::size_t k = 0; k < bytes; k += 64) __builtin_prefetch(c + k);
  __builtin_prefetch(c + bytes - 1);
#else
  (void)p;
  (void)bytes;
#endif
}

/// What a TraversalStack does when its N fixed slots are full.
enum class StackOverflow {
  Heap,  ///< further entries go to a heap vector (any depth)
  None,  ///< no overflow: the caller guarantees at most N entries (checked by IMPACT_ASSERT only)
};

/// A small fixed stack, for traversal without per-query allocation in the common case: with
/// StackOverflow::Heap, entries beyond the N fixed slots go to a heap vector; with
/// StackOverflow::None, there are only the slots (a push is one store; the caller bounds the
/// depth, e.g. by its tree's). The fixed slots are left uninitialised (a query pays only for what
/// it pushes), so T must be trivially destructible.
template <class T, int N = 256, StackOverflow Overflow = StackOverflow::Heap> class TraversalStack {
  static_assert(std::is_trivially_destructible_v<T>, "TraversalStack: entries need no destructor");
  static constexpr bool kHeap = Overflow == StackOverflow::Heap;

 public:
  TraversalStack() {}  // NOLINT(modernize-use-equals-default): the slots stay uninitialised
  void push(const T& v) {
    if constexpr (kHeap) {
      if (top_ < N)
        new (&data_[top_++].value) T(v);
      else overflow_.push_back(v);
    } else {
      IMPACT_ASSERT(top_ < N);
      new (&data_[top_++].value) T(v);
    }
  }
  bool empty() const { return top_ == 0; }  // the overflow is used only while the fixed slots are full
  T pop() {
    if constexpr (kHeap) {
      if (!overflow_.empty()) {
        T v = overflow_.back();
        overflow_.pop_back();
        return v;
      }
    }
    return data_[--top_].value;
  }

 private:
  union Slot {
    Slot() {}  // NOLINT(modernize-use-equals-default): no initialisation
    T value;
  };
  struct NoOverflow {};
  Slot data_[N];
  int top_ = 0;
  std::conditional_t<kHeap, std::vector<T>, NoOverflow> overflow_;
};
}  // namespace detail

}  // namespace impact
