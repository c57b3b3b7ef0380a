// SPDX-License-Identifier: GPL-3.0-or-later
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <vector>

#include "prepare/rays.h"

namespace sdf {
namespace {

constexpr float kPi = 3.14159265f;

class ConeRays : public ::testing::TestWithParam<Sampling> {};

TEST_P(ConeRays, UnitDirectionsInsideTheCone) {
  const std::vector<glm::vec3> axes = {{0, 0, 1},
                                       {0, 0, -1},
                                       {1, 0, 0},
                                       {0, -1, 0},
                                       glm::normalize(glm::vec3(1, 2, 3)),
                                       glm::normalize(glm::vec3(-1e-4f, 1e-4f, -1))};
  for (double cone_deg : {10.0, 120.0, 170.0}) {
    const Cone cone = make_cone(64, cone_deg, GetParam(), 7);
    const float half = static_cast<float>(cone_deg * M_PI / 360.0);
    for (const glm::vec3& axis : axes) {
      std::vector<glm::vec3> d(cone.rays);
      std::vector<float> angle(cone.rays);
      cone_rays(cone, axis, fallback_tangent(axis), 3, d.data(), angle.data());
      for (int i = 0; i < cone.rays; ++i) {
        EXPECT_NEAR(glm::length(d[i]), 1.0f, 1e-5f);
        const float a = std::acos(std::min(1.0f, glm::dot(d[i], axis)));
        EXPECT_LE(a, half + 1e-3f);
        EXPECT_NEAR(a, angle[i], 2e-3f) << "ray " << i;
      }
    }
  }
}

INSTANTIATE_TEST_SUITE_P(AllSamplings, ConeRays,
                         ::testing::Values(Sampling::Fibonacci, Sampling::Random, Sampling::Cgal));

TEST(ConeRays, FibonacciCoversTheCapEvenly) {
  // Equal-area bands: the cosines of the ray angles are evenly spaced over [cos(half), 1].
  const Cone cone = make_cone(30, 120.0, Sampling::Fibonacci, 0);
  for (int i = 0; i < 30; ++i) {
    const float expected = 1.0f - (i + 0.5f) / 30.0f * 0.5f;
    EXPECT_NEAR(std::cos(cone.local_angle[i]), expected, 1e-5f);
    EXPECT_GE(cone.local_angle[i], cone.angle_floor * 0.9999f);
  }
  EXPECT_NEAR(cone.local_angle[0], cone.angle_floor, 1e-6f);
}

TEST(ConeRays, CgalSampleZeroIsTheAxisAndRadiiGrowLinearly) {
  const Cone cone = make_cone(25, 120.0, Sampling::Cgal, 0);
  EXPECT_FLOAT_EQ(cone.local_angle[0], 0.0f);
  for (int i = 1; i < 25; ++i) {
    // disk radius i/n maps to tan(angle) = tan(60 deg) * i / n.
    EXPECT_NEAR(std::tan(cone.local_angle[i]), std::tan(kPi / 3) * i / 25.0f, 1e-4f);
  }
}

TEST(ConeRays, RandomDependsOnSeedAndPointOnly) {
  const Cone a = make_cone(16, 120.0, Sampling::Random, 1),
             b = make_cone(16, 120.0, Sampling::Random, 2);
  std::vector<glm::vec3> d1(16), d2(16), d3(16);
  std::vector<float> ang(16);
  const glm::vec3 axis(0, 0, 1);
  cone_rays(a, axis, fallback_tangent(axis), 5, d1.data(), ang.data());
  cone_rays(a, axis, fallback_tangent(axis), 5, d2.data(), ang.data());
  cone_rays(b, axis, fallback_tangent(axis), 5, d3.data(), ang.data());
  for (int i = 0; i < 16; ++i) EXPECT_EQ(d1[i], d2[i]);
  int differ = 0;
  for (int i = 0; i < 16; ++i) differ += d1[i] != d3[i];
  EXPECT_EQ(differ, 16);
}

TEST(ConeRays, TheRaySetTurnsWithItsTangent) {
  // Rotating axis and tangent together rotates every ray by the same rotation.
  const Cone cone = make_cone(30, 120.0, Sampling::Fibonacci, 0);
  const glm::vec3 axis(0, 0, -1), tangent(1, 0, 0);
  const glm::mat3 turn = glm::mat3(glm::vec3(0, 1, 0), glm::vec3(0, 0, 1), glm::vec3(1, 0, 0));
  std::vector<glm::vec3> a(30), b(30);
  std::vector<float> angle(30);
  cone_rays(cone, axis, tangent, 0, a.data(), angle.data());
  cone_rays(cone, turn * axis, turn * tangent, 0, b.data(), angle.data());
  for (int i = 0; i < 30; ++i) EXPECT_LT(glm::length(turn * a[i] - b[i]), 1e-6f) << i;
}

TEST(ConeRays, FallbackTangentIsPerpendicularAndContinuousAcrossAxisPlanes) {
  // Axis-aligned normals (common in CAD) and their +-0 neighbours get the same frame.
  for (const glm::vec3 axis : {glm::vec3(1, 0, 0), glm::vec3(0, 0, -1), glm::vec3(0, 1, 0)}) {
    const glm::vec3 t = fallback_tangent(axis);
    EXPECT_NEAR(glm::length(t), 1.0f, 1e-6f);
    EXPECT_NEAR(glm::dot(t, axis), 0.0f, 1e-6f);
    const glm::vec3 nudged = glm::normalize(axis + glm::vec3(-1e-7f, 1e-7f, -1e-7f));
    const glm::vec3 negative_zero(axis.x == 0 ? -0.0f : axis.x, axis.y == 0 ? -0.0f : axis.y,
                                  axis.z == 0 ? -0.0f : axis.z);
    EXPECT_LT(glm::length(fallback_tangent(nudged) - t), 1e-5f);
    EXPECT_EQ(fallback_tangent(negative_zero), t);
  }
}

TEST(ConeRays, NarrowConesStayFinite) {
  // cos(half) rounds to 1 in float below ~0.02 degrees; 1 - cos is carried instead.
  for (Sampling s : {Sampling::Fibonacci, Sampling::Random, Sampling::Cgal}) {
    const Cone cone = make_cone(30, 1e-4, s, 1);
    EXPECT_GT(cone.one_minus_cos_half, 0.0f);
    EXPECT_GT(cone.angle_floor, 0.0f);
    std::vector<glm::vec3> d(30);
    std::vector<float> angle(30);
    const glm::vec3 axis(0, 1, 0);
    cone_rays(cone, axis, fallback_tangent(axis), 0, d.data(), angle.data());
    for (int i = 0; i < 30; ++i) {
      EXPECT_TRUE(std::isfinite(angle[i]));
      EXPECT_GT(glm::dot(d[i], axis), 0.999999f);
    }
  }
}

TEST(ConeRays, RejectsBadCounts) {
  EXPECT_THROW(make_cone(0, 120.0, Sampling::Fibonacci, 0), std::invalid_argument);
  EXPECT_THROW(make_cone(kMaxRays + 1, 120.0, Sampling::Fibonacci, 0), std::invalid_argument);
  EXPECT_THROW(make_cone(30, 180.0, Sampling::Fibonacci, 0), std::invalid_argument);
  EXPECT_THROW(make_cone(30, 0.0, Sampling::Fibonacci, 0), std::invalid_argument);
}

}  // namespace
}  // namespace sdf
