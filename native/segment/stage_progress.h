// SPDX-License-Identifier: GPL-3.0-or-later
// Progress and cancellation for the segmentation stage, whose long loops (the max-flow's
// search, the mixture's iterations) run on the calling thread: they ask often, and the
// caller's callback is called at most every 20 ms of them, so that a cancel stops a
// segmentation of a million faces within a few hundredths of a second.
#pragma once

#include <chrono>
#include <functional>

#include "util/parallel.h"

namespace sdf::segment {

// A check the loops call with the fraction of their own work done (an estimate where the
// work's length is not known); it may throw to stop them (Cancelled, or the callback's own
// exception), leaving their outputs unspecified.
using WorkCheck = std::function<void(double)>;

// The check as parallel_for's progress (called on the calling thread; a throw stops it).
inline ProgressFn as_progress(const WorkCheck& check) {
  if (!check) return nullptr;
  return [&check](double fraction) {
    check(fraction);
    return true;
  };
}

class StageProgress {
 public:
  explicit StageProgress(const ProgressFn& progress) : progress_(progress) {}

  // Reports `fraction` of the whole stage now; throws Cancelled if the callback says stop.
  void report(double fraction) {
    if (!progress_) return;
    last_ = Clock::now();
    if (!progress_(fraction)) throw Cancelled();
  }

  // report(), but only when kEvery has passed since the last report: one clock read.
  void poll(double fraction) {
    if (progress_ && Clock::now() - last_ >= kEvery) report(fraction);
  }

  // A check for a step covering [from, to] of the stage (empty without a callback).
  WorkCheck step(double from, double to) {
    if (!progress_) return nullptr;
    return [this, from, to](double done) { poll(from + (to - from) * done); };
  }

 private:
  using Clock = std::chrono::steady_clock;
  static constexpr std::chrono::milliseconds kEvery{20};
  const ProgressFn& progress_;
  Clock::time_point last_ = Clock::now();
};

}  // namespace sdf::segment
