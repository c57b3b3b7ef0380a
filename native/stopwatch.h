// SPDX-License-Identifier: GPL-3.0-or-later
// Seconds between laps, for the stage timings the API reports.
#pragma once

#include <chrono>

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

}  // namespace sdf
