// SPDX-License-Identifier: MIT
/// \file
/// sorted_union: the sorted, duplicate-free union of several lists, on several threads. The batch
/// operations that collect candidates on many threads (each thread its own list) and need them
/// in one canonical order use it instead of concatenating and sorting on the calling thread,
/// which would leave the largest serial step of the batch:
///
///   std::vector<std::vector<Pair>> parts = ...;            // one list per task, any order
///   std::vector<Pair> all = impact::sorted_union(parts, threads);
///
/// Each list is sorted and deduplicated on its own (in parallel), then the value range is cut at
/// splitters sampled from the lists, and each slice is merged from every list by a thread of its
/// own (sorted). The answer is the sorted set of all elements: the same for every thread count, and the
/// same as sorting the concatenation and removing duplicates. The lists in `parts` are left in
/// some order. T needs operator< and operator==.
#pragma once

#include "impact/core/parallel.hpp"

#include <algorithm>
#include <cstddef>
#include <vector>

namespace impact {

template <class T>
std::vector<T> sorted_union(std::vector<std::vector<T>>& parts, int threads) {
  const auto finish = [](std::vector<T>& v) {
    std::sort(v.begin(), v.end());
    v.erase(std::unique(v.begin(), v.end()), v.end());
  };
  std::size_t total = 0;
  for (const auto& p : parts) total += p.size();
  const int t = resolve_threads(threads);
  if (t <= 1 || parts.size() < 2 || total < 8192) {  // below this, one thread sorts faster than the pool starts
    std::vector<T> all;
    all.reserve(total);
    for (const auto& p : parts) all.insert(all.end(), p.begin(), p.end());
    finish(all);
    return all;
  }
  parallel_for(parts.size(), t, [&](std::size_t k) { finish(parts[k]); });
  // Splitters: evenly spaced samples of every list, sorted; slices [split[s], split[s + 1]).
  const std::size_t slices = 4 * static_cast<std::size_t>(t);
  std::vector<T> samples;
  for (const auto& p : parts)
    for (std::size_t k = 1; k < slices; ++k)
      if (!p.empty()) samples.push_back(p[k * p.size() / slices]);
  finish(samples);
  std::vector<T> split;
  for (std::size_t s = 1; s < slices && !samples.empty(); ++s) split.push_back(samples[s * samples.size() / slices]);
  split.erase(std::unique(split.begin(), split.end()), split.end());
  const std::size_t n = split.size() + 1;
  std::vector<std::vector<T>> out(n);
  parallel_for(n, t, [&](std::size_t s) {
    std::vector<T>& o = out[s];
    for (const auto& p : parts) {
      const auto b = s == 0 ? p.begin() : std::lower_bound(p.begin(), p.end(), split[s - 1]);
      const auto e = s + 1 == n ? p.end() : std::lower_bound(p.begin(), p.end(), split[s]);
      o.insert(o.end(), b, e);
    }
    finish(o);
  });
  std::vector<T> all;
  std::size_t size = 0;
  for (const auto& o : out) size += o.size();
  all.reserve(size);
  for (const auto& o : out) all.insert(all.end(), o.begin(), o.end());
  return all;
}

}  // namespace impact
