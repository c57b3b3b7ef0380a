// SPDX-License-Identifier: GPL-3.0-or-later
#include "parallel.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace sdf {

unsigned resolve_threads(unsigned requested) {
  if (requested > 0) return requested;
  unsigned cores = std::thread::hardware_concurrency();
  return cores > 0 ? cores : 1;
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

  auto worker = [&]() {
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

  std::vector<std::thread> pool;
  pool.reserve(threads);
  for (unsigned i = 0; i < threads; ++i) pool.emplace_back(worker);

  bool cancelled = false;
  if (progress) {
    // Report at most every 50 ms: a Python callback is not free, and people read bars slowly.
    std::unique_lock<std::mutex> lock(mutex);
    while (chunks_done.load() < chunks && !stop.load()) {
      changed.wait_for(lock, std::chrono::milliseconds(50));
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
  for (auto& t : pool) t.join();
  if (failure) std::rethrow_exception(failure);
  if (cancelled) throw Cancelled();
}

}  // namespace sdf
