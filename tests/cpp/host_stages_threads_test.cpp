// SPDX-License-Identifier: GPL-3.0-or-later
// The host stages before and after the cast run on several threads; their results must not
// depend on how many, and must be those of the serial code they replaced.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <utility>
#include <vector>

#include "prepare/sampling.h"
#include "test_meshes.h"
#include "util/radix_sort.h"

namespace sdf {
namespace {

template <class Vector>
bool same_bits(const Vector& a, const Vector& b) {
  return a.size() == b.size() &&
         std::memcmp(a.data(), b.data(), a.size() * sizeof(typename Vector::value_type)) == 0;
}

// A soup of 60k triangles, with some faces collapsed (zero area: zero axis) and shared
// vertices, so that vertex normals sum several faces.
Mesh test_mesh() {
  test::Arrays a = test::soup(60000, 5);
  for (std::size_t f = 0; f < a.triangles.size() / 3; f += 17)
    a.triangles[3 * f + 2] = a.triangles[3 * f];
  for (std::size_t f = 1; f < a.triangles.size() / 3; f += 5)
    a.triangles[3 * f + 1] = a.triangles[3 * f - 3];
  return a.mesh();
}

TEST(HostStagesThreads, SamplePointsDoNotDependOnThreads) {
  const Mesh mesh = test_mesh();
  for (PointKind kind : {PointKind::Faces, PointKind::Vertices}) {
    const SamplePoints one = sample_points(mesh, kind, 1);
    for (unsigned threads : {2u, 7u}) {
      const SamplePoints many = sample_points(mesh, kind, threads);
      EXPECT_TRUE(same_bits(one.origins, many.origins));
      EXPECT_TRUE(same_bits(one.axes, many.axes));
      EXPECT_TRUE(same_bits(one.tangents, many.tangents));
      EXPECT_TRUE(same_bits(one.own_face, many.own_face));
    }
  }
}

// spatial_order as first written: std::sort of (Morton code, index) pairs.
std::vector<std::uint32_t> reference_spatial_order(const SamplePoints& points) {
  auto spread = [](std::uint32_t v) {
    v = (v | (v << 16)) & 0x030000FFu;
    v = (v | (v << 8)) & 0x0300F00Fu;
    v = (v | (v << 4)) & 0x030C30C3u;
    v = (v | (v << 2)) & 0x09249249u;
    return v;
  };
  glm::vec3 lo(INFINITY), hi(-INFINITY);
  for (const glm::vec3& p : points.origins) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  const glm::vec3 scale = 1023.0f / glm::max(hi - lo, glm::vec3(1e-30f));
  std::vector<std::pair<std::uint32_t, std::uint32_t>> keyed(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    const glm::uvec3 c = glm::uvec3((points.origins[i] - lo) * scale);
    keyed[i] = {spread(c.x) | (spread(c.y) << 1) | (spread(c.z) << 2),
                static_cast<std::uint32_t>(i)};
  }
  std::sort(keyed.begin(), keyed.end());
  std::vector<std::uint32_t> order(points.size());
  for (std::size_t i = 0; i < keyed.size(); ++i) order[i] = keyed[i].second;
  return order;
}

TEST(HostStagesThreads, SpatialOrderIsTheSortedOrderForAnyThreadCount) {
  SamplePoints points = sample_points(test_mesh(), PointKind::Faces, 0);
  // Many exact ties (equal codes): their order must be index order.
  for (std::size_t i = 0; i < points.size(); i += 3) points.origins[i] = points.origins[i / 2];
  const std::vector<std::uint32_t> expected = reference_spatial_order(points);
  for (unsigned threads : {1u, 2u, 5u}) EXPECT_EQ(spatial_order(points, threads), expected);
}

TEST(HostStagesThreads, RadixSortIsAStableSortOnTheKeyBits) {
  std::mt19937_64 rng(9);
  UninitializedVector<std::uint64_t> items(300000);
  for (std::size_t i = 0; i < items.size(); ++i)
    items[i] = (rng() % 5000) << 20 | (rng() & 0xfffff);  // 13 key bits above 20 others
  UninitializedVector<std::uint64_t> expected = items;
  std::stable_sort(expected.begin(), expected.end(),
                   [](std::uint64_t a, std::uint64_t b) { return (a >> 20) < (b >> 20); });
  for (unsigned threads : {1u, 3u}) {
    UninitializedVector<std::uint64_t> sorted = items;
    radix_sort_by_bits(sorted, 20, 13, threads);
    EXPECT_EQ(sorted, expected);
  }
}

}  // namespace
}  // namespace sdf
