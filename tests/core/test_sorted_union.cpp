// SPDX-License-Identifier: MIT
// sorted_union (core/sorted_union.hpp): the sorted set of every element of every list, equal to
// sorting the concatenation and removing duplicates, for every thread count; lists that are
// empty, hold duplicates of each other, or all the same value (splitters that coincide), sizes
// on both sides of the serial cut-off. Labelled "concurrency": also run under ThreadSanitizer.
#include "impact/core/sorted_union.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <random>
#include <vector>

namespace {

using Item = std::array<std::int32_t, 3>;
using Lists = std::vector<std::vector<Item>>;

std::vector<Item> reference(const Lists& parts) {
  std::vector<Item> all;
  for (const auto& p : parts) all.insert(all.end(), p.begin(), p.end());
  std::sort(all.begin(), all.end());
  all.erase(std::unique(all.begin(), all.end()), all.end());
  return all;
}

Lists random_lists(std::mt19937& rng, std::size_t lists, std::size_t size, std::int32_t range) {
  std::uniform_int_distribution<std::int32_t> v(0, range);
  std::uniform_int_distribution<std::size_t> len(0, 2 * size);
  Lists parts(lists);
  for (auto& p : parts) {
    p.resize(len(rng));
    for (auto& x : p) x = {v(rng), v(rng) / 3, v(rng) % 5};
  }
  return parts;
}

TEST(SortedUnion, EqualsSortingTheConcatenationForEveryThreadCount) {
  std::mt19937 rng(5);
  for (const std::size_t lists : {1u, 2u, 7u, 32u})
    for (const std::size_t size : {0u, 10u, 400u, 6000u})
      for (const std::int32_t range : {0, 3, 100, 1000000}) {
        const Lists parts = random_lists(rng, lists, size, range);
        const std::vector<Item> want = reference(parts);
        for (const int threads : {1, 2, 3, 8}) {
          Lists copy = parts;
          ASSERT_EQ(impact::sorted_union(copy, threads), want)
              << lists << " lists of about " << size << ", range " << range << ", " << threads << " threads";
        }
      }
}

TEST(SortedUnion, ListsThatRepeatEachOtherAndEmptyOnes) {
  std::mt19937 rng(11);
  Lists parts = random_lists(rng, 1, 20000, 50000);
  parts.push_back(parts[0]);  // a duplicate of every element
  parts.emplace_back();       // empty lists among them
  parts.insert(parts.begin(), std::vector<Item>());
  std::reverse(parts[1].begin(), parts[1].end());
  parts.push_back(std::vector<Item>(30000, Item{7, 7, 7}));  // one value many times
  const std::vector<Item> want = reference(parts);
  for (const int threads : {1, 2, 4}) {
    Lists copy = parts;
    EXPECT_EQ(impact::sorted_union(copy, threads), want) << threads << " threads";
  }
  Lists none;
  EXPECT_TRUE(impact::sorted_union(none, 2).empty());
  Lists all_same(6, std::vector<Item>(5000, Item{1, 2, 3}));
  EXPECT_EQ(impact::sorted_union(all_same, 3), std::vector<Item>{Item({1, 2, 3})});
}

}  // namespace
