// SPDX-License-Identifier: GPL-3.0-or-later
// The parallel BVH builder must give the same bytes for any thread count: results and their
// timings are then reproducible, and a bug in the parallel phases shows up as a difference.
#include <gtest/gtest.h>

#include <cstring>
#include <utility>

#include "accel/bvh.h"
#include "accel/bvh_stats.h"
#include "mesh/mesh.h"
#include "test_meshes.h"
#include "traverse/sdf_bvh_traverse.h"

namespace sdf {
namespace {

template <typename Array>
bool same_bytes(const Array& a, const Array& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(a[0])) == 0;
}

Bvh build_with_threads(const Mesh& mesh, unsigned threads) {
  BvhConfig config;
  config.threads = threads;
  return build_bvh(mesh, config);
}

class BvhDeterminism : public ::testing::TestWithParam<int> {};

// Sizes below, at and well above the size where nodes are split by all threads together, so
// the serial subtrees, the parallel top levels and the hand-over between them all run.
TEST_P(BvhDeterminism, SameArraysForOneAndFourThreads) {
  const Mesh mesh = test::soup(GetParam(), 17).mesh();
  const Bvh one = build_with_threads(mesh, 1);
  const Bvh four = build_with_threads(mesh, 4);
  ASSERT_FALSE(one.empty());
  EXPECT_TRUE(same_bytes(one.nodes, four.nodes));
  EXPECT_TRUE(same_bytes(one.triangles, four.triangles));
  EXPECT_TRUE(same_bytes(one.nodes, build_with_threads(mesh, 3).nodes));
}

INSTANTIATE_TEST_SUITE_P(Sizes, BvhDeterminism, ::testing::Values(1000, 16384, 150000));

TEST(BvhDeterminism, ManyIdenticalTrianglesStillSplitTheSameWay) {
  // Every centroid equal: the top levels cut the list by position, as the subtrees do.
  test::Arrays a;
  for (int t = 0; t < 40000; ++t) {
    a.vertices.insert(a.vertices.end(), {0, 0, 0, 1, 0, 0, 0, 1, 0});
    a.triangles.insert(a.triangles.end(), {3 * t, 3 * t + 1, 3 * t + 2});
  }
  const Mesh mesh = a.mesh();
  const Bvh one = build_with_threads(mesh, 1);
  const Bvh four = build_with_threads(mesh, 4);
  EXPECT_TRUE(same_bytes(one.nodes, four.nodes));
  EXPECT_TRUE(same_bytes(one.triangles, four.triangles));
  for (const auto& node : one.nodes) EXPECT_LE(node.count, BvhConfig().max_leaf_size);
  EXPECT_LT(bvh_depth(one), SDF_BVH_STACK_SIZE);
}

// compute() builds the tree from the mesh before orientation reverses faces, then rewrites the
// records: that must be the tree and records of building after the reversal, byte for byte.
TEST(BvhDeterminism, RewritingTrianglesAfterReversalsEqualsBuildingAfterThem) {
  for (std::size_t morton_below : {std::size_t{0}, std::size_t{1024}}) {
    test::Arrays soup = test::soup(50000, 5);
    // Zeros of both signs on one axis of some faces: min and max keep the first of two equal
    // values, so their boxes would follow the corner order but for build_bvh's +0.
    // Two faces at x = -10 and 10 put the centre, which make_mesh subtracts, at x = 0.
    for (double x : {-10.0, 10.0}) {
      const auto first = static_cast<std::int64_t>(soup.vertices.size() / 3);
      soup.vertices.insert(soup.vertices.end(), {x, 0.0, 0.0, x, 1.0, 0.0, x, 0.0, 1.0});
      soup.triangles.insert(soup.triangles.end(), {first, first + 1, first + 2});
    }
    for (std::size_t f = 0; f < 3000; f += 3) {
      soup.vertices[9 * f + 3] = 0.0;
      soup.vertices[9 * f + 6] = -0.0;
    }
    const Mesh before = soup.mesh();
    Mesh turned = copy_mesh(before);
    std::size_t reversed = 0;
    for (std::size_t f = 0; f < turned.triangles.size(); f += 3, ++reversed)
      std::swap(turned.triangles[f].y, turned.triangles[f].z);  // as orient() reverses
    BvhConfig config;
    config.morton_below = morton_below;
    Bvh early = build_bvh(before, config);
    const Bvh late = build_bvh(turned, config);
    EXPECT_TRUE(same_bytes(early.nodes, late.nodes));
    EXPECT_FALSE(same_bytes(early.triangles, late.triangles));  // the test reverses something
    rewrite_triangles(early, turned, 3);
    EXPECT_TRUE(same_bytes(early.nodes, late.nodes));
    EXPECT_TRUE(same_bytes(early.triangles, late.triangles));
    EXPECT_GT(reversed, 10000u);
  }
}

TEST(BvhSahCost, OneTriangleCostsOneAndASplitTreeCostsLessThanALeaf) {
  test::Arrays a;
  a.vertices = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  a.triangles = {0, 1, 2};
  EXPECT_DOUBLE_EQ(bvh_sah_cost(build_bvh(a.mesh())), 1.0);
  const Bvh soup = build_bvh(test::soup(5000, 3).mesh());
  EXPECT_GT(bvh_sah_cost(soup), 1.0);
  EXPECT_LT(bvh_sah_cost(soup), 5000.0 / 10);  // far below one leaf holding everything
}

}  // namespace
}  // namespace sdf
