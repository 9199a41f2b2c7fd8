// SPDX-License-Identifier: MIT
/// \file
/// TraversalStack: the explicit stack of the iterative traversals; a fixed array with a heap
/// overflow, so the common case allocates nothing per query.
#pragma once

#include <new>
#include <type_traits>
#include <vector>

namespace impact {

namespace detail {
/// A small fixed stack with a heap overflow, for traversal without per-query allocation in the
/// common case. The fixed slots are left uninitialised (a query pays only for what it pushes), so
/// T must be trivially destructible.
template <class T, int N = 256> class TraversalStack {
  static_assert(std::is_trivially_destructible_v<T>, "TraversalStack: entries need no destructor");

 public:
  TraversalStack() {}  // NOLINT(modernize-use-equals-default): the slots stay uninitialised
  void push(const T& v) {
    if (top_ < N)
      new (&data_[top_++].value) T(v);
    else overflow_.push_back(v);
  }
  bool empty() const { return top_ == 0; }  // the overflow is used only while the fixed slots are full
  T pop() {
    if (!overflow_.empty()) {
      T v = overflow_.back();
      overflow_.pop_back();
      return v;
    }
    return data_[--top_].value;
  }

 private:
  union Slot {
    Slot() {}  // NOLINT(modernize-use-equals-default): no initialisation
    T value;
  };
  Slot data_[N];
  int top_ = 0;
  std::vector<T> overflow_;
};
}  // namespace detail

}  // namespace impact
