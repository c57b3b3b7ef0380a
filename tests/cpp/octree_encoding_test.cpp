// SPDX-License-Identifier: GPL-3.0-or-later
#include <gtest/gtest.h>

#include <random>
#include <stdexcept>

#include "accel/octree.h"
#include "test_meshes.h"
#include "traverse/sdf_octree.h"

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
  EXPECT_FALSE(
      triangle_overlaps_box(c, h, {1.0f, 0.6f, 0.6f}, {0.6f, 1.0f, 0.6f}, {0.6f, 0.6f, 1.0f}));
  EXPECT_TRUE(
      triangle_overlaps_box(c, h, {0.9f, 0.2f, 0.2f}, {0.2f, 0.9f, 0.2f}, {0.2f, 0.2f, 0.9f}));
}

TEST(TriangleBoxOverlap, SameAnswersAtAnyScale) {
  // Scaling everything by a power of two changes no answer: the products (up to a length
  // cubed) stay in range at 2^60 (a mesh ~1e18 wide), which overflowed in float.
  const glm::vec3 c(0.0f), h(0.5f);
  const glm::vec3 cases[][3] = {{{-0.1f, -0.1f, 0}, {0.1f, -0.1f, 0}, {0, 0.1f, 0}},
                                {{0.6f, 0, 0}, {2, 0, 0}, {2, 0.2f, 0}},
                                {{0.45f, 0.8f, 0}, {0.8f, 0.45f, 0}, {0.8f, 0.8f, 0}},
                                {{0.9f, 0.2f, 0.2f}, {0.2f, 0.9f, 0.2f}, {0.2f, 0.2f, 0.9f}},
                                {{1.0f, 0.6f, 0.6f}, {0.6f, 1.0f, 0.6f}, {0.6f, 0.6f, 1.0f}}};
  for (const auto& t : cases) {
    const bool unscaled = triangle_overlaps_box(c, h, t[0], t[1], t[2]);
    for (const float scale : {0x1p-60f, 0x1p30f, 0x1p60f, 0x1p100f})
      EXPECT_EQ(
          triangle_overlaps_box(c * scale, h * scale, t[0] * scale, t[1] * scale, t[2] * scale),
          unscaled)
          << "scale " << scale << ", triangle " << t[0].x << " " << t[0].y;
  }
}

// Every node's pointer leads to words that exist: inner nodes to their children, leaves to a
// count and that many triangle indices.
void expect_well_formed(const Octree& tree) {
  for (std::size_t i = 0; i < tree.nodes.size(); ++i) {
    const std::uint32_t pointer = tree.nodes[i] >> 8, mask = tree.nodes[i] & 0xffu;
    if (mask != 0) {
      EXPECT_LE(pointer + __builtin_popcount(mask), tree.nodes.size()) << "node " << i;
      continue;
    }
    ASSERT_LT(pointer, tree.leaves.size()) << "leaf node " << i;
    const std::uint32_t count = tree.leaves[pointer];
    ASSERT_LE(pointer + 1 + count, tree.leaves.size()) << "leaf node " << i;
    for (std::uint32_t k = 0; k < count; ++k)
      EXPECT_LT(tree.leaves[pointer + 1 + k], tree.triangles.size()) << "leaf node " << i;
  }
}

TEST(OctreeEncoding, MeshOf1e18UnitsIsWellFormed) {
  // Found by the compute fuzzer: a tetrahedron 1e18 wide. The overlap test's plane products
  // overflowed, every child refused the triangles, and the mask-0 node read as a leaf with no
  // words behind it (a wild triangle index in the cast).
  const double s = 5.0440315826549555e17;
  test::Arrays a;
  a.vertices = {-s, -s, -s, s, -s, -s, -s, 9007199254740992.0, -3.5578437056226918e17, -s, -s, s};
  a.triangles = {0, 2, 1, 2, 1, 3, 0, 2, 2, 1, 2, 3};
  OctreeConfig config;
  config.max_depth = 4;
  config.leaf_size = 1;
  const Octree tree = build_octree(a.mesh(), config);
  EXPECT_GT(tree.depth, 0);
  expect_well_formed(tree);
}

TEST(OctreeEncoding, TrianglesOnlyInACellsMarginMakeItALeaf) {
  // Each cell holds what overlaps it grown by 1e-5 of its size. Two triangles just past the
  // x = 0 mid-plane (3e-6, inside octant 0's margin of 5e-6 but outside its children's 2.5e-6)
  // are all octant 0 holds: none of its children takes them, and it must end as a leaf.
  test::Arrays a;
  // Small triangles in four corners set the root cube to [-1, 1]^3 (grown by 1e-4).
  const double corners[4][3] = {{-1, 1, 1}, {1, -1, 1}, {1, 1, -1}, {1, 1, 1}};
  for (const auto& c : corners) {
    const std::int64_t v = static_cast<std::int64_t>(a.vertices.size() / 3);
    const double in[3] = {c[0] > 0 ? -0.1 : 0.1, c[1] > 0 ? -0.1 : 0.1, c[2] > 0 ? -0.1 : 0.1};
    a.vertices.insert(a.vertices.end(),
                      {c[0], c[1], c[2], c[0] + in[0], c[1], c[2], c[0], c[1] + in[1], c[2]});
    a.triangles.insert(a.triangles.end(), {v, v + 1, v + 2});
  }
  for (const double y : {-0.5, -0.2}) {
    const std::int64_t v = static_cast<std::int64_t>(a.vertices.size() / 3);
    a.vertices.insert(a.vertices.end(), {3e-6, y, -0.5, 3e-6, y + 0.1, -0.5, 3e-6, y, -0.4});
    a.triangles.insert(a.triangles.end(), {v, v + 1, v + 2});
  }
  OctreeConfig config;
  config.max_depth = 4;
  config.leaf_size = 1;
  const Mesh mesh = a.mesh();
  ASSERT_EQ(mesh.vertices[12].x, 3e-6f);  // not moved by make_mesh's centring
  const Octree tree = build_octree(mesh, config);
  ASSERT_TRUE(tree.nodes[0] & 1u) << "octant 0 holds the two triangles";
  const std::uint32_t octant0 = tree.nodes[tree.nodes[0] >> 8];
  EXPECT_EQ(octant0 & 0xffu, 0u);
  EXPECT_EQ(tree.leaves[octant0 >> 8], 2u);
  expect_well_formed(tree);
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
  for (int i = 1; i <= 4; ++i)
    EXPECT_EQ(tree.nodes[i], static_cast<std::uint32_t>(2 * (i - 1)) << 8);
}

TEST(OctreeEncoding, RejectsBadConfigs) {
  OctreeConfig config;
  config.max_depth = SDF_OCTREE_MAX_DEPTH + 1;
  EXPECT_THROW(build_octree(test::box(1, 1, 1).mesh(), config), std::invalid_argument);
  config.max_depth = 4;
  config.leaf_size = 0;
  EXPECT_THROW(build_octree(test::box(1, 1, 1).mesh(), config), std::invalid_argument);
}

// A ray through a cube's centre touches all 8 octants there (the entry test is inclusive, so a
// ray grazing a cell at one point visits it). Along the root's main diagonal every cell's
// centre is on the ray, and pages meeting at the diagonal make the builder split every cell
// along it down to the deepest level: up to 8 children pushed for each one popped, the stack
// 112 entries deep here (the bound is 113; found by reading: the stack once held 50, and
// UBSan saw it overflow here).
TEST(OctreeClosestHit, RayDownTheDiagonalOfTheDeepestTree) {
  test::Arrays a;
  a.vertices = {-1, -1, -1, 1, 1, 1, 1, -1, -1, -1, 1, -1, -1, -1, 1};
  a.triangles = {0, 1, 2, 0, 1, 3, 0, 1, 4};
  // The target: in the plane x + y + z = 1.5, its centroid (0.5, 0.5, 0.5) on the diagonal.
  a.vertices.insert(a.vertices.end(), {1, 0.5, 0, 0, 1, 0.5, 0.5, 0, 1});
  a.triangles.insert(a.triangles.end(), {5, 6, 7});
  OctreeConfig config;
  config.max_depth = SDF_OCTREE_MAX_DEPTH;
  config.leaf_size = 1;
  const Mesh mesh = a.mesh();
  const Octree tree = build_octree(mesh, config);
  ASSERT_EQ(tree.depth, SDF_OCTREE_MAX_DEPTH);
  // The same corner on every axis: the three axes' entry distances tie exactly.
  ASSERT_EQ(tree.root.lo_x, tree.root.lo_y);
  ASSERT_EQ(tree.root.lo_x, tree.root.lo_z);
  const glm::vec3 d = glm::normalize(glm::vec3(1.0f));
  for (const float from : {-2.0f, -0.3f}) {
    const glm::vec3 o(from);
    const kern::SdfHit hit = kern::sdf_octree_closest_hit(
        tree.nodes.data(), tree.leaves.data(), tree.triangles.data(), tree.root, o, d, 1e-4f, -1);
    kern::SdfHit expected{INFINITY, 0.0f, -1};
    for (const kern::SdfTriangle& t : tree.triangles)
      kern::sdf_intersect_triangle(o, d, 1e-4f, &t, &expected);
    ASSERT_EQ(expected.id, 3);  // the pages lie along the ray
    EXPECT_EQ(hit.t, expected.t) << "from " << from;
    EXPECT_EQ(hit.id, 3);
  }
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
    const kern::SdfHit a = kern::sdf_octree_closest_hit(
        tree.nodes.data(), tree.leaves.data(), tree.triangles.data(), tree.root, o, d, 1e-4f, skip);
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
