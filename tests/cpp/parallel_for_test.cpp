// SPDX-License-Identifier: GPL-3.0-or-later
#include <gtest/gtest.h>

#include <atomic>
#include <cfenv>
#include <chrono>
#include <stdexcept>
#include <thread>
#include <vector>

#if defined(__unix__)
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>
#endif

#include "util/parallel.h"

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

// The workers are kept between calls (a pool): calls made from inside a body, and calls from
// several threads at once, must each get their threads without waiting on one another.
TEST(ParallelFor, NestedAndConcurrentCallsAllFinish) {
  std::atomic<long> total{0};
  std::vector<std::thread> callers;
  for (int c = 0; c < 4; ++c)
    callers.emplace_back([&] {
      for (int round = 0; round < 20; ++round)
        parallel_for(64, 1, 8, [&](std::size_t b, std::size_t e) {
          parallel_for(100, 7, 3, [&](std::size_t ib, std::size_t ie) {
            total += static_cast<long>((e - b) * (ie - ib));
          });
        });
    });
  for (std::thread& t : callers) t.join();
  EXPECT_EQ(total.load(), 4L * 20 * 64 * 100);
}

// Workers run in the caller's floating-point environment, as threads the caller started
// would (the pool's threads were started by whichever call came first).
TEST(ParallelFor, WorkersUseTheCallersRoundingMode) {
  parallel_for(64, 1, 4, [](std::size_t, std::size_t) {});  // the pool's threads exist now
  const int before = std::fegetround();
  ASSERT_EQ(std::fesetround(FE_UPWARD), 0);
  std::atomic<int> other{0};
  parallel_for(64, 1, 4, [&](std::size_t, std::size_t) {
    if (std::fegetround() != FE_UPWARD) ++other;
  });
  std::fesetround(before);
  EXPECT_EQ(other.load(), 0);
  // And the workers' own environment is back to what it was.
  parallel_for(64, 1, 4, [&](std::size_t, std::size_t) {
    if (std::fegetround() != before) ++other;
  });
  EXPECT_EQ(other.load(), 0);
}

#if defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer)
#define SDF_SANITIZED_THREADS 1
#endif
#endif
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define SDF_SANITIZED_THREADS 1
#endif

#if defined(__unix__)
// A process forked after the pool has threads (Python's multiprocessing does this) has none
// of them: its own calls must still run, not wait forever for workers that do not exist.
TEST(ParallelFor, WorksInAForkedChild) {
#if defined(SDF_SANITIZED_THREADS)
  // The sanitizers' own allocator is not fork-safe once threads exist: a forked child's new
  // threads were seen blocked inside it (ASan's thread start-up freeing memory), whatever
  // the code under test does. glibc's allocator is; the plain build runs this test.
  GTEST_SKIP() << "fork with threads is not supported under the sanitizers' allocator";
#endif
  std::atomic<long> sum{0};
  parallel_for(1000, 10, 4, [&](std::size_t b, std::size_t e) { sum += static_cast<long>(e - b); });
  ASSERT_EQ(sum.load(), 1000);
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    std::atomic<long> in_child{0};
    parallel_for(1000, 10, 4,
                 [&](std::size_t b, std::size_t e) { in_child += static_cast<long>(e - b); });
    _exit(in_child.load() == 1000 ? 0 : 1);
  }
  // The child is given 20 s; a child stuck waiting for workers is killed and fails the test.
  int status = 0;
  for (int waited = 0; waited < 200 && waitpid(child, &status, WNOHANG) == 0; ++waited)
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  if (waitpid(child, &status, WNOHANG) == 0) {
    kill(child, SIGKILL);
    waitpid(child, &status, 0);
    FAIL() << "the forked child did not finish its parallel_for";
  }
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0);
}
#endif

}  // namespace
}  // namespace sdf
