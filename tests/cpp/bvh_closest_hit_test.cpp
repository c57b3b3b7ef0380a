// SPDX-License-Identifier: GPL-3.0-or-later
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <random>
#include <tuple>
#include <vector>

#include "accel/bvh.h"
#include "accel/bvh_margin.h"
#include "cast/bvh4_traverse.h"
#include "cast/bvh8_traverse.h"
#include "test_meshes.h"
#include "traverse/sdf_bvh_traverse.h"

namespace sdf {
namespace {

// Every triangle, in order: the answer the BVH must reproduce.
kern::SdfHit brute_force(const Bvh& bvh, glm::vec3 o, glm::vec3 d, float tmin, int skip) {
  kern::SdfHit hit{INFINITY, 0.0f, -1};
  for (const kern::SdfTriangle& tri : bvh.triangles)
    if (tri.id != skip) kern::sdf_intersect_triangle(o, d, tmin, &tri, &hit);
  return hit;
}

bool box_contains(const kern::SdfBvhNode& outer, glm::vec3 p) {
  return p.x >= outer.lo_x && p.y >= outer.lo_y && p.z >= outer.lo_z && p.x <= outer.hi_x &&
         p.y <= outer.hi_y && p.z <= outer.hi_z;
}

// Triangle count, and BvhConfig::morton_below: SAH everywhere, Morton splits at the bottom,
// Morton splits below the parallel top levels.
class BvhOnSoup : public ::testing::TestWithParam<std::tuple<int, int>> {};

TEST_P(BvhOnSoup, ClosestHitEqualsBruteForce) {
  const int size = std::get<0>(GetParam());
  const Mesh mesh = test::soup(size, 11).mesh();
  BvhConfig config;
  config.threads = 2;
  config.morton_below = std::get<1>(GetParam());
  Bvh bvh = build_bvh(mesh, config);
  grow_boxes_to_cover_hits(bvh);
  const Bvh4 wide = collapse_to_bvh4(bvh);
  const Bvh8 wide8 = collapse_to_bvh8(bvh);
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-1.2f, 1.2f);
  int hits = 0;
  for (int r = 0; r < 3000; ++r) {
    const glm::vec3 o(u(rng), u(rng), u(rng));
    const glm::vec3 d = glm::normalize(glm::vec3(u(rng), u(rng), u(rng)));
    const int skip = r % 7 == 0 ? r % size : -1;
    const kern::SdfHit a =
        kern::sdf_bvh_closest_hit(bvh.nodes.data(), bvh.triangles.data(), o, d, 1e-4f, skip);
    const kern::SdfHit b = brute_force(bvh, o, d, 1e-4f, skip);
    ASSERT_EQ(a.t, b.t) << "ray " << r;
#if SDF_HAVE_BVH4_SSE
    const kern::SdfHit w = bvh4_closest_hit(wide, o, d, 1e-4f, skip);
    ASSERT_EQ(w.t, b.t) << "4-wide, ray " << r;
#endif
#if SDF_HAVE_BVH8
    if (bvh8_supported()) {
      // Bit for bit: the SIMD triangle test rounds as the scalar one does.
      const kern::SdfHit e = bvh8_closest_hit_avx2(wide8, o, d, 1e-4f, skip);
      ASSERT_EQ(std::memcmp(&e, &b, sizeof e), 0) << "8-wide, ray " << r;
    }
#endif
    if (std::isfinite(a.t)) {
      ++hits;
      EXPECT_EQ(a.det < 0.0f, b.det < 0.0f);
    }
  }
  // The test exercises hits, not only misses (a lone triangle is rarely hit).
  EXPECT_GT(hits, size >= 100 ? 200 : 0);
}

INSTANTIATE_TEST_SUITE_P(Sizes, BvhOnSoup,
                         ::testing::Combine(::testing::Values(1, 5, 100, 5000, 20000),
                                            ::testing::Values(0, 64, 100000)));

#if SDF_HAVE_BVH8
TEST(Bvh8, TiesOnSharedEdgesAndLargeLeavesMatchBruteForceBitForBit) {
  if (!bvh8_supported()) GTEST_SKIP() << "no AVX2 on this CPU";
  // Rays from inside a box at points of its edges and face diagonals, where two triangles
  // tie; leaves of up to 16 triangles, and subtrees merged into one leaf (100: the whole box),
  // span several packets.
  for (int leaf : {1, 4, 16}) {
    BvhConfig config;
    config.max_leaf_size = leaf;
    Bvh bvh = build_bvh(test::box(2, 3, 4).mesh(), config);
    grow_boxes_to_cover_hits(bvh);
    for (int merge : {0, kBvh8MergeUpTo, 100}) {
      const Bvh8 wide8 = collapse_to_bvh8(bvh, merge);
      for (int i = 0; i < 27; ++i) {
        const glm::vec3 o(0.1f * (i % 3), 0.2f * (i / 3 % 3), -0.3f * (i / 9));
        std::vector<glm::vec3> directions;
        for (int k = 0; k < 125; ++k) {
          const glm::vec3 target((k % 5 - 2) * 0.5f, (k / 5 % 5 - 2) * 0.75f, (k / 25 - 2) * 1.0f);
          if (target != o) directions.push_back(glm::normalize(target - o));  // else none
        }
        const int skip = i % 12;
        // Rays from one origin two at a time (an odd count leaves one alone), as the engine
        // casts them, and one at a time.
        std::vector<kern::SdfHit> pairs(directions.size());
        bvh8_closest_hits_avx2(wide8, o, directions.data(), static_cast<int>(directions.size()),
                               1e-4f, skip, pairs.data());
        for (std::size_t k = 0; k < directions.size(); ++k) {
          const kern::SdfHit b = brute_force(bvh, o, directions[k], 1e-4f, skip);
          const kern::SdfHit e = bvh8_closest_hit_avx2(wide8, o, directions[k], 1e-4f, skip);
          ASSERT_EQ(std::memcmp(&e, &b, sizeof e), 0)
              << "leaf " << leaf << " merge " << merge << " ray " << i << "," << k;
          ASSERT_EQ(std::memcmp(&pairs[k], &b, sizeof b), 0)
              << "in pairs: leaf " << leaf << " merge " << merge << " ray " << i << "," << k;
        }
      }
    }
  }
}
#endif

class BvhShape : public ::testing::TestWithParam<int> {};  // BvhConfig::morton_below

TEST_P(BvhShape, EveryTrianglePresentAndBoxesNest) {
  // Present at least once: slivers lying across the axes are cut into pieces of their own
  // (bvh_split_test.cpp checks that the pieces cover their triangle).
  const Mesh mesh = test::soup(20000, 3).mesh();
  BvhConfig config;
  config.morton_below = GetParam();
  const Bvh bvh = build_bvh(mesh, config);
  std::vector<int> seen(mesh.triangles.size(), 0);
  for (const auto& t : bvh.triangles) ++seen[t.id];
  EXPECT_TRUE(std::all_of(seen.begin(), seen.end(), [](int c) { return c >= 1; }));
  EXPECT_LE(bvh.triangles.size(), 3 * mesh.triangles.size());
  for (const auto& node : bvh.nodes) {
    if (node.count == 0) {
      for (int c = 0; c < 2; ++c) {
        const auto& child = bvh.nodes[node.first + c];
        EXPECT_TRUE(box_contains(node, {child.lo_x, child.lo_y, child.lo_z}));
        EXPECT_TRUE(box_contains(node, {child.hi_x, child.hi_y, child.hi_z}));
      }
    } else {
      EXPECT_LE(node.count, BvhConfig().max_leaf_size);
      for (int k = node.first; k < node.first + node.count; ++k) {
        const auto& t = bvh.triangles[k];
        // A whole triangle's leaf holds its corner; a piece's need not.
        if (seen[t.id] == 1) EXPECT_TRUE(box_contains(node, {t.v0_x, t.v0_y, t.v0_z}));
      }
    }
  }
  EXPECT_LT(bvh_depth(bvh), SDF_BVH_STACK_SIZE);
}

TEST_P(BvhShape, MortonSplitsBoxesAreTight) {
  // Each inner node's box is exactly its children's union, as SAH's are; a leaf's is its
  // triangles' union, or inside it where it holds pieces of cut slivers.
  BvhConfig config;
  config.morton_below = GetParam();
  const Bvh bvh = build_bvh(test::soup(3000, 8).mesh(), config);
  std::vector<int> records_of(3000, 0);
  for (const auto& t : bvh.triangles) ++records_of[t.id];
  for (const auto& node : bvh.nodes) {
    glm::vec3 lo(INFINITY), hi(-INFINITY);
    bool cut = false;
    if (node.count == 0) {
      for (int c = 0; c < 2; ++c) {
        const auto& child = bvh.nodes[node.first + c];
        lo = glm::min(lo, glm::vec3(child.lo_x, child.lo_y, child.lo_z));
        hi = glm::max(hi, glm::vec3(child.hi_x, child.hi_y, child.hi_z));
      }
    } else {
      for (int k = node.first; k < node.first + node.count; ++k) {
        const auto& t = bvh.triangles[k];
        cut = cut || records_of[t.id] > 1;
        const glm::vec3 v0(t.v0_x, t.v0_y, t.v0_z), e1(t.e1_x, t.e1_y, t.e1_z),
            e2(t.e2_x, t.e2_y, t.e2_z);
        // The builder's boxes come from the input vertices; v0 + e1 rounds back to them only
        // approximately, so compare within a float step.
        for (const glm::vec3 p : {v0, v0 + e1, v0 + e2}) {
          lo = glm::min(lo, p);
          hi = glm::max(hi, p);
        }
      }
    }
    const float slack = 1e-5f;
    if (cut) {
      EXPECT_GE(node.lo_x, lo.x - slack);
      EXPECT_GE(node.lo_y, lo.y - slack);
      EXPECT_GE(node.lo_z, lo.z - slack);
      EXPECT_LE(node.hi_x, hi.x + slack);
      EXPECT_LE(node.hi_y, hi.y + slack);
      EXPECT_LE(node.hi_z, hi.z + slack);
      continue;
    }
    EXPECT_NEAR(node.lo_x, lo.x, slack);
    EXPECT_NEAR(node.lo_y, lo.y, slack);
    EXPECT_NEAR(node.lo_z, lo.z, slack);
    EXPECT_NEAR(node.hi_x, hi.x, slack);
    EXPECT_NEAR(node.hi_y, hi.y, slack);
    EXPECT_NEAR(node.hi_z, hi.z, slack);
  }
}

INSTANTIATE_TEST_SUITE_P(MortonBelow, BvhShape, ::testing::Values(0, 64, 100000));

TEST(Bvh, LeavesOutZeroAreaTrianglesAndHandlesAllDegenerate) {
  test::Arrays a = test::box(1, 1, 1);
  a.triangles.insert(a.triangles.end(), {0, 0, 0, 0, 1, 1});  // a point and a segment
  const Bvh bvh = build_bvh(a.mesh());
  EXPECT_EQ(bvh.triangles.size(), 12u);

  test::Arrays flat;
  flat.vertices = {0, 0, 0, 1, 0, 0, 2, 0, 0};
  flat.triangles = {0, 1, 2};
  EXPECT_TRUE(build_bvh(flat.mesh()).empty());
}

TEST_P(BvhShape, IdenticalCentroidsStillGiveSmallLeaves) {
  // 100 copies of one triangle: no SAH split exists and every Morton code is equal; the
  // builder must still bound leaves.
  test::Arrays a;
  for (int t = 0; t < 100; ++t) {
    a.vertices.insert(a.vertices.end(), {0, 0, 0, 1, 0, 0, 0, 1, 0});
    a.triangles.insert(a.triangles.end(), {3 * t, 3 * t + 1, 3 * t + 2});
  }
  BvhConfig config;
  config.morton_below = GetParam();
  const Bvh bvh = build_bvh(a.mesh(), config);
  for (const auto& node : bvh.nodes) EXPECT_LE(node.count, BvhConfig().max_leaf_size);
}

TEST(Bvh, ExitTestSeesTheFaceTheRayLeavesThrough) {
  // From inside a box, every ray leaves through a face whose outward normal it follows.
  const Bvh bvh = build_bvh(test::box(2, 2, 2).mesh());
  const kern::SdfHit up = kern::sdf_bvh_closest_hit(bvh.nodes.data(), bvh.triangles.data(),
                                                    {0.1f, 0.2f, 0}, {0, 0, 1}, 0.0f, -1);
  EXPECT_FLOAT_EQ(up.t, 1.0f);
  EXPECT_LT(up.det, 0.0f);
  // From outside, looking in: the first hit is a front face.
  const kern::SdfHit in = kern::sdf_bvh_closest_hit(bvh.nodes.data(), bvh.triangles.data(),
                                                    {0.1f, 0.2f, 3}, {0, 0, -1}, 0.0f, -1);
  EXPECT_FLOAT_EQ(in.t, 2.0f);
  EXPECT_GT(in.det, 0.0f);
}

TEST(Bvh, RaysAlongAnAxisAreNotLostFarFromTheCentre) {
  // Two unit-thick plates 2e12 apart, 4e12 wide: rays go up from the lower plate's top face,
  // along z, with x and y components that are zero or round-off small. o * (1 / d) once
  // overflowed there (1e30 stood in for 1 / 0), and every box was missed.
  test::Arrays a;
  const float w = 2e12f, lo = -1e12f, hi = 1e12f;
  for (float z : {lo, hi}) {
    const int base = static_cast<int>(a.vertices.size() / 3);
    a.vertices.insert(a.vertices.end(), {-w, -w, z, w, -w, z, w, w, z, -w, w, z});
    a.triangles.insert(a.triangles.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
  }
  Bvh bvh = build_bvh(a.mesh());
  grow_boxes_to_cover_hits(bvh);
  const Bvh4 wide = collapse_to_bvh4(bvh);
  for (float tiny : {0.0f, 1e-31f, 5e-29f, 1e-27f, 1e-20f}) {
    const glm::vec3 o(1e12f, -5e11f, lo);
    const glm::vec3 d = glm::normalize(glm::vec3(tiny, -tiny, 1.0f));
    const kern::SdfHit want = brute_force(bvh, o, d, 1.0f, -1);
    ASSERT_NEAR(want.t, 2e12f, 1e6f) << "tiny " << tiny;
    EXPECT_EQ(kern::sdf_bvh_closest_hit(bvh.nodes.data(), bvh.triangles.data(), o, d, 1.0f, -1).t,
              want.t)
        << "binary, tiny " << tiny;
#if SDF_HAVE_BVH4_SSE
    EXPECT_EQ(bvh4_closest_hit(wide, o, d, 1.0f, -1).t, want.t) << "4-wide, tiny " << tiny;
#endif
#if SDF_HAVE_BVH8
    if (bvh8_supported()) {
      const Bvh8 wide8 = collapse_to_bvh8(bvh);
      EXPECT_EQ(bvh8_closest_hit_avx2(wide8, o, d, 1.0f, -1).t, want.t) << "8-wide, tiny " << tiny;
    }
#endif
  }
}

}  // namespace
}  // namespace sdf

// A triangle of edges 1e-20 has det = 1e-40 (a float denormal, not zero): 1 / det overflows
// to infinity, and with s orthogonal to d x e2, u = 0 * inf and t = 0 * inf are NaN. Every
// ordered comparison lets a NaN through; the test must still turn the hit away, or engines
// whose min/max treat NaN differently would disagree.
TEST(Intersect, ATriangleWhoseInverseDeterminantOverflowsIsNeverHit) {
  const sdf::kern::SdfTriangle tiny{-1.0f, 0.0f, 0.0f,   7,    0.0f, 1e-20f,
                                    0.0f,  0.0f, 1e-20f, 0.0f, 0.0f, 0.0f};
  const glm::vec3 origin(0.0f, 0.0f, 0.0f), direction(0.0f, 0.0f, 1.0f);
  sdf::kern::SdfHit hit{INFINITY, 0.0f, -1};
  sdf::kern::sdf_intersect_triangle(origin, direction, 0.0f, &tiny, &hit);
  EXPECT_EQ(hit.id, -1);
  EXPECT_EQ(hit.t, INFINITY);
}
