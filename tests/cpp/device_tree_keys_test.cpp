// SPDX-License-Identifier: GPL-3.0-or-later
// The host's share of the device-built tree: every face once, faces with area first in Morton
// order (ties in face order), zero-area faces last in face order, codes that match, and the
// margin the host tree's boxes grow by.
#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>
#include <vector>

#include "bvh.h"
#include "bvh_margin.h"
#include "device_tree_keys.h"
#include "test_meshes.h"

namespace sdf {
namespace {

// A soup with zero-area faces mixed in: repeated corners, three collinear corners.
test::Arrays soup_with_degenerates(int count) {
  test::Arrays a = test::soup(count, 5);
  for (int k = 0; k < count; k += 7) {
    a.triangles[3 * k + 1] = a.triangles[3 * k];  // a repeated corner
  }
  const std::int64_t base = static_cast<std::int64_t>(a.vertices.size() / 3);
  for (double x : {0.0, 0.25, 0.5}) a.vertices.insert(a.vertices.end(), {x, x, x});
  a.triangles.insert(a.triangles.end(), {base, base + 1, base + 2});  // collinear
  return a;
}

bool has_area(const Mesh& mesh, std::uint32_t f) {
  const glm::uvec3 t = mesh.triangles[f];
  const glm::vec3 v0 = mesh.vertices[t.x];
  const glm::vec3 n = glm::cross(mesh.vertices[t.y] - v0, mesh.vertices[t.z] - v0);
  return n.x != 0.0f || n.y != 0.0f || n.z != 0.0f;
}

TEST(DeviceTreeKeys, OrderIsEveryFaceWithAreaFirstInCodeOrder) {
  const Mesh mesh = soup_with_degenerates(5000).mesh();
  const TreeKeys keys = make_tree_keys(mesh, 3);
  const std::size_t n = mesh.triangles.size();
  ASSERT_EQ(keys.order.size(), n);
  std::vector<std::uint32_t> sorted(keys.order.begin(), keys.order.end());
  std::sort(sorted.begin(), sorted.end());
  std::vector<std::uint32_t> all(n);
  std::iota(all.begin(), all.end(), 0u);
  EXPECT_EQ(sorted, all);

  std::size_t with_area = 0;
  for (std::uint32_t f = 0; f < n; ++f) with_area += has_area(mesh, f);
  ASSERT_EQ(keys.with_area, with_area);
  ASSERT_LT(with_area, n);  // the test has zero-area faces
  ASSERT_EQ(keys.codes.size(), with_area);
  for (std::size_t i = 0; i < n; ++i) EXPECT_EQ(has_area(mesh, keys.order[i]), i < with_area);
  for (std::size_t i = 1; i < with_area; ++i) {
    ASSERT_LT(keys.codes[i], 1u << 30);
    // Codes ascend; equal codes keep face order.
    ASSERT_TRUE(keys.codes[i - 1] < keys.codes[i] ||
                (keys.codes[i - 1] == keys.codes[i] && keys.order[i - 1] < keys.order[i]));
  }
  for (std::size_t i = with_area + 1; i < n; ++i) EXPECT_LT(keys.order[i - 1], keys.order[i]);
  // Spatially ordered: the codes are not all one cell.
  EXPECT_GT(keys.codes.back(), keys.codes.front());
}

TEST(DeviceTreeKeys, MarginIsTheHostTreesAndKeysDoNotDependOnThreads) {
  for (int count : {1, 40, 5000}) {
    const Mesh mesh = soup_with_degenerates(count).mesh();
    const TreeKeys one = make_tree_keys(mesh, 1), four = make_tree_keys(mesh, 4);
    EXPECT_EQ(one.margin, bvh_box_margin(build_bvh(mesh)));
    EXPECT_EQ(one.margin, four.margin);
    EXPECT_TRUE(std::equal(one.order.begin(), one.order.end(), four.order.begin()));
    EXPECT_TRUE(std::equal(one.codes.begin(), one.codes.end(), four.codes.begin(),
                           four.codes.end()));
  }
}

TEST(DeviceTreeKeys, ZeroAreaOnlyMeshHasNoKeys) {
  test::Arrays a;
  a.vertices = {0, 0, 0, 1, 0, 0, 2, 0, 0};
  a.triangles = {0, 1, 2, 0, 0, 1};
  const TreeKeys keys = make_tree_keys(a.mesh());
  EXPECT_EQ(keys.with_area, 0u);
  EXPECT_EQ(keys.margin, 0.0f);
  EXPECT_TRUE(keys.codes.empty());
  ASSERT_EQ(keys.order.size(), 2u);
  EXPECT_EQ(keys.order[0], 0u);
  EXPECT_EQ(keys.order[1], 1u);
}

}  // namespace
}  // namespace sdf
