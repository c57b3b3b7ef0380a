// SPDX-License-Identifier: GPL-3.0-or-later
// The cast's launch sizes (native/opencl/launch_sizes.h), played out as the cast loop uses
// them (opencl_engine.cpp) for devices of given speeds taking launches from one shared count:
// several devices must finish together.
#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

#include "opencl/launch_sizes.h"

namespace {

// An H200 casts 1.21M faces x 30 rays in about 38 ms; it is filled by 132 x 2048 points.
constexpr std::size_t kPoints = 1206528, kFill = 132 * 2048;
constexpr double kH200 = kPoints / 0.038;  // points a second
constexpr double kWait = 1e-4;             // a launch's own cost (its finish and read-back)

struct Cast {
  std::vector<double> done;  // when each device finished
  double end() const { return *std::max_element(done.begin(), done.end()); }
  double spread() const { return end() - *std::min_element(done.begin(), done.end()); }
};

// Devices of these speeds (points a second) casting kPoints; `shared`: launches sized for
// sharing (false: each device grows its launches as if it were alone, as before).
Cast cast_points(const std::vector<double>& speeds, bool shared = true) {
  const std::size_t n = speeds.size(), devices = shared ? n : 1;
  std::vector<double> free_at(n, 0.0), rates(n, 0.0), took(n, 0.0);
  std::vector<std::size_t> size(n, sdf::cl::first_launch_points(kFill, kPoints, devices));
  const std::size_t floor = size[0] / 4;
  Cast run{std::vector<double>(n, 0.0)};
  for (std::size_t next = 0; next < kPoints;) {
    // The device free first sizes its next launch from its last one, as the loop does once
    // that launch has finished, then takes it.
    const std::size_t d = std::min_element(free_at.begin(), free_at.end()) - free_at.begin();
    if (took[d] > 0.0) {
      rates[d] = size[d] / took[d];
      const double share = shared ? sdf::cl::launch_share(rates.data(), n, d) : 1.0;
      size[d] =
          sdf::cl::next_launch_points(size[d], took[d], 0.1, floor, kPoints - next, devices, share);
    }
    const std::size_t take = std::min(size[d], kPoints - next);
    next += take;
    took[d] = take / speeds[d] + kWait;
    size[d] = take;
    free_at[d] += took[d];
    run.done[d] = free_at[d];
  }
  return run;
}

double ideal(const std::vector<double>& speeds) {
  double sum = 0.0;
  for (double s : speeds) sum += s;
  return kPoints / sum;
}

TEST(LaunchSizes, EqualDevicesFinishTogether) {
  for (std::size_t devices : {2, 3, 4, 8}) {
    const std::vector<double> speeds(devices, kH200);
    const Cast run = cast_points(speeds);
    EXPECT_LT(run.end(), 1.1 * ideal(speeds) + 0.001) << devices << " devices";
    EXPECT_LT(run.spread(), 0.002) << devices << " devices";
  }
  // Sized as for one device, the first done with its first launch took all the rest: the
  // 30 ms cast measured on 2 x H200 where 20 was due.
  const Cast alone = cast_points({kH200, kH200}, false);
  EXPECT_GT(alone.end(), 0.029);
  EXPECT_GT(alone.spread(), 0.005);
}

// Devices of one speed share it evenly; devices of several need the shares weighted by speed
// (split evenly, one device 8x slower of two ended the cast at 63 ms where 40 was due) and a
// first launch small enough (a quarter of an even share: one 16x slower of two, 76 ms for 36).
TEST(LaunchSizes, UnequalDevicesFinishTogether) {
  for (std::size_t devices : {2, 3, 4}) {
    for (double slower : {2.0, 4.0, 8.0, 16.0}) {
      std::vector<double> speeds(devices, kH200);
      speeds[0] = kH200 / slower;
      const Cast run = cast_points(speeds);
      EXPECT_LT(run.end(), 1.15 * ideal(speeds) + 0.001)
          << devices << " devices, one " << slower << "x slower";
    }
  }
}

TEST(LaunchSizes, OneDeviceGrowsTowardTheTarget) {
  using sdf::cl::next_launch_points;
  EXPECT_EQ(sdf::cl::first_launch_points(kFill, kPoints, 1), kFill);
  // 10 ms for a launch of a 100 ms target: 8x at most at once; halved at most; 256 to 2^22.
  EXPECT_EQ(next_launch_points(kFill, 0.01, 0.1, 0, 0, 1, 1.0), 8 * kFill);
  EXPECT_EQ(next_launch_points(1000, 0.05, 0.1, 0, 0, 1, 1.0), 2000u);
  EXPECT_EQ(next_launch_points(1000, 1.0, 0.1, 0, 0, 1, 1.0), 500u);
  EXPECT_EQ(next_launch_points(300, 1.0, 0.1, 0, 0, 1, 1.0), 256u);
  EXPECT_EQ(next_launch_points(1u << 22, 0.001, 0.1, 0, 0, 1, 1.0), 1u << 22);
  // Shared: half the device's share of what is left, not below the floor.
  EXPECT_EQ(next_launch_points(kFill, 0.01, 0.1, 1000, 8 * kFill, 2, 0.5), 2 * kFill);
  EXPECT_EQ(next_launch_points(kFill, 0.01, 0.1, 1000, 0, 2, 0.5), 1000u);
  EXPECT_EQ(sdf::cl::first_launch_points(kFill, kPoints, 2), kPoints / 32);
  EXPECT_EQ(sdf::cl::first_launch_points(kFill, 1000, 2), 4096u);
  // A share that rounds to 1 beside a vastly slower device still caps the launch.
  EXPECT_EQ(next_launch_points(kFill, 0.01, 0.1, 1000, 8 * kFill, 2, 1.0), 4 * kFill);
  const double rates[3] = {1.0, 3.0, 0.0};  // the third has not reported: taken as the asker
  EXPECT_DOUBLE_EQ(sdf::cl::launch_share(rates, 3, 1), 3.0 / 7.0);
  EXPECT_DOUBLE_EQ(sdf::cl::launch_share(rates, 3, 2), 1.0 / 3.0);
}

}  // namespace
