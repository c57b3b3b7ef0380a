// SPDX-License-Identifier: GPL-3.0-or-later
// Segmentation to a number of segments: the count asked for where the search can reach it,
// the nearest count otherwise, and the usual progress and cancel.
#include <gtest/gtest.h>

#include <algorithm>
#include <stdexcept>
#include <vector>

#include "segment/segment_count.h"
#include "segment_test_meshes.h"

namespace {

using namespace sdf::segment;

struct Mesh {
  sdf::test::Arrays arrays;
  std::vector<double> values;
  std::size_t vertices() const { return arrays.vertices.size() / 3; }
  std::size_t faces() const { return values.size(); }
};

Mesh two_dumbbells() {
  Mesh m;
  m.arrays = sdf::test::dumbbell(&m.values);
  const std::size_t faces = m.values.size(), vertices = m.arrays.vertices.size() / 3;
  for (std::size_t i = 0; i < 3 * vertices; ++i)
    m.arrays.vertices.push_back(m.arrays.vertices[i] + (i % 3 == 1 ? 5.0 : 0.0));
  for (std::size_t i = 0; i < 3 * faces; ++i)
    m.arrays.triangles.push_back(m.arrays.triangles[i] + static_cast<std::int64_t>(vertices));
  m.values.insert(m.values.end(), m.values.begin(), m.values.end());
  return m;
}

Segmentation to_count(const Mesh& m, std::size_t segments, const sdf::ProgressFn& progress = {}) {
  return segment_to_count(m.arrays.vertices.data(), m.vertices(), m.arrays.triangles.data(),
                          m.faces(), m.values.data(), SegmentOptions{}, segments, progress);
}

TEST(SegmentCount, ReachesACountTheClustersCanGive) {
  Mesh one;
  one.arrays = sdf::test::dumbbell(&one.values);
  const Segmentation s = to_count(one, 3);
  EXPECT_EQ(s.segment_count, 3u);  // two balls and the neck
  EXPECT_EQ(to_count(two_dumbbells(), 6).segment_count, 6u);
  const auto& t = s.timings;
  EXPECT_TRUE(
      std::any_of(t.begin(), t.end(), [](const auto& p) { return p.first == "count_search"; }));
}

TEST(SegmentCount, KeepsTheNearestCountWhenNoneMatches) {
  // Far more segments than any clusters and smoothness give: the largest count of the search,
  // found here by running every pair it tries.
  const Mesh m = two_dumbbells();
  std::size_t largest = 0;
  for (const double factor : kSmoothnessFactors) {
    for (std::size_t k = kMinSearchClusters; k <= kMaxSearchClusters; ++k) {
      SegmentOptions o;
      o.clusters = k;
      o.smoothness *= factor;
      largest =
          std::max(largest, segment_mesh(m.arrays.vertices.data(), m.vertices(),
                                         m.arrays.triangles.data(), m.faces(), m.values.data(), o)
                                .segment_count);
    }
  }
  EXPECT_EQ(to_count(m, 4096).segment_count, largest);
}

TEST(SegmentCount, APreparedInputGivesSegmentMeshsResult) {
  // The search prepares the face graph and the (filtered) values once for every try.
  const Mesh m = two_dumbbells();
  for (bool filter : {false, true}) {
    SegmentOptions o;
    o.filter = filter;
    const SegmentInput input = prepare_segment_input(m.arrays.triangles.data(), m.faces(),
                                                     m.vertices(), m.values.data(), o);
    for (std::size_t k : {2u, 5u}) {
      o.clusters = k;
      const Segmentation direct =
          segment_mesh(m.arrays.vertices.data(), m.vertices(), m.arrays.triangles.data(), m.faces(),
                       m.values.data(), o);
      const Segmentation prepared = segment_prepared(input, m.arrays.vertices.data(), m.vertices(),
                                                     m.arrays.triangles.data(), m.faces(), o);
      EXPECT_EQ(prepared.segments, direct.segments);
      EXPECT_EQ(prepared.values, direct.values);
      EXPECT_EQ(prepared.energy, direct.energy);
      EXPECT_EQ(prepared.timings.size(), direct.timings.size());
    }
  }
}

TEST(SegmentCount, RefusesZeroSegments) {
  EXPECT_THROW(to_count(two_dumbbells(), 0), std::invalid_argument);
}

TEST(SegmentCount, ProgressMovesForwardAndCancelStops) {
  const Mesh m = two_dumbbells();
  std::vector<double> seen;
  to_count(m, 4096, [&](double f) {
    seen.push_back(f);
    return true;
  });
  ASSERT_FALSE(seen.empty());
  const auto back = std::is_sorted_until(seen.begin(), seen.end());
  EXPECT_EQ(back, seen.end()) << "at " << (back - seen.begin()) << ": " << *(back - 1) << " then "
                              << (back == seen.end() ? 0.0 : *back);
  EXPECT_EQ(seen.back(), 1.0);
  int calls = 0;
  EXPECT_THROW(to_count(m, 4096, [&](double) { return ++calls < 3; }), sdf::Cancelled);
}

}  // namespace
