// SPDX-License-Identifier: GPL-3.0-or-later
// The whole stage on shapes of known thickness: a dumbbell's balls and neck, separate solids,
// the same result on any thread count.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <set>
#include <vector>

#include "segment/segmentation.h"
#include "segment_test_meshes.h"

namespace {

using namespace sdf::segment;

Segmentation run(const sdf::test::Arrays& a, const std::vector<double>& values, std::size_t k,
                 bool cgal, unsigned threads = 0) {
  SegmentOptions o;
  o.clusters = k;
  o.expansion = ExpansionRules{cgal, cgal};
  o.threads = threads;
  return segment_mesh(a.vertices.data(), a.vertices.size() / 3, a.triangles.data(),
                      a.triangles.size() / 3, values.data(), o);
}

double face_x(const sdf::test::Arrays& a, std::size_t f) {
  double x = 0.0;
  for (int c = 0; c < 3; ++c) x += a.vertices[3 * a.triangles[3 * f + c]] / 3.0;
  return x;
}

TEST(SegmentSegmentation, DumbbellGivesTwoBallsAndANeck) {
  std::vector<double> thickness;
  const auto a = sdf::test::dumbbell(&thickness);
  const double neck = sdf::test::dumbbell_neck_end();
  for (bool cgal : {false, true}) {
    const Segmentation s = run(a, thickness, 2, cgal);
    ASSERT_EQ(s.segment_count, 3u);
    std::set<int> left, middle, right;
    for (std::size_t f = 0; f < thickness.size(); ++f) {
      const double x = face_x(a, f);
      if (x < -neck - 0.1) left.insert(s.segments[f]);
      if (std::abs(x) < neck - 0.1) middle.insert(s.segments[f]);
      if (x > neck + 0.1) right.insert(s.segments[f]);
    }
    ASSERT_EQ(left.size(), 1u);
    ASSERT_EQ(middle.size(), 1u);
    ASSERT_EQ(right.size(), 1u);
    EXPECT_EQ(*middle.begin(), 0);  // the neck is the thinnest
    EXPECT_NE(*left.begin(), *right.begin());
    ASSERT_EQ(s.boundaries.size(), 2u);
    // A loop around each neck: at least its circumference, a third more where the cut takes
    // the quads' diagonals, centred on the axis where the neck meets the ball.
    for (const Boundary& b : s.boundaries) {
      EXPECT_GT(b.length, 2 * M_PI * 0.25 * 0.99);
      EXPECT_LT(b.length, 2 * M_PI * 0.25 * 1.35);
      EXPECT_NEAR(std::abs(b.centroid[0]), neck, 0.1);
      EXPECT_NEAR(b.centroid[1], 0.0, 1e-9);
    }
  }
}

TEST(SegmentSegmentation, SeparateSolidsNeverShareASegment) {
  std::vector<double> thickness;
  sdf::test::Arrays a = sdf::test::dumbbell(&thickness);
  const std::size_t faces = thickness.size(), vertices = a.vertices.size() / 3;
  // A second dumbbell beside the first: same values, so the same clusters on both.
  for (std::size_t i = 0; i < 3 * vertices; ++i)
    a.vertices.push_back(a.vertices[i] + (i % 3 == 1 ? 5.0 : 0.0));
  for (std::size_t i = 0; i < 3 * faces; ++i)
    a.triangles.push_back(a.triangles[i] + static_cast<std::int64_t>(vertices));
  thickness.insert(thickness.end(), thickness.begin(), thickness.end());
  const Segmentation s = run(a, thickness, 2, false);
  EXPECT_EQ(s.segment_count, 6u);
  std::set<int> first(s.segments.begin(), s.segments.begin() + static_cast<long>(faces));
  for (std::size_t f = faces; f < 2 * faces; ++f) EXPECT_EQ(first.count(s.segments[f]), 0u);
}

TEST(SegmentSegmentation, SameResultForAnyThreadCount) {
  std::vector<double> thickness;
  const auto a = sdf::test::dumbbell(&thickness);
  std::mt19937 rng(1);
  std::normal_distribution<double> noise(0.0, 0.05);
  for (double& v : thickness) v += noise(rng);
  for (bool cgal : {false, true}) {
    const Segmentation one = run(a, thickness, 5, cgal, 1);
    for (unsigned threads : {2u, 3u, 7u}) {
      const Segmentation s = run(a, thickness, 5, cgal, threads);
      EXPECT_EQ(s.segments, one.segments);
      EXPECT_EQ(s.clusters, one.clusters);
      EXPECT_EQ(s.energy, one.energy);
      EXPECT_EQ(s.vertex_weights.weight, one.vertex_weights.weight);
    }
  }
}

}  // namespace
