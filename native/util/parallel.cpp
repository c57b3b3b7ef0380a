// SPDX-License-Identifier: GPL-3.0-or-later
#include "util/parallel.h"

#include <algorithm>
#include <atomic>
#include <cfenv>
#include <chrono>
#include <condition_variable>
#include <exception>
#include <mutex>
#include <system_error>
#include <thread>
#include <vector>

#if defined(__unix__) || defined(__APPLE__)
#include <pthread.h>
#endif
#if defined(__linux__)
#include <sched.h>
#endif

namespace sdf {

namespace {

// Worker threads kept between calls. Starting a thread costs tens of microseconds, and one
// compute() makes dozens of parallel_for calls of up to a thread per core: 0.55 ms per call
// at 16 threads (measured on 2 cores), several percent of a GPU run on a million faces.
// A call gets all the threads it asks for at once: idle ones, and new ones when too few are
// idle (so calls from several threads, or from inside a body, never wait on each other).
// A thread idle for kIdleSeconds ends, so a burst of calls (or one asking for thousands of
// threads) leaves nothing behind for long.
class WorkerPool {
 public:
  // A task for up to `count` workers: each runs *work once, in the caller's floating-point
  // environment (rounding, flush-to-zero), as a thread started by the caller would.
  struct Job {
    const std::function<void()>* work = nullptr;
    std::fenv_t environment;
    unsigned unclaimed = 0;  // guarded by the pool's mutex
    unsigned running = 0;    // guarded by finished_mutex
    std::mutex finished_mutex;
    std::condition_variable finished;
  };

  // Hands `job` to up to `count` threads and returns how many took it: fewer (down to 0) only
  // when the system refuses new threads, and the caller then does the rest of the work.
  unsigned start(Job& job, unsigned count) {
    std::fegetenv(&job.environment);
    std::lock_guard<std::mutex> lock(mutex_);
    try {
      while (available_ < unclaimed_ + count) {
        std::thread(&WorkerPool::serve, this).detach();
        ++available_;
      }
    } catch (const std::system_error&) {
      count = available_ > unclaimed_ ? std::min(count, available_ - unclaimed_) : 0;
    }
    if (count == 0) return 0;
    job.running = count;  // no worker sees the job before it is queued below
    job.unclaimed = count;
    queue_.push_back(&job);
    unclaimed_ += count;
    for (unsigned i = 0; i < count; ++i) wake_.notify_one();
    return count;
  }

  // Returns once every worker that took `job` has finished its run.
  static void wait(Job& job) {
    std::unique_lock<std::mutex> lock(job.finished_mutex);
    job.finished.wait(lock, [&] { return job.running == 0; });
  }

 private:
  static constexpr int kIdleSeconds = 10;

  void serve() {
    std::unique_lock<std::mutex> lock(mutex_);
    for (;;) {
      if (!wake_.wait_for(lock, std::chrono::seconds(kIdleSeconds),
                          [&] { return !queue_.empty(); })) {
        // Idle too long; a claim left now still has a thread for it (available_ counts it).
        if (available_ > unclaimed_) {
          --available_;
          return;
        }
        continue;
      }
      Job* job = queue_.front();
      if (--job->unclaimed == 0) queue_.erase(queue_.begin());
      --unclaimed_;
      --available_;
      lock.unlock();
      std::fenv_t own;
      std::fegetenv(&own);
      std::fesetenv(&job->environment);
      (*job->work)();
      std::fesetenv(&own);
      {
        std::lock_guard<std::mutex> done(job->finished_mutex);
        if (--job->running == 0) job->finished.notify_all();
      }
      lock.lock();
      ++available_;
    }
  }

  std::mutex mutex_;
  std::condition_variable wake_;
  std::vector<Job*> queue_;  // jobs with claims left, oldest first
  unsigned unclaimed_ = 0;   // claims left over all queued jobs
  unsigned available_ = 0;   // threads waiting for a claim or on their way to wait
};

// Never destroyed: its threads may still be waiting when the process exits. A child process
// made by fork() has none of them, so it starts a pool of its own.
WorkerPool* pool = new WorkerPool();

// available_cores() once a process: 0 until read, and again in a forked child (a Pool's
// initializer may pin its worker before the worker's first use).
std::atomic<unsigned> cores_read{0};

#if defined(__unix__) || defined(__APPLE__)
const bool fork_handler_set = [] {
  pthread_atfork(nullptr, nullptr, [] {
    pool = new WorkerPool();
    cores_read.store(0, std::memory_order_relaxed);
  });
  return true;
}();
#endif

// The CPUs this process may run on: its affinity (taskset, a container's or a farm slot's
// cpuset), which hardware_concurrency ignores (a slot pinned to 1 of 2 cores ran 2
// threads; pinned to 4 of 64, it would run 64). Read at a process's first use (below).
unsigned available_cores() {
#if defined(__linux__)
  cpu_set_t set;
  if (sched_getaffinity(0, sizeof set, &set) == 0 && CPU_COUNT(&set) > 0)
    return static_cast<unsigned>(CPU_COUNT(&set));
#endif
  const unsigned cores = std::thread::hardware_concurrency();  // (more than 1024 CPUs, too)
  return cores > 0 ? cores : 1;
}

}  // namespace

unsigned resolve_threads(unsigned requested) {
  if (requested > 0) return requested;
  unsigned cores = cores_read.load(std::memory_order_relaxed);
  if (cores == 0) {
    cores = available_cores();
    cores_read.store(cores, std::memory_order_relaxed);
  }
  return cores;
}

void parallel_for(std::size_t n, std::size_t grain, unsigned threads,
                  const std::function<void(std::size_t, std::size_t)>& body,
                  const ProgressFn& progress, double progress_from, double progress_to) {
  if (n == 0) return;
  grain = std::max<std::size_t>(grain, 1);
  const std::size_t chunks = (n + grain - 1) / grain;
  threads = static_cast<unsigned>(std::min<std::size_t>(resolve_threads(threads), chunks));

  std::atomic<std::size_t> next_chunk{0};
  std::atomic<std::size_t> chunks_done{0};
  std::atomic<bool> stop{false};
  std::exception_ptr failure;
  std::mutex mutex;
  std::condition_variable changed;

  const std::function<void()> worker = [&]() {
    for (;;) {
      if (stop.load(std::memory_order_relaxed)) break;
      const std::size_t chunk = next_chunk.fetch_add(1);
      if (chunk >= chunks) break;
      const std::size_t begin = chunk * grain;
      try {
        body(begin, std::min(n, begin + grain));
      } catch (...) {
        std::lock_guard<std::mutex> lock(mutex);
        if (!failure) failure = std::current_exception();
        stop = true;
      }
      chunks_done.fetch_add(1);
      changed.notify_one();
    }
    changed.notify_one();
  };

  WorkerPool::Job job;
  job.work = &worker;
  // Without a thread to take it (the system refusing threads), the caller works instead.
  if (pool->start(job, threads) == 0) worker();

  bool cancelled = false;
  if (progress) {
    // Report at most every 50 ms (and after the first chunk and the last): a Python callback
    // is not free (it takes the GIL, and runs Python's signal handlers), and people read bars
    // slowly. Workers wake this thread at every chunk: 4,700 reports for a 1.2M-point cast.
    using Clock = std::chrono::steady_clock;
    constexpr auto kEvery = std::chrono::milliseconds(50);
    Clock::time_point last = Clock::now() - kEvery;  // the first wake reports
    std::unique_lock<std::mutex> lock(mutex);
    while (chunks_done.load() < chunks && !stop.load()) {
      changed.wait_for(lock, kEvery);
      // (The end is always reported: callers' bars reach their top.)
      if (Clock::now() - last < kEvery && chunks_done.load() < chunks) continue;
      last = Clock::now();
      lock.unlock();
      const double fraction = static_cast<double>(chunks_done.load()) / chunks;
      bool keep_going = true;
      try {
        keep_going = progress(progress_from + (progress_to - progress_from) * fraction);
      } catch (...) {
        std::lock_guard<std::mutex> guard(mutex);
        if (!failure) failure = std::current_exception();
        keep_going = false;
      }
      lock.lock();
      if (!keep_going) {
        cancelled = true;
        stop = true;
      }
    }
  }
  WorkerPool::wait(job);
  if (failure) std::rethrow_exception(failure);
  if (cancelled) throw Cancelled();
}

}  // namespace sdf
