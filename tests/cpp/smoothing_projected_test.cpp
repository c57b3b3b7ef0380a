// SPDX-License-Identifier: GPL-3.0-or-later
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "post/smoothing_projected.h"
#include "smoothing_test_meshes.h"

namespace sdf {
namespace {

// Points spread over a few clusters, with values.
void cloud(std::size_t n, std::vector<glm::vec3>& p, std::vector<float>& v) {
  std::mt19937 rng(11);
  std::normal_distribution<float> g(0.0f, 0.05f);
  std::uniform_int_distribution<int> pick(0, 3);
  const glm::vec3 centres[4] = {{0, 0, 0}, {1, 0, 0}, {0, 2, 0}, {0, 0, 3}};
  for (std::size_t i = 0; i < n; ++i) {
    const int c = pick(rng);
    p.push_back(centres[c] + glm::vec3(g(rng), g(rng), g(rng)));
    v.push_back(0.1f * (c + 1) + std::fabs(g(rng)));
  }
}

TEST(PointOctree, NodesSumUpAndFollowTheBranchRules) {
  std::vector<glm::vec3> p;
  std::vector<float> v;
  cloud(20000, p, v);
  ProjectedOptions o;
  const auto nodes = build_point_octree(p.data(), v.data(), p.size(), o);
  ASSERT_FALSE(nodes.empty());
  EXPECT_EQ(nodes[0].count, p.size());
  double total = 0.0;
  for (float x : v) total += x;
  EXPECT_NEAR(nodes[0].mean, total / v.size(), 1e-5);
  std::size_t leaves = 0, leaf_points = 0;
  for (const PointOctreeNode& n : nodes) {
    if (n.first_child < 0) {
      ++leaves;
      leaf_points += n.count;
      continue;
    }
    // Branching nodes hold more than 0.2% of the points and a mean at most their side.
    EXPECT_GT(n.count, 0.002 * p.size());
    EXPECT_LE(n.mean, 2.0f * n.half_side);
    std::uint32_t count = 0;
    double sum = 0.0;
    for (std::uint32_t c = 0; c < n.child_count; ++c) {
      const PointOctreeNode& child = nodes[n.first_child + c];
      EXPECT_FLOAT_EQ(child.half_side, 0.5f * n.half_side);
      count += child.count;
      sum += double(child.mean) * child.count;
    }
    EXPECT_EQ(count, n.count);
    EXPECT_NEAR(sum / count, n.mean, 1e-5);
  }
  EXPECT_EQ(leaf_points, p.size());
  EXPECT_GT(leaves, 4u);
  // Every point lies in its leaf's cube: walk down from the root.
  for (std::size_t i = 0; i < p.size(); i += 97) {
    const PointOctreeNode* n = &nodes[0];
    for (int depth = 0; n->first_child >= 0; ++depth) {
      ASSERT_LE(depth, o.max_depth);
      const PointOctreeNode* next = nullptr;
      for (std::uint32_t c = 0; c < n->child_count; ++c) {
        const PointOctreeNode& child = nodes[n->first_child + c];
        if (std::fabs(p[i].x - child.center[0]) <= child.half_side &&
            std::fabs(p[i].y - child.center[1]) <= child.half_side &&
            std::fabs(p[i].z - child.center[2]) <= child.half_side)
          next = &child;
      }
      ASSERT_NE(next, nullptr) << i;
      n = next;
    }
  }
}

TEST(PointOctree, DepthZeroIsOneNode) {
  std::vector<glm::vec3> p;
  std::vector<float> v;
  cloud(1000, p, v);
  ProjectedOptions o;
  o.max_depth = 0;
  EXPECT_EQ(build_point_octree(p.data(), v.data(), p.size(), o).size(), 1u);
}

TEST(PointOctree, BranchingOnTheMinimumSplitsMixedNodes) {
  // Thin points (value 0.01) among thick ones (value 1) in a unit cube: by the mean (about 1)
  // no node below side 1 splits; by the minimum, nodes split down to the thin points' size.
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<glm::vec3> p;
  std::vector<float> v;
  for (int i = 0; i < 4000; ++i) {
    p.push_back({u(rng), u(rng), u(rng)});
    v.push_back(i % 50 == 0 ? 0.01f : 1.0f);
  }
  ProjectedOptions mean, min;
  min.branch_on = ProjectedOptions::Branch::Min;
  const auto by_mean = build_point_octree(p.data(), v.data(), p.size(), mean);
  const auto by_min = build_point_octree(p.data(), v.data(), p.size(), min);
  EXPECT_LT(by_mean.size(), 10u);
  EXPECT_GT(by_min.size(), 100u);
}

TEST(PointOctree, FixedPointSumsKeepMeansExactForAnyScaleAndCount) {
  // Node sums are integers of 2^-shift units (kern::sdf_fixed_value): a constant's mean must
  // come back exactly, with no sum overflowing, from tiny to huge values and counts.
  for (float value : {1e-30f, 3.7e-5f, 1.0f, 0.1f, 6.02e20f}) {
    for (std::size_t n : {std::size_t{1}, std::size_t{1000}, std::size_t{1} << 20}) {
      std::vector<glm::vec3> p(n);
      for (std::size_t i = 0; i < n; ++i)
        p[i] = glm::vec3(float(i % 101), float(i % 37), float(i % 13)) * value;
      const std::vector<float> v(n, value);
      ProjectedOptions o;
      o.node_size_ratio = 1e30;  // branch wherever the counts allow
      const auto nodes = build_point_octree(p.data(), v.data(), n, o);
      for (const PointOctreeNode& node : nodes) ASSERT_EQ(node.mean, value) << value << " " << n;
    }
  }
  // Mixed magnitudes: a mean's relative error stays at float precision (values down to
  // 2^-24 of the largest keep 16 of their bits or more).
  std::vector<glm::vec3> p;
  std::vector<float> v;
  cloud(50000, p, v);
  for (std::size_t i = 0; i < v.size(); i += 3) v[i] *= 1e-4f;
  const auto nodes = build_point_octree(p.data(), v.data(), p.size(), ProjectedOptions{});
  double total = 0.0;
  for (float x : v) total += x;
  EXPECT_NEAR(nodes[0].mean, total / v.size(), 1e-7 * total / v.size());
}

TEST(CubeFraction, LimitsAndShape) {
  const float side = 1.0f, rho = 0.62035049f;
  EXPECT_EQ(cube_fraction_in_sphere(side, 5.0f, 1.0f), 0.0f);  // far apart
  EXPECT_EQ(cube_fraction_in_sphere(side, 0.1f, 3.0f), 1.0f);  // the sphere holds it
  EXPECT_NEAR(cube_fraction_in_sphere(side, 0.0f, 0.1f), std::pow(0.1f / rho, 3.0f), 1e-6);
  EXPECT_EQ(cube_fraction_in_sphere(side, 0.0f, 0.0f), 0.0f);
  // Falls from 1 to 0 as the centres move apart, continuously at both ends of the lens.
  float previous = 1.0f;
  for (float d = 0.0f; d < 2.0f; d += 0.01f) {
    const float f = cube_fraction_in_sphere(side, d, 0.8f);
    ASSERT_LE(f, previous + 1e-6f);
    ASSERT_GE(f, 0.0f);
    previous = f;
  }
  EXPECT_NEAR(cube_fraction_in_sphere(side, 0.8f - rho + 1e-4f, 0.8f), 1.0f, 1e-3);
  EXPECT_NEAR(cube_fraction_in_sphere(side, 0.8f + rho - 1e-4f, 0.8f), 0.0f, 1e-3);
  // Half-way (centre on the sphere, ball much smaller): about half inside.
  EXPECT_NEAR(cube_fraction_in_sphere(0.01f, 10.0f, 10.0f), 0.5f, 0.01f);
}

TEST(GatherSphere, WholeTreeAndNothing) {
  std::vector<glm::vec3> p;
  std::vector<float> v;
  cloud(5000, p, v);
  ProjectedOptions o;
  o.min_points = 0.0;
  o.node_size_ratio = 100.0;  // a deep tree
  const auto nodes = build_point_octree(p.data(), v.data(), p.size(), o);
  float mean = -1.0f;
  ASSERT_TRUE(gather_sphere(nodes.data(), glm::vec3(0.5f, 1.0f, 1.5f), 100.0f, &mean));
  EXPECT_NEAR(mean, nodes[0].mean, 1e-6);
  EXPECT_FALSE(gather_sphere(nodes.data(), glm::vec3(50.0f), 1.0f, &mean));
  // A sphere around one cluster gathers that cluster's values only: (0.4, ...] at (0, 0, 3).
  ASSERT_TRUE(gather_sphere(nodes.data(), glm::vec3(0, 0, 3), 0.5f, &mean));
  EXPECT_GT(mean, 0.4f);
  EXPECT_LT(mean, 0.5f);
}

TEST(ProjectedSmoothing, SphereOfConstantDiameterStaysPut) {
  // On a sphere every point projects near the centre; noise around 2r averages out.
  const Mesh mesh = test::icosphere(3).mesh();
  for (PointKind kind : {PointKind::Faces, PointKind::Vertices}) {
    const std::size_t n = kind == PointKind::Faces ? mesh.triangles.size() : mesh.vertices.size();
    const std::vector<float> v = test::noisy(n, 1.8f, 0.1f, 2);
    ProjectedOptions o;
    const std::vector<float> s = smooth_projected(mesh, kind, v.data(), o);
    for (float x : s) ASSERT_NEAR(x, 1.8f, 0.01f);
    EXPECT_LT(test::variance(s), 0.05 * test::variance(v));
  }
}

TEST(ProjectedSmoothing, ConstantStaysExactlyConstantAndZeroIterationsIsIdentity) {
  const Mesh mesh = test::split_cube(6).mesh();
  const std::vector<float> c(mesh.triangles.size(), 0.3f);
  ProjectedOptions o;
  o.iterations = 3;
  EXPECT_EQ(smooth_projected(mesh, PointKind::Faces, c.data(), o), c);
  const std::vector<float> v = test::noisy(mesh.triangles.size(), 2.0f, 0.5f, 4);
  o.iterations = 0;
  EXPECT_EQ(smooth_projected(mesh, PointKind::Faces, v.data(), o), v);
}

TEST(ProjectedSmoothing, NoiseGoesDownWithIterationsAndStaysInRange) {
  const Mesh mesh = test::split_cube(12).mesh();  // SDF of a cube: about its side, 2
  const std::vector<float> v = test::noisy(mesh.triangles.size(), 1.6f, 0.4f, 8);
  const auto [lo, hi] = std::minmax_element(v.begin(), v.end());
  double previous = test::variance(v);
  for (int iterations : {1, 2}) {
    ProjectedOptions o;
    o.iterations = iterations;
    const std::vector<float> s = smooth_projected(mesh, PointKind::Faces, v.data(), o);
    const double now = test::variance(s);
    EXPECT_LT(now, 0.5 * previous);
    previous = now;
    for (float x : s) {
      ASSERT_GE(x, *lo);
      ASSERT_LE(x, *hi);
    }
  }
}

TEST(ProjectedSmoothing, SameResultForAnyThreadCount) {
  const Mesh mesh = test::icosphere(4).mesh();
  const std::vector<float> v = test::noisy(mesh.triangles.size(), 1.8f, 0.3f, 10);
  ProjectedOptions one, many;
  one.threads = 1;
  many.threads = 5;
  EXPECT_EQ(smooth_projected(mesh, PointKind::Faces, v.data(), one),
            smooth_projected(mesh, PointKind::Faces, v.data(), many));
}

TEST(ProjectedSmoothing, RejectsBadInput) {
  const Mesh mesh = test::icosphere(1).mesh();
  std::vector<float> v(mesh.triangles.size(), 1.0f);
  ProjectedOptions o;
  o.max_depth = 21;
  EXPECT_THROW(smooth_projected(mesh, PointKind::Faces, v.data(), o), std::invalid_argument);
  o = ProjectedOptions();
  o.min_points = 2.0;
  EXPECT_THROW(smooth_projected(mesh, PointKind::Faces, v.data(), o), std::invalid_argument);
  v[0] = -1.0f;
  EXPECT_THROW(smooth_projected(mesh, PointKind::Faces, v.data(), ProjectedOptions()),
               std::invalid_argument);
}

}  // namespace
}  // namespace sdf
