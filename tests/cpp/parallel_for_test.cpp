// SPDX-License-Identifier: GPL-3.0-or-later
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <stdexcept>
#include <thread>
#include <vector>

#include "parallel.h"

namespace sdf {
namespace {

TEST(ParallelFor, VisitsEveryIndexOnce) {
  std::vector<std::atomic<int>> seen(10007);
  parallel_for(seen.size(), 64, 3, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) seen[i]++;
  });
  for (auto& s : seen) EXPECT_EQ(s.load(), 1);
}

TEST(ParallelFor, ProgressIsMonotoneAndEndsAtTheTop) {
  std::vector<double> reported;
  parallel_for(
      400, 1, 2,
      [](std::size_t, std::size_t) { std::this_thread::sleep_for(std::chrono::microseconds(300)); },
      [&](double f) {
        reported.push_back(f);
        return true;
      },
      0.2, 0.8);
  ASSERT_FALSE(reported.empty());
  for (std::size_t i = 1; i < reported.size(); ++i) EXPECT_GE(reported[i], reported[i - 1]);
  EXPECT_GE(reported.front(), 0.2);
  EXPECT_DOUBLE_EQ(reported.back(), 0.8);
}

TEST(ParallelFor, CancelStopsHandingOutWork) {
  std::atomic<int> done{0};
  EXPECT_THROW(parallel_for(
                   100000, 1, 2,
                   [&](std::size_t, std::size_t) {
                     std::this_thread::sleep_for(std::chrono::microseconds(100));
                     ++done;
                   },
                   [](double) { return false; }),
               Cancelled);
  EXPECT_LT(done.load(), 100000);
}

TEST(ParallelFor, WorkerExceptionReachesTheCaller) {
  EXPECT_THROW(parallel_for(1000, 10, 2,
                            [](std::size_t b, std::size_t) {
                              if (b == 500) throw std::runtime_error("boom");
                            }),
               std::runtime_error);
}

}  // namespace
}  // namespace sdf
