// host/parallel: every index runs once, results land by index whatever the thread count, and the
// exception rethrown is the lowest index's, as a serial loop would meet it.
#include "host/parallel.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <random>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace talus {
namespace {

TEST(Parallel, EveryIndexRunsOnceAndTheResultsDoNotDependOnTheThreadCount) {
  const std::size_t n = 1000;
  // a result per index that takes a varying amount of work, so threads finish out of order
  auto result_of = [](std::size_t i) {
    std::mt19937_64 rng(i);
    double x = 0.0;
    for (std::size_t k = 0; k < 50 + (i * 7919) % 400; ++k)
      x += std::generate_canonical<double, 53>(rng);
    return x;
  };
  std::vector<double> serial(n);
  for (std::size_t i = 0; i < n; ++i) serial[i] = result_of(i);
  for (int threads : {1, 2, 3, 8}) {
    std::vector<double> out(n, -1.0);
    std::vector<std::atomic<int>> runs(n);
    parallel_for(n, threads, [&](std::size_t i) {
      out[i] = result_of(i);
      ++runs[i];
    });
    for (std::size_t i = 0; i < n; ++i) {
      ASSERT_EQ(runs[i].load(), 1) << "index " << i << ", " << threads << " threads";
      ASSERT_EQ(out[i], serial[i]) << "index " << i << ", " << threads << " threads";
    }
  }
}

TEST(Parallel, OneThreadIsAPlainLoopOnTheCallersThread) {
  const std::thread::id caller = std::this_thread::get_id();
  std::vector<std::size_t> order;
  parallel_for(5, 1, [&](std::size_t i) {
    EXPECT_EQ(std::this_thread::get_id(), caller);
    order.push_back(i);
  });
  EXPECT_EQ(order, (std::vector<std::size_t>{0, 1, 2, 3, 4}));
  // no task: nothing runs, nothing throws
  parallel_for(0, 4, [](std::size_t) { FAIL() << "a task ran"; });
}

TEST(Parallel, TheLowestIndexsExceptionIsRethrownAfterEveryTaskRan) {
  for (int threads : {1, 2, 4}) {
    std::atomic<int> ran{0};
    try {
      parallel_for(40, threads, [&](std::size_t i) {
        ++ran;
        if (i == 31 || i == 17 || i == 23) throw std::runtime_error("task " + std::to_string(i));
      });
      FAIL() << "nothing thrown";
    } catch (const std::runtime_error& e) {
      EXPECT_STREQ(e.what(), "task 17") << threads << " threads";
    }
    EXPECT_EQ(ran.load(), 40) << threads << " threads";
  }
  EXPECT_GE(hardware_threads(), 1);
}

}  // namespace
}  // namespace talus
