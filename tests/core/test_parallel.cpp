// SPDX-License-Identifier: MIT
// parallel_for / parallel_for_ranges (core/parallel.hpp): every index exactly once for every thread
// count, the serial order with one thread, exceptions carried to the caller, nested and concurrent
// calls (which fall back to serial runs) giving the same results. Labelled "concurrency": these also
// run under ThreadSanitizer (IMPACT_TSAN).
#include "impact/core/parallel.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <stdexcept>
#include <thread>
#include <vector>

namespace {

TEST(Parallel, ResolveThreads) {
  EXPECT_GE(impact::hardware_threads(), 1);
  EXPECT_EQ(impact::resolve_threads(0), impact::hardware_threads());
  EXPECT_EQ(impact::resolve_threads(-3), impact::hardware_threads());
  EXPECT_EQ(impact::resolve_threads(1), 1);
  EXPECT_EQ(impact::resolve_threads(5), 5);
}

TEST(Parallel, EveryIndexOnceForEveryThreadCount) {
  for (const std::size_t n : {0u, 1u, 2u, 3u, 7u, 64u, 1000u, 12345u})
    for (const int threads : {0, 1, 2, 3, 8, 17}) {
      std::vector<std::atomic<int>> hits(n);
      for (auto& h : hits) h.store(0);
      impact::parallel_for(n, threads, [&](std::size_t i) { hits[i].fetch_add(1, std::memory_order_relaxed); });
      for (std::size_t i = 0; i < n; ++i) ASSERT_EQ(hits[i].load(), 1) << "n=" << n << " threads=" << threads << " i=" << i;
    }
}

TEST(Parallel, RangesCoverOnceWithinGrain) {
  for (const std::size_t n : {1u, 5u, 100u, 1001u})
    for (const std::size_t grain : {1u, 3u, 64u, 5000u})
      for (const int threads : {1, 2, 3, 8}) {
        std::vector<int> hits(n, 0);  // each index owned by one range: no atomics needed
        impact::parallel_for_ranges(n, grain, threads, [&](std::size_t b, std::size_t e) {
          ASSERT_LT(b, e);
          ASSERT_LE(e - b, grain);
          ASSERT_EQ(b % grain, 0u);
          for (std::size_t i = b; i < e; ++i) ++hits[i];
        });
        for (std::size_t i = 0; i < n; ++i) ASSERT_EQ(hits[i], 1) << "n=" << n << " grain=" << grain << " i=" << i;
      }
}

TEST(Parallel, OneThreadIsTheSerialLoopOnTheCaller) {
  std::vector<std::size_t> order;
  const auto caller = std::this_thread::get_id();
  impact::parallel_for(100, 1, [&](std::size_t i) {
    EXPECT_EQ(std::this_thread::get_id(), caller);
    order.push_back(i);
  });
  ASSERT_EQ(order.size(), 100u);
  for (std::size_t i = 0; i < order.size(); ++i) EXPECT_EQ(order[i], i);
}

TEST(Parallel, UsesSeveralThreadsWhenAsked) {
  // Each index waits until two distinct threads have been seen (or a generous deadline): with
  // two participants both must take part. Fails if the pool never runs a worker.
  std::atomic<int> distinct{0};
  std::atomic<bool> caller_seen{false}, other_seen{false};
  const auto caller = std::this_thread::get_id();
  impact::parallel_for(64, 2, [&](std::size_t) {
    if (std::this_thread::get_id() == caller) {
      if (!caller_seen.exchange(true)) distinct.fetch_add(1);
    } else if (!other_seen.exchange(true)) {
      distinct.fetch_add(1);
    }
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
    while (distinct.load() < 2 && std::chrono::steady_clock::now() < deadline) std::this_thread::yield();
  });
  EXPECT_EQ(distinct.load(), 2);
}

TEST(Parallel, ResultsByIndexDoNotDependOnThreads) {
  const std::size_t n = 5000;
  const auto run = [&](int threads) {
    std::vector<double> out(n);
    impact::parallel_for(n, threads, [&](std::size_t i) {
      double x = double(i) * 0.1;
      for (int k = 0; k < 20; ++k) x = x * 1.000001 + 1.0 / (1.0 + x);
      out[i] = x;
    });
    return out;
  };
  const auto ref = run(1);
  for (const int threads : {2, 3, 8, 0}) EXPECT_EQ(run(threads), ref) << threads;
}

TEST(Parallel, ExceptionReachesTheCaller) {
  for (const int threads : {1, 2, 8}) {
    std::atomic<int> ran{0};
    EXPECT_THROW(impact::parallel_for(1000, threads,
                                      [&](std::size_t i) {
                                        ran.fetch_add(1);
                                        if (i == 17) throw std::runtime_error("boom");
                                      }),
                 std::runtime_error);
    EXPECT_GE(ran.load(), 1);
    // the pool is usable again afterwards
    std::atomic<int> count{0};
    impact::parallel_for(100, threads, [&](std::size_t) { count.fetch_add(1); });
    EXPECT_EQ(count.load(), 100);
  }
}

TEST(Parallel, NestedCallsRunAndGiveTheSameResults) {
  const std::size_t n = 40, m = 50;
  std::vector<std::uint64_t> out(n * m, 0);
  impact::parallel_for(n, 2, [&](std::size_t i) {
    impact::parallel_for(m, 2, [&](std::size_t j) { out[i * m + j] = i * 1000 + j; });
  });
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = 0; j < m; ++j) ASSERT_EQ(out[i * m + j], i * 1000 + j);
}

TEST(Parallel, CallsFromSeveralThreadsAtOnce) {
  const int callers = 4;
  const std::size_t n = 2000;
  std::vector<std::vector<std::uint64_t>> out(callers, std::vector<std::uint64_t>(n, 0));
  std::vector<std::thread> threads;
  for (int c = 0; c < callers; ++c)
    threads.emplace_back([&, c] {
      for (int rep = 0; rep < 20; ++rep)
        impact::parallel_for(n, 2, [&](std::size_t i) { out[std::size_t(c)][i] += i + std::uint64_t(c); });
    });
  for (auto& t : threads) t.join();
  for (int c = 0; c < callers; ++c)
    for (std::size_t i = 0; i < n; ++i) ASSERT_EQ(out[std::size_t(c)][i], 20 * (i + std::uint64_t(c)));
}

}  // namespace
