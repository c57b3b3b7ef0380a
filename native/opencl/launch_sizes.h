// SPDX-License-Identifier: GPL-3.0-or-later
// How many points a device's next cast launch takes (opencl_engine.cpp). Pure arithmetic, so
// that a test can play several devices against one another without any.
#pragma once

#include <algorithm>
#include <cstddef>

namespace sdf::cl {

// The first launch: `fill` points (enough to fill the device), but at most a sixteenth of
// the points' even share when several devices cast, and not below 4096: a slow device's first
// launch would otherwise decide when the cast ends (launches grow up to 8x a step after it;
// with a quarter, one device 16x slower of two ended a cast at 76 ms where 36 was due).
inline std::size_t first_launch_points(std::size_t fill, std::size_t points, std::size_t devices) {
  if (devices < 2) return fill;
  return std::max<std::size_t>(4096, std::min(fill, points / (16 * devices)));
}

// The share of the points left that device `me` of `devices` should cast, from each device's
// points a second in its last launch (0: none yet, taken as fast as `me`): its rate over
// their sum. 1 for a single device.
inline double launch_share(const double* rates, std::size_t devices, std::size_t me) {
  if (devices < 2 || !(rates[me] > 0.0)) return devices < 2 ? 1.0 : 1.0 / devices;
  double sum = 0.0;
  for (std::size_t d = 0; d < devices; ++d) sum += rates[d] > 0.0 ? rates[d] : rates[me];
  return rates[me] / sum;
}

// The launch after one of `points` that took `took` seconds: scaled toward `target` seconds
// (by 0.5x to 8x at once, 256 to 2^22 points). Where several devices cast, at most half its
// `share` of the `left` points (guided scheduling, weighted by speed), so that
// they finish together: growing alone, the device done first with its first launch took all
// the rest (2 x H200, 1.21M faces: a 30 ms cast where an even split takes 20). Not below
// `floor` then (a quarter of the first launch: smaller launches add a wait each; a floor of
// 256 points cost 2 ms of waits at 832k faces).
inline std::size_t next_launch_points(std::size_t points, double took, double target,
                                      std::size_t floor, std::size_t left, std::size_t devices,
                                      double share) {
  const double factor = std::clamp(target / std::max(took, 1e-4), 0.5, 8.0);
  std::size_t next =
      std::clamp<std::size_t>(static_cast<std::size_t>(points * factor), 256, 1u << 22);
  if (devices > 1)
    next = std::min(next, std::max(floor, static_cast<std::size_t>(0.5 * share * left)));
  return next;
}

}  // namespace sdf::cl
