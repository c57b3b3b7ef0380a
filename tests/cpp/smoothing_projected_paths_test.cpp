// SPDX-License-Identifier: GPL-3.0-or-later
// The parallel projected-points smoothing (native/post/smoothing_projected.cpp) against the serial
// one it replaced (point_octree_reference.h): the same octree node for node and bit for bit,
// the same smoothed values, on any thread count. Inputs span several of its 16k-point chunks,
// keys past 32 bits (depth > 10), both branching rules, coincident points and points with no
// inward axis.
#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "point_octree_reference.h"
#include "post/smoothing_projected.h"
#include "smoothing_test_meshes.h"
#include "util/test_overrides.h"

namespace sdf {
namespace {

// Clusters of different spreads and values, with runs of coincident points (equal keys: their
// order in the sort decides the rounding of every later prefix sum). With `huge`, the cluster
// first in Morton order has values near 1e8, so the other nodes' sums are differences of two
// large prefix sums: any other summation order than the serial builder's changes their means
// (only the branch-on-minimum rule still splits such a tree).
void clustered_cloud(std::size_t n, unsigned seed, bool huge, std::vector<glm::vec3>& p,
                     std::vector<float>& v) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> g(0.0f, 1.0f);
  std::uniform_int_distribution<int> pick(0, 4);
  const glm::vec3 centres[5] = {{0, 0, 0}, {1, 0, 0}, {0, 2, 0}, {0, 0, 3}, {5, 5, 5}};
  const float spreads[5] = {0.05f, 0.3f, 0.01f, 0.5f, 1e-4f};
  for (std::size_t i = 0; i < n; ++i) {
    if (i % 97 == 5 && i > 0) {  // a copy of the previous point, with another value
      p.push_back(p.back());
      v.push_back(v.back() * 0.5f);
      continue;
    }
    const int c = pick(rng);
    p.push_back(centres[c] + spreads[c] * glm::vec3(g(rng), g(rng), g(rng)));
    const float scale = c == 0 && huge ? 1e8f : 0.1f * (c + 1);
    v.push_back(scale * (1.0f + 0.3f * std::fabs(g(rng))));
  }
}

void expect_same_nodes(const std::vector<PointOctreeNode>& a, const std::vector<PointOctreeNode>& b,
                       const char* what) {
  ASSERT_EQ(a.size(), b.size()) << what;
  for (std::size_t i = 0; i < a.size(); ++i)
    ASSERT_EQ(std::memcmp(&a[i], &b[i], sizeof(PointOctreeNode)), 0)
        << what << ": node " << i << " of " << a.size() << " (count " << a[i].count << " vs "
        << b[i].count << ", mean " << a[i].mean << " vs " << b[i].mean << ")";
}

struct Case {
  const char* name;
  int max_depth;
  double min_points, node_size_ratio;
  ProjectedOptions::Branch branch;
};

const Case kCases[] = {
    {"defaults", 8, 0.002, 1.0, ProjectedOptions::Branch::Mean},
    {"by minimum", 8, 0.002, 1.0, ProjectedOptions::Branch::Min},
    {"deep and fine", 8, 0.0, 100.0, ProjectedOptions::Branch::Mean},
    {"keys of 36 bits", 12, 0.0001, 1000.0, ProjectedOptions::Branch::Mean},
    {"keys of 60 bits, by minimum", 20, 0.0, 1e6, ProjectedOptions::Branch::Min},
    {"root only", 0, 0.0, 1.0, ProjectedOptions::Branch::Mean},
};

ProjectedOptions options_of(const Case& c, unsigned threads) {
  ProjectedOptions o;
  o.max_depth = c.max_depth;
  o.min_points = c.min_points;
  o.node_size_ratio = c.node_size_ratio;
  o.branch_on = c.branch;
  o.threads = threads;
  return o;
}

TEST(PointOctreePaths, SameNodesAsTheSerialBuilder) {
  for (bool huge : {false, true})
    for (std::size_t n : {1u, 7u, 5000u, 70000u}) {
      std::vector<glm::vec3> p;
      std::vector<float> v;
      clustered_cloud(n, static_cast<unsigned>(n), huge, p, v);
      for (const Case& c : kCases) {
        const auto expected = test::reference_point_octree(p.data(), v.data(), n, options_of(c, 1));
        for (unsigned threads : {1u, 3u}) {
          SCOPED_TRACE(std::string(c.name) + ", " + std::to_string(n) + " points" +
                       (huge ? " (huge values)" : "") + ", " + std::to_string(threads) +
                       " threads");
          expect_same_nodes(build_point_octree(p.data(), v.data(), n, options_of(c, threads)),
                            expected, c.name);
        }
        const bool splits = c.max_depth > 0 && (!huge || c.branch == ProjectedOptions::Branch::Min);
        if (n == 70000 && splits) EXPECT_GT(expected.size(), 8u) << c.name;
      }
    }
}

TEST(PointOctreePaths, BranchingOnTheMinimumFindsARareThinPoint) {
  // Thick points (value 1) in a unit cube with a thin one (0.001) now and then: a node splits
  // only if it holds a thin point, so a minimum that skips any of its points shows.
  std::mt19937 rng(8);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<glm::vec3> p;
  std::vector<float> v;
  for (int i = 0; i < 60000; ++i) {
    p.push_back({u(rng), u(rng), u(rng)});
    v.push_back(i % 1499 == 0 ? 0.001f : 1.0f);
  }
  ProjectedOptions o;
  o.branch_on = ProjectedOptions::Branch::Min;
  o.min_points = 0.0;
  o.threads = 2;
  const auto expected = test::reference_point_octree(p.data(), v.data(), p.size(), o);
  expect_same_nodes(build_point_octree(p.data(), v.data(), p.size(), o), expected, "thin points");
  EXPECT_GT(expected.size(), 100u);
}

// Acts out a CPU with or without AVX2 for its lifetime, then puts back what was there.
class ScopedCpu {
 public:
  explicit ScopedCpu(bool without_avx2) : old_(test_overrides().cpu_without_avx2) {
    test_overrides().cpu_without_avx2 = without_avx2;
  }
  ~ScopedCpu() { test_overrides().cpu_without_avx2 = old_; }

 private:
  bool old_;
};

// An icosphere with five zero-area faces (a repeated corner: no inward axis) and a vertex no
// face uses, so that some points stay out of the tree.
Mesh sphere_with_degenerate_points() {
  test::Arrays a = test::icosphere(6);  // 81,920 faces, 40,962 vertices: several chunks
  for (std::int64_t f = 0; f < 5; ++f) a.triangles.insert(a.triangles.end(), {f, f, f + 1});
  a.vertices.insert(a.vertices.end(), {0.1, 0.2, 0.3});
  return a.mesh();
}

TEST(ProjectedSmoothingPaths, SameValuesAsTheSerialVersion) {
  const Mesh mesh = sphere_with_degenerate_points();
  for (PointKind kind : {PointKind::Faces, PointKind::Vertices}) {
    const std::size_t n = kind == PointKind::Faces ? mesh.triangles.size() : mesh.vertices.size();
    std::vector<float> v = test::noisy(n, 1.8f, 0.6f, 21);
    for (std::size_t i = 0; i < n; i += 1000) v[i] = 0.0f;  // zero radius: gathers nothing
    for (const Case& c : kCases) {
      for (int iterations : {1, 2}) {
        ProjectedOptions o = options_of(c, 1);
        o.iterations = iterations;
        // A smaller sphere than the paper's on the coarse trees: on the deep ones it opens
        // most nodes down to the leaves, minutes of the reference's walk.
        o.radius = iterations == 2 && c.min_points >= 0.002 ? 0.25 : 1.0;
        const std::vector<float> expected =
            test::reference_smooth_projected(mesh, kind, v.data(), o);
        // The gather eight points at a time (AVX2), and the scalar one (as without AVX2).
        for (bool without_avx2 : {false, true})
          for (unsigned threads : {1u, 2u}) {
            SCOPED_TRACE(std::string(c.name) +
                         (kind == PointKind::Faces ? ", faces" : ", vertices") + ", " +
                         std::to_string(iterations) + " iterations, " + std::to_string(threads) +
                         " threads" + (without_avx2 ? ", as without AVX2" : ""));
            o.threads = threads;
            std::vector<float> got;
            {
              const ScopedCpu cpu(without_avx2);
              got = smooth_projected(mesh, kind, v.data(), o);
            }
            ASSERT_EQ(got.size(), expected.size());
            std::size_t differ = 0;
            for (std::size_t i = 0; i < n; ++i) differ += got[i] != expected[i];
            EXPECT_EQ(differ, 0u);
          }
        if (c.max_depth > 0) EXPECT_NE(expected, v) << "the case smooths something";
      }
    }
  }
}

}  // namespace
}  // namespace sdf
