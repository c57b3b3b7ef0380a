// SPDX-License-Identifier: GPL-3.0-or-later
// Work split into chunks over a few threads, with progress and cancellation between chunks.
#pragma once

#include <cstddef>
#include <functional>
#include <stdexcept>

namespace sdf {

// Called with the fraction done, in [0, 1], on the thread that called the computation (so a
// Python callback needs no extra locking). Returning false cancels the work.
using ProgressFn = std::function<bool(double)>;

// Thrown when a progress callback asked to stop.
struct Cancelled : std::runtime_error {
  Cancelled() : std::runtime_error("computation cancelled") {}
};

// Number of worker threads to use when the caller asks for `requested` (0 = every core).
unsigned resolve_threads(unsigned requested);

// Runs body(begin, end) over [0, n) in chunks of `grain` items on `threads` workers. The
// calling thread only watches: it reports progress as chunks finish (the fraction maps to
// [progress_from, progress_to]) and stops handing out chunks once progress returns false, then
// throws Cancelled. An exception thrown by body stops the other workers and is rethrown here.
void parallel_for(std::size_t n, std::size_t grain, unsigned threads,
                  const std::function<void(std::size_t, std::size_t)>& body,
                  const ProgressFn& progress = nullptr, double progress_from = 0.0,
                  double progress_to = 1.0);

}  // namespace sdf
