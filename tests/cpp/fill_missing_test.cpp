// SPDX-License-Identifier: GPL-3.0-or-later
#include <gtest/gtest.h>

#include <vector>

#include "post/fill.h"
#include "test_meshes.h"

namespace sdf {
namespace {

// A strip of n triangles, each sharing an edge with the next.
test::Arrays strip(int n) {
  test::Arrays a;
  for (int i = 0; i < n + 2; ++i)
    a.vertices.insert(a.vertices.end(), {double(i / 2), double(i % 2), 0.0});
  for (int t = 0; t < n; ++t) a.triangles.insert(a.triangles.end(), {t, t + 1, t + 2});
  return a;
}

TEST(FillMissing, SpreadsOutwardLayerByLayer) {
  const Mesh mesh = strip(6).mesh();
  // Only face 0 (value 1) and face 5 (value 4) have values.
  std::vector<float> raw = {1, -1, -1, -1, -1, 4};
  std::vector<std::int32_t> valid = {3, 0, 0, 0, 0, 3};
  EXPECT_EQ(fill_missing(mesh, PointKind::Faces, raw.data(), valid.data()), FillResult::Filled);
  // Faces share vertices with faces up to two away in a strip: layer 1 = {1, 2, 3, 4}, each the
  // mean of its known neighbours: 1 -> {0}, 2 -> {0}, 3 -> {5}, 4 -> {5}.
  EXPECT_EQ(raw, (std::vector<float>{1, 1, 1, 4, 4, 4}));
}

TEST(FillMissing, ComponentWithoutValuesTakesTheMedian) {
  test::Arrays a = strip(2);
  test::Arrays b = strip(3);
  const std::int64_t offset = static_cast<std::int64_t>(a.vertices.size() / 3);
  a.vertices.insert(a.vertices.end(), b.vertices.begin(), b.vertices.end());
  for (auto v : b.triangles) a.triangles.push_back(v + offset);
  std::vector<float> raw = {2, 6, -1, -1, -1};
  std::vector<std::int32_t> valid = {1, 1, 0, 0, 0};
  fill_missing(a.mesh(), PointKind::Faces, raw.data(), valid.data());
  EXPECT_EQ(raw, (std::vector<float>{2, 6, 6, 6, 6}));  // median of {2, 6}: upper middle
}

TEST(FillMissing, NoValueAnywhereGivesZeros) {
  std::vector<float> raw = {-1, -1};
  std::vector<std::int32_t> valid = {0, 0};
  EXPECT_EQ(fill_missing(strip(2).mesh(), PointKind::Faces, raw.data(), valid.data()),
            FillResult::NoValueAnywhere);
  EXPECT_EQ(raw, (std::vector<float>{0, 0}));
}

TEST(FillMissing, VerticesUseEdgeNeighbours) {
  const Mesh mesh = strip(1).mesh();  // one triangle, vertices 0 1 2
  std::vector<float> raw = {1, 3, -1};
  std::vector<std::int32_t> valid = {1, 1, 0};
  fill_missing(mesh, PointKind::Vertices, raw.data(), valid.data());
  EXPECT_FLOAT_EQ(raw[2], 2.0f);
}

}  // namespace
}  // namespace sdf
