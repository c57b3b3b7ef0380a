// SPDX-License-Identifier: GPL-3.0-or-later
// Seconds between laps, for the stage timings the API reports.
#pragma once

#include <chrono>
#include <string>
#include <utility>
#include <vector>

namespace sdf {

class Stopwatch {
 public:
  // Seconds since the previous lap (or since construction).
  double lap() {
    const auto now = std::chrono::steady_clock::now();
    const double s = std::chrono::duration<double>(now - last_).count();
    last_ = now;
    return s;
  }

 private:
  std::chrono::steady_clock::time_point last_ = std::chrono::steady_clock::now();
};

// Seconds per named stage, in the order they ran.
using StageTimings = std::vector<std::pair<std::string, double>>;

// Appends each lap to `timings` under a name; does nothing without `timings` (the stages of a
// call that reports none cost nothing).
class StageClock {
 public:
  explicit StageClock(StageTimings* timings) : timings_(timings) {}
  void lap(const char* stage) {
    if (timings_) timings_->emplace_back(stage, watch_.lap());
  }

 private:
  StageTimings* timings_;
  Stopwatch watch_;
};

// Adds seconds to `stage` (a stage run again, e.g. per iteration, sums); nothing when times
// is null.
inline void add_time(StageTimings* times, const std::string& stage, double seconds) {
  if (!times) return;
  for (auto& [name, total] : *times)
    if (name == stage) {
      total += seconds;
      return;
    }
  times->emplace_back(stage, seconds);
}

}  // namespace sdf
