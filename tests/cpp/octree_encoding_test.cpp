// SPDX-License-Identifier: GPL-3.0-or-later
#include <gtest/gtest.h>

#include <random>
#include <stdexcept>

#include "../../kernels/sdf_octree.h"
#include "octree.h"
#include "test_meshes.h"

namespace sdf {
namespace {

TEST(TriangleBoxOverlap, SeparatingAxes) {
  const glm::vec3 c(0.0f), h(0.5f);
  // Inside, crossing a face, and the plane cutting a corner.
  EXPECT_TRUE(triangle_overlaps_box(c, h, {-0.1f, -0.1f, 0}, {0.1f, -0.1f, 0}, {0, 0.1f, 0}));
  EXPECT_TRUE(triangle_overlaps_box(c, h, {0.4f, 0, 0}, {2, 0, 0}, {2, 0.2f, 0}));
  // Off to the side (box axis), and beside a corner with bounding boxes overlapping (only an
  // edge cross product or the plane separates).
  EXPECT_FALSE(triangle_overlaps_box(c, h, {0.6f, 0, 0}, {2, 0, 0}, {2, 0.2f, 0}));
  EXPECT_FALSE(triangle_overlaps_box(c, h, {0.45f, 0.8f, 0}, {0.8f, 0.45f, 0}, {0.8f, 0.8f, 0}));
  EXPECT_FALSE(triangle_overlaps_box(c, h, {1.0f, 0.6f, 0.6f}, {0.6f, 1.0f, 0.6f}, {0.6f, 0.6f, 1.0f}));
  EXPECT_TRUE(triangle_overlaps_box(c, h, {0.9f, 0.2f, 0.2f}, {0.2f, 0.9f, 0.2f}, {0.2f, 0.2f, 0.9f}));
}

TEST(OctreeEncoding, HandMadeMeshGivesThePapersWords) {
  // Two small triangles in opposite corners of the root cube [0, 4]^3 (after centring):
  // triangle 0 near the low corner (octant 0), triangle 1 near the high corner (octant 7).
  test::Arrays a;
  a.vertices = {0, 0, 0, 1, 0, 0, 0, 1, 0,   // triangle 0
                4, 4, 4, 3, 4, 4, 4, 3, 4};  // triangle 1
  a.triangles = {0, 1, 2, 3, 4, 5};
  OctreeConfig config;
  config.max_depth = 1;
  config.leaf_size = 1;
  const Octree tree = build_octree(a.mesh(), config);
  // Root: children at node 1, octants 0 and 7 valid -> mask 0b10000001.
  ASSERT_EQ(tree.nodes.size(), 3u);
  EXPECT_EQ(tree.nodes[0], (1u << 8) | 0x81u);
  // Two leaves: leaf words [1, 0] at 0 and [1, 1] at 2; descriptors point at them, mask 0.
  EXPECT_EQ(tree.nodes[1], 0u << 8);
  EXPECT_EQ(tree.nodes[2], 2u << 8);
  EXPECT_EQ(tree.leaves, (std::vector<std::uint32_t>{1, 0, 1, 1}));
  EXPECT_EQ(tree.depth, 1);
  EXPECT_NEAR(tree.root.size, 4.0f, 1e-3f);
}

TEST(OctreeEncoding, SharedTriangleGoesIntoEveryCellItOverlaps) {
  // Root cube [0, 4]^3. Triangle 0 lies on the y = 0 face with x + z <= 3: it overlaps the
  // low-y octants 0, 1 (high x) and 4 (high z) but not 5 (high x and z: x + z >= 4 there).
  // Triangle 1 is small, at the high corner (octant 7). Triangle 2 has zero area: left out.
  test::Arrays a;
  a.vertices = {0, 0, 0, 3, 0, 0, 0, 0, 3, 4, 4, 4, 3.9, 4, 4, 4, 3.9, 4};
  a.triangles = {0, 2, 1, 3, 4, 5, 0, 3, 3};
  OctreeConfig config;
  config.max_depth = 1;
  config.leaf_size = 1;
  const Octree tree = build_octree(a.mesh(), config);
  EXPECT_EQ(tree.nodes[0] & 0xffu, 0x01u | 0x02u | 0x10u | 0x80u);
  // Leaves in octant order: 0, 1, 4 hold triangle 0; 7 holds triangle 1.
  EXPECT_EQ(tree.leaves, (std::vector<std::uint32_t>{1, 0, 1, 0, 1, 0, 1, 1}));
  for (int i = 1; i <= 4; ++i) EXPECT_EQ(tree.nodes[i], static_cast<std::uint32_t>(2 * (i - 1)) << 8);
}

TEST(OctreeEncoding, RejectsBadConfigs) {
  OctreeConfig config;
  config.max_depth = SDF_OCTREE_MAX_DEPTH + 1;
  EXPECT_THROW(build_octree(test::box(1, 1, 1).mesh(), config), std::invalid_argument);
  config.max_depth = 4;
  config.leaf_size = 0;
  EXPECT_THROW(build_octree(test::box(1, 1, 1).mesh(), config), std::invalid_argument);
}

class OctreeOnSoup : public ::testing::TestWithParam<int> {};

TEST_P(OctreeOnSoup, ClosestHitEqualsBruteForce) {
  const Mesh mesh = test::soup(GetParam(), 17).mesh();
  const Octree tree = build_octree(mesh);
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> u(-1.2f, 1.2f);
  int hits = 0;
  for (int r = 0; r < 3000; ++r) {
    const glm::vec3 o(u(rng), u(rng), u(rng));
    const glm::vec3 d = glm::normalize(glm::vec3(u(rng), u(rng), u(rng)));
    const int skip = r % 5 == 0 ? r % GetParam() : -1;
    const kern::SdfHit a = kern::sdf_octree_closest_hit(tree.nodes.data(), tree.leaves.data(),
                                                        tree.triangles.data(), tree.root, o, d,
                                                        1e-4f, skip);
    kern::SdfHit b{INFINITY, 0.0f, -1};
    for (const kern::SdfTriangle& t : tree.triangles)
      if (t.id != skip) kern::sdf_intersect_triangle(o, d, 1e-4f, &t, &b);
    ASSERT_EQ(a.t, b.t) << "ray " << r;
    hits += std::isfinite(a.t);
  }
  EXPECT_GT(hits, GetParam() >= 100 ? 200 : 0);
}

INSTANTIATE_TEST_SUITE_P(Sizes, OctreeOnSoup, ::testing::Values(1, 7, 300, 5000, 20000));

}  // namespace
}  // namespace sdf
