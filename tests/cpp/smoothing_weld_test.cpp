// SPDX-License-Identifier: GPL-3.0-or-later
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>
#include <vector>

#include "adjacency_reference.h"
#include "mesh/mesh_weld.h"
#include "smoothing_test_meshes.h"
#include "weld_reference.h"

namespace sdf {
namespace {

TEST(WeldVertices, MergesTheSplitSidesOfACube) {
  const int n = 4;
  const Mesh mesh = test::split_cube(n).mesh();
  const Weld weld = weld_vertices(mesh.vertices.data(), mesh.vertices.size(), weld_tolerance(mesh));
  EXPECT_EQ(weld.count, 6u * n * n + 2u);  // a closed cube grid: V = F / 2 + 2
  EXPECT_EQ(weld.merged[0], 0u);
  // Merged vertices sit at one position, and are numbered by first appearance.
  std::uint32_t highest = 0;
  for (std::size_t v = 0; v < mesh.vertices.size(); ++v) {
    EXPECT_LE(weld.merged[v], highest + 1);
    if (weld.merged[v] > highest) highest = weld.merged[v];
  }
  std::vector<glm::vec3> first(weld.count, glm::vec3(NAN));
  for (std::size_t v = 0; v < mesh.vertices.size(); ++v) {
    if (std::isnan(first[weld.merged[v]].x)) first[weld.merged[v]] = mesh.vertices[v];
    EXPECT_EQ(first[weld.merged[v]], mesh.vertices[v]);
  }
  // Every edge of the welded cube has exactly two faces.
  const auto tris = welded_triangles(mesh, weld);
  const Adjacency vf = faces_of_vertices(tris.data(), tris.size(), weld.count);
  const Adjacency vv = vertex_neighbours(tris.data(), vf);
  std::size_t edges = 0;
  for (std::size_t v = 0; v < vv.size(); ++v) edges += vv.offsets[v + 1] - vv.offsets[v];
  EXPECT_EQ(edges / 2, 3 * tris.size() / 2);
}

TEST(WeldVertices, ToleranceDecides) {
  const std::vector<glm::vec3> p = {{0, 0, 0}, {1e-4f, 0, 0}, {0, 3e-4f, 0}, {-0.0f, 0, 0}};
  Weld exact = weld_vertices(p.data(), p.size(), 0.0f);
  EXPECT_EQ(exact.count, 3u);
  EXPECT_EQ(exact.merged, (std::vector<std::uint32_t>{0, 1, 2, 0}));  // -0 == +0
  Weld near = weld_vertices(p.data(), p.size(), 2e-4f);
  EXPECT_EQ(near.merged, (std::vector<std::uint32_t>{0, 0, 1, 0}));  // 3e-4 is too far from 0
  Weld wide = weld_vertices(p.data(), p.size(), 1.0f);
  EXPECT_EQ(wide.count, 1u);
}

TEST(WeldVertices, FindsNeighboursAcrossCellBorders) {
  // Pairs 1e-6 apart straddling many grid cell borders (cells are 2e-6 wide).
  std::vector<glm::vec3> p;
  for (int i = 0; i < 1000; ++i) {
    const float x = i * 2e-6f + 1e-6f;
    p.push_back({x - 4e-7f, 0.5f, -0.25f});
    p.push_back({x + 4e-7f, 0.5f, -0.25f});
  }
  const Weld weld = weld_vertices(p.data(), p.size(), 1e-6f);
  for (int i = 0; i < 1000; ++i) EXPECT_EQ(weld.merged[2 * i], weld.merged[2 * i + 1]);
}

TEST(Adjacency, FacesAndNeighboursOfAGrid) {
  const Mesh mesh = test::grid(2, 1).mesh();  // 6 vertices, 4 triangles
  const Weld weld = weld_vertices(mesh.vertices.data(), mesh.vertices.size(), 0.0f);
  const auto tris = welded_triangles(mesh, weld);
  const Adjacency vf = faces_of_vertices(tris.data(), tris.size(), weld.count);
  const Adjacency vv = vertex_neighbours(tris.data(), vf);
  // Vertex 1 (bottom middle): faces 0, 2, 3; neighbours 0, 2, 4 and the diagonal 5.
  std::vector<std::uint32_t> f1(vf.items.begin() + vf.offsets[1], vf.items.begin() + vf.offsets[2]);
  EXPECT_EQ(f1, (std::vector<std::uint32_t>{0, 2, 3}));
  std::vector<std::uint32_t> n1(vv.items.begin() + vv.offsets[1], vv.items.begin() + vv.offsets[2]);
  EXPECT_EQ(n1, (std::vector<std::uint32_t>{0, 2, 4, 5}));
}

TEST(VertexNeighbours, SameListsForAnyThreadCount) {
  // 40,962 vertices: three blocks of 16k listed by different workers.
  const Mesh mesh = test::icosphere(6).mesh();
  const Weld weld = weld_vertices(mesh.vertices.data(), mesh.vertices.size(), 0.0f);
  const auto tris = welded_triangles(mesh, weld);
  const Adjacency vf = faces_of_vertices(tris.data(), tris.size(), weld.count);
  const Adjacency one = vertex_neighbours(tris.data(), vf, 1);
  const Adjacency many = vertex_neighbours(tris.data(), vf, 3);
  EXPECT_EQ(one.offsets, many.offsets);
  EXPECT_EQ(one.items, many.items);
  // Each list increasing, without the vertex itself (an icosphere vertex has 5 or 6).
  for (std::size_t v = 0; v < one.size(); ++v) {
    const std::uint32_t count = one.offsets[v + 1] - one.offsets[v];
    ASSERT_TRUE(count == 5 || count == 6) << v;
    for (std::uint32_t j = one.offsets[v]; j < one.offsets[v + 1]; ++j) {
      ASSERT_NE(one.items[j], v);
      if (j > one.offsets[v]) ASSERT_LT(one.items[j - 1], one.items[j]);
    }
  }
}

// Random triangles over `vertex_count` vertices, scattered over the index range (so that a
// block of faces meets every range of vertices), some with corners merged into one vertex
// (listed once per distinct corner), and the last vertices unused.
std::vector<glm::uvec3> scattered_triangles(std::size_t faces, std::uint32_t vertex_count,
                                            unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<std::uint32_t> vertex(0, vertex_count - 100);
  std::vector<glm::uvec3> t(faces);
  for (std::size_t f = 0; f < faces; ++f) {
    t[f] = glm::uvec3(vertex(rng), vertex(rng), vertex(rng));
    if (f % 7 == 0) t[f].y = t[f].x;
    if (f % 11 == 0) t[f].z = t[f].y;
  }
  return t;
}

// A fan of `faces` triangles around vertex 0, its ring numbered in shuffled order: a vertex
// of very high valence (fan-triangulated caps, poles), and ring vertices of valence 2.
std::vector<glm::uvec3> shuffled_fan(std::uint32_t faces, unsigned seed) {
  std::vector<std::uint32_t> ring(faces);
  for (std::uint32_t i = 0; i < faces; ++i) ring[i] = i + 1;
  std::shuffle(ring.begin(), ring.end(), std::mt19937(seed));
  std::vector<glm::uvec3> t(faces);
  for (std::uint32_t i = 0; i < faces; ++i) t[i] = glm::uvec3(0, ring[i], ring[(i + 1) % faces]);
  return t;
}

// The parallel lists against the serial ones they replaced: welded meshes (seams merged,
// Morton-like locality), scattered triangles (300k faces: more face blocks than one thread's
// 8; the last vertices unused) and a fan (one vertex of valence 20000), on 1 to 8 threads.
TEST(Adjacency, SameAsTheSerialListsForAnyThreadCount) {
  std::vector<std::pair<std::vector<glm::uvec3>, std::uint32_t>> cases;
  for (const Mesh& mesh : {test::split_cube(20).mesh(), test::icosphere(6).mesh()}) {
    const Weld weld =
        weld_vertices(mesh.vertices.data(), mesh.vertices.size(), weld_tolerance(mesh));
    cases.emplace_back(welded_triangles(mesh, weld), weld.count);
  }
  cases.emplace_back(scattered_triangles(300000, 120000, 5), 120000);
  cases.emplace_back(scattered_triangles(1000, 5000, 6), 5000);
  cases.emplace_back(shuffled_fan(20000, 7), 20001);
  for (const auto& [tris, vertex_count] : cases) {
    const Adjacency vf = test_reference::reference_faces_of_vertices(tris, vertex_count);
    const Adjacency vv = test_reference::reference_vertex_neighbours(tris, vf);
    for (unsigned threads : {1u, 2u, 3u, 8u}) {
      const Adjacency got_vf = faces_of_vertices(tris.data(), tris.size(), vertex_count, threads);
      ASSERT_EQ(got_vf.offsets, vf.offsets) << tris.size() << " faces, " << threads << " threads";
      ASSERT_EQ(got_vf.items, vf.items) << tris.size() << " faces, " << threads << " threads";
      const Adjacency got_vv = vertex_neighbours(tris.data(), vf, threads);
      ASSERT_EQ(got_vv.offsets, vv.offsets) << tris.size() << " faces, " << threads << " threads";
      ASSERT_EQ(got_vv.items, vv.items) << tris.size() << " faces, " << threads << " threads";
    }
  }
}

// The parallel weld against the serial greedy it replaced: clusters of near copies (some in
// chains longer than the tolerance, some across cell borders), exact duplicates with +0 and
// -0, and lone points; tolerance 0 (exact), small and large; any thread count.
TEST(WeldVertices, SameAsTheSerialGreedyForAnyThreadCount) {
  std::mt19937 rng(17);
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
  std::vector<glm::vec3> p;
  for (int c = 0; c < 30000; ++c) {
    const glm::vec3 centre(unit(rng), unit(rng), unit(rng));
    p.push_back(centre);
    switch (c % 5) {
      case 0:  // a chain: each step within 1e-3 of the last, the ends farther apart
        for (int k = 1; k < 5; ++k) p.push_back(centre + glm::vec3(0.0007f * k, 0.0f, 0.0f));
        break;
      case 1:  // exact copies, one with -0 where the centre has +0
        p.push_back(centre);
        p.push_back(glm::vec3(centre.x, 0.0f, centre.z));
        p.push_back(glm::vec3(centre.x, -0.0f, centre.z));
        break;
      case 2:  // a cloud
        for (int k = 0; k < 3; ++k)
          p.push_back(centre + 0.0004f * glm::vec3(unit(rng), unit(rng), unit(rng)));
        break;
      default:  // alone
        break;
    }
  }
  std::shuffle(p.begin() + p.size() / 2, p.end(), rng);  // later copies before their originals
  for (float tolerance : {0.0f, 1e-6f, 1e-3f, 5e-3f}) {
    const Weld expected = test_reference::reference_weld_vertices(p.data(), p.size(), tolerance);
    EXPECT_LT(expected.count, p.size());  // something merged
    for (unsigned threads : {1u, 3u}) {
      const Weld got = weld_vertices(p.data(), p.size(), tolerance, threads);
      ASSERT_EQ(got.count, expected.count) << "tolerance " << tolerance << ", threads " << threads;
      ASSERT_EQ(got.merged, expected.merged)
          << "tolerance " << tolerance << ", threads " << threads;
    }
  }
}

// A tolerance whose square underflows: two points 2e-26 apart, tolerance 1e-26. The float
// distance test accepts the pair although one point's cell range misses the other's cell;
// the serial greedy merges them from the later side, and so must the parallel weld.
TEST(WeldVertices, UnderflowingToleranceSameAsTheSerialGreedy) {
  const std::vector<glm::vec3> p = {{1.5e-26f, 0, 0}, {-0.5e-26f, 0, 0}};
  const Weld expected = test_reference::reference_weld_vertices(p.data(), p.size(), 1e-26f);
  const Weld got = weld_vertices(p.data(), p.size(), 1e-26f, 2);
  EXPECT_EQ(got.count, expected.count);
  EXPECT_EQ(got.merged, expected.merged);
}

}  // namespace
}  // namespace sdf
