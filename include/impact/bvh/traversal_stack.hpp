// SPDX-License-Identifier: MIT
/// \file
/// TraversalStack: the explicit stack of the iterative traversals; a fixed array with a heap
/// overflow, so the common case allocates nothing per query.
#pragma once

#include <vector>

namespace impact {

namespace detail {
/// A small fixed stack with a heap overflow, for traversal without per-query allocation in the
/// common case.
template <class T, int N = 256> class TraversalStack {
 public:
  void push(const T& v) {
    if (top_ < N) data_[top_++] = v;
    else overflow_.push_back(v);
  }
  bool empty() const { return top_ == 0 && overflow_.empty(); }
  T pop() {
    if (!overflow_.empty()) {
      T v = overflow_.back();
      overflow_.pop_back();
      return v;
    }
    return data_[--top_];
  }

 private:
  T data_[N];
  int top_ = 0;
  std::vector<T> overflow_;
};
}  // namespace detail

}  // namespace impact
