// SPDX-License-Identifier: GPL-3.0-or-later
// Slivers lying across the axes enter the BVH as pieces (bvh_split.h): the pieces' boxes cover
// their triangle, the casts find what a test of every face finds, well-shaped meshes are left
// as they were, and the cut follows neither the thread count nor the winding.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include "accel/bvh.h"
#include "accel/bvh_margin.h"
#include "smoothing_test_meshes.h"
#include "test_meshes.h"
#include "traverse/sdf_bvh_traverse.h"
#include "util/test_overrides.h"

namespace sdf {
namespace {

// A disc fanned from its centre into `n` slivers (as CAD exports close a cylinder), tilted
// out of the axis planes, and a unit box around it.
test::Arrays fan_in_a_box(int n) {
  test::Arrays a = test::box(2.0, 2.0, 2.0);
  const std::int64_t centre = static_cast<std::int64_t>(a.vertices.size() / 3);
  const glm::dvec3 u = glm::normalize(glm::dvec3(1.0, 0.3, 0.2));
  const glm::dvec3 v = glm::normalize(glm::cross(u, glm::dvec3(0.1, 0.2, 1.0)));
  a.vertices.insert(a.vertices.end(), {0.0, 0.0, 0.0});
  for (int k = 0; k < n; ++k) {
    const double angle = 2.0 * M_PI * k / n;
    const glm::dvec3 p = 0.9 * (std::cos(angle) * u + std::sin(angle) * v);
    a.vertices.insert(a.vertices.end(), {p.x, p.y, p.z});
  }
  for (int k = 0; k < n; ++k)
    a.triangles.insert(a.triangles.end(), {centre, centre + 1 + k, centre + 1 + (k + 1) % n});
  return a;
}

kern::SdfTriangle record_of(const Mesh& mesh, std::size_t f) {
  const glm::uvec3 t = mesh.triangles[f];
  const glm::vec3 v0 = mesh.vertices[t.x];
  const glm::vec3 e1 = mesh.vertices[t.y] - v0, e2 = mesh.vertices[t.z] - v0;
  return kern::SdfTriangle{v0.x, v0.y, v0.z, static_cast<std::int32_t>(f),
                           e1.x, e1.y, e1.z, 0.0f,
                           e2.x, e2.y, e2.z, 0.0f};
}

// Every face of the mesh, in order: independent of the tree and of its records.
kern::SdfHit every_face(const Mesh& mesh, glm::vec3 o, glm::vec3 d, float tmin) {
  kern::SdfHit hit{INFINITY, 0.0f, -1};
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    const kern::SdfTriangle tri = record_of(mesh, f);
    kern::sdf_intersect_triangle(o, d, tmin, &tri, &hit);
  }
  return hit;
}

bool inside(const kern::SdfBvhNode& n, glm::vec3 p) {
  return p.x >= n.lo_x && p.y >= n.lo_y && p.z >= n.lo_z && p.x <= n.hi_x && p.y <= n.hi_y &&
         p.z <= n.hi_z;
}

TEST(BvhSplit, SliversAreCutWithinTheBudget) {
  // Nearly every face a sliver: most want 16 pieces, the budget (twice the faces added at
  // most) gives them 2; beside many fat faces, the same slivers get more.
  const Mesh slivers = fan_in_a_box(4000).mesh();
  const std::size_t cut = build_bvh(slivers).triangles.size();
  EXPECT_GE(cut, 2 * slivers.triangles.size() - 12);
  EXPECT_LE(cut, 3 * slivers.triangles.size());
  test::Arrays few = fan_in_a_box(4000);
  const test::Arrays fat = test::icosphere(6, 0.5);
  const std::int64_t base = static_cast<std::int64_t>(few.vertices.size() / 3);
  few.vertices.insert(few.vertices.end(), fat.vertices.begin(), fat.vertices.end());
  for (const std::int64_t index : fat.triangles) few.triangles.push_back(base + index);
  const Mesh mixed = few.mesh();
  const std::size_t added = build_bvh(mixed).triangles.size() - mixed.triangles.size();
  EXPECT_GT(added, 4000u * 7);  // more than 8 pieces a sliver on average
  EXPECT_LE(added, 4000u * 15);
}

TEST(BvhSplit, TheTestOverrideBuildsWithoutCutting) {
  // bench/slivers.py compares the cut tree with one that cuts nothing.
  const Mesh slivers = fan_in_a_box(4000).mesh();
  const bool before = test_overrides().no_sliver_cutting;
  test_overrides().no_sliver_cutting = true;
  const std::size_t uncut = build_bvh(slivers).triangles.size();
  test_overrides().no_sliver_cutting = before;
  EXPECT_EQ(uncut, slivers.triangles.size());
  EXPECT_GT(build_bvh(slivers).triangles.size(), uncut);
}

TEST(BvhSplit, WellShapedTrianglesAreNotCut) {
  // A box and a sphere: every face once, as before cutting existed.
  for (const test::Arrays& a : {test::box(1.0, 2.0, 3.0), test::icosphere(5)}) {
    const Mesh mesh = a.mesh();
    EXPECT_EQ(build_bvh(mesh).triangles.size(), mesh.triangles.size());
  }
}

TEST(BvhSplit, PiecesCoverTheirTriangle) {
  // Points spread over every sliver each lie in some leaf that holds the sliver.
  const Mesh mesh = fan_in_a_box(2000).mesh();
  const Bvh bvh = build_bvh(mesh);
  std::vector<std::vector<int>> leaves_of(mesh.triangles.size());
  for (std::size_t i = 0; i < bvh.nodes.size(); ++i) {
    const kern::SdfBvhNode& n = bvh.nodes[i];
    for (int k = n.first; n.count > 0 && k < n.first + n.count; ++k)
      leaves_of[bvh.triangles[k].id].push_back(static_cast<int>(i));
  }
  int points = 0;
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    const glm::uvec3 t = mesh.triangles[f];
    const glm::vec3 a = mesh.vertices[t.x], b = mesh.vertices[t.y], c = mesh.vertices[t.z];
    for (int i = 0; i <= 8; ++i)
      for (int j = 0; i + j <= 8; ++j, ++points) {
        const float s = i / 8.0f, r = j / 8.0f;
        const glm::vec3 p = a + s * (b - a) + r * (c - a);
        bool found = false;
        for (int leaf : leaves_of[f]) found = found || inside(bvh.nodes[leaf], p);
        ASSERT_TRUE(found) << "face " << f << " point " << i << "," << j;
      }
  }
  EXPECT_GT(points, 80000);
}

TEST(BvhSplit, ClosestHitsEqualATestOfEveryFace) {
  // Rays from the box's walls and from points on the disc, as the SDF casts them.
  for (const int n : {64, 3000}) {
    const Mesh mesh = fan_in_a_box(n).mesh();
    Bvh bvh = build_bvh(mesh);
    grow_boxes_to_cover_hits(bvh);
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(-0.99f, 0.99f);
    int hits_on_the_disc = 0;
    for (int r = 0; r < 4000; ++r) {
      const glm::vec3 o(u(rng), u(rng), u(rng));
      const glm::vec3 d = glm::normalize(glm::vec3(u(rng), u(rng), u(rng)));
      const kern::SdfHit a =
          kern::sdf_bvh_closest_hit(bvh.nodes.data(), bvh.triangles.data(), o, d, 1e-4f, -1);
      const kern::SdfHit b = every_face(mesh, o, d, 1e-4f);
      ASSERT_EQ(a.t, b.t) << "fan of " << n << ", ray " << r;
      hits_on_the_disc += b.id >= 12;
    }
    EXPECT_GT(hits_on_the_disc, 500);
  }
}

TEST(BvhSplit, TheCutIgnoresThreadsAndWinding) {
  test::Arrays a = fan_in_a_box(3000);
  const Mesh mesh = a.mesh();
  BvhConfig one, many;
  one.threads = 1;
  many.threads = 3;
  const Bvh first = build_bvh(mesh, one), second = build_bvh(mesh, many);
  ASSERT_EQ(first.nodes.size(), second.nodes.size());
  EXPECT_EQ(std::memcmp(first.nodes.data(), second.nodes.data(),
                        first.nodes.size() * sizeof first.nodes[0]),
            0);
  // Every face reversed as orientation does (two corners swapped): the same tree, and the
  // records rewritten from the reversed mesh equal those built from it.
  for (std::size_t f = 0; f < a.triangles.size(); f += 3)
    std::swap(a.triangles[f + 1], a.triangles[f + 2]);
  const Mesh turned = a.mesh();
  Bvh rewritten = build_bvh(mesh);
  const Bvh built = build_bvh(turned);
  ASSERT_EQ(rewritten.nodes.size(), built.nodes.size());
  EXPECT_EQ(std::memcmp(rewritten.nodes.data(), built.nodes.data(),
                        built.nodes.size() * sizeof built.nodes[0]),
            0);
  rewrite_triangles(rewritten, turned);
  EXPECT_EQ(std::memcmp(rewritten.triangles.data(), built.triangles.data(),
                        built.triangles.size() * sizeof built.triangles[0]),
            0);
}

}  // namespace
}  // namespace sdf
