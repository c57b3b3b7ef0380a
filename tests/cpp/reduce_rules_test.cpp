// SPDX-License-Identifier: GPL-3.0-or-later
#include <gtest/gtest.h>

#include <vector>

#include "ray/sdf_reduce.h"

namespace sdf {
namespace {

float reduce(int sampling, std::vector<float> lengths, std::vector<float> angles, float floor) {
  return kern::sdf_reduce(sampling, lengths.data(), angles.data(), static_cast<int>(lengths.size()),
                          floor);
}

TEST(ReducePaper, DropsOutliersAndWeighsByInverseAngle) {
  // Median 2.0, population std of {1.9, 2, 2.1, 10} is 3.46: 10 lies beyond the std -> dropped.
  // Kept: 1.9 (angle 0.1), 2.0 (0.2), 2.1 (0.4); weights 10, 5, 2.5.
  const float v =
      reduce(SDF_SAMPLING_FIBONACCI, {10.0f, 2.0f, 1.9f, 2.1f}, {0.3f, 0.2f, 0.1f, 0.4f}, 0.01f);
  EXPECT_NEAR(v, (1.9f * 10 + 2.0f * 5 + 2.1f * 2.5f) / 17.5f, 1e-6f);
}

TEST(ReducePaper, FloorsTheAngleOfAnOnAxisRay) {
  // An on-axis ray (angle 0) weighs as a ray at the floor angle, not infinitely.
  const float v = reduce(SDF_SAMPLING_RANDOM, {1.0f, 1.2f}, {0.0f, 0.5f}, 0.25f);
  EXPECT_NEAR(v, (1.0f * 4 + 1.2f * 2) / 6.0f, 1e-6f);
}

TEST(ReducePaper, EmptyAndSingle) {
  EXPECT_EQ(reduce(SDF_SAMPLING_FIBONACCI, {}, {}, 0.1f), -1.0f);
  EXPECT_FLOAT_EQ(reduce(SDF_SAMPLING_FIBONACCI, {3.5f}, {0.2f}, 0.1f), 3.5f);
}

TEST(ReduceCgal, KeepsWithinOneAndAHalfMedianAbsoluteDeviations) {
  // Median 2.05 (even count), deviations {0.05, 0.05, 0.15, 0.15, 1.95, 3.95} -> MAD 0.15;
  // keep |d - 2.05| <= 0.225: 1.9, 2.0, 2.1, 2.2 -> mean 2.05.
  const float v =
      reduce(SDF_SAMPLING_CGAL, {2.0f, 6.0f, 1.9f, 4.0f, 2.1f, 2.2f}, {0, 0, 0, 0, 0, 0}, 0.0f);
  EXPECT_NEAR(v, 2.05f, 1e-5f);
  EXPECT_FLOAT_EQ(reduce(SDF_SAMPLING_CGAL, {7.0f}, {0.0f}, 0.0f), 7.0f);
}

}  // namespace
}  // namespace sdf
