// SPDX-License-Identifier: GPL-3.0-or-later
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "mesh/mesh_weld.h"
#include "post/smoothing_texture.h"
#include "post/uv_islands.h"
#include "smoothing_test_meshes.h"

namespace sdf {
namespace {

// Per-corner UVs of a grid mesh: its (x, y) mapped linearly onto [u0, u1] x [v0, v1].
void planar_uvs(const Mesh& mesh, float x0, float x1, float y0, float y1, float u0, float u1,
                float v0, float v1, std::vector<float>& uvs) {
  for (const glm::uvec3& t : mesh.triangles)
    for (int c = 0; c < 3; ++c) {
      const glm::vec3 p = mesh.vertices[t[c]] + glm::vec3(mesh.center);
      uvs.push_back(u0 + (p.x - x0) / (x1 - x0) * (u1 - u0));
      uvs.push_back(v0 + (p.y - y0) / (y1 - y0) * (v1 - v0));
    }
}

// Two 8 x 8 grids side by side in space and in UV, 2 texels apart at 64 x 64.
struct TwoSheets {
  Mesh mesh;
  std::vector<float> uvs;
  std::size_t half;
};

TwoSheets two_sheets() {
  test::Arrays a = test::grid(8, 8, 0.125);
  const test::Arrays b = test::grid(8, 8, 0.125, 1.5, 0.0);
  const std::int64_t offset = static_cast<std::int64_t>(a.vertices.size() / 3);
  a.vertices.insert(a.vertices.end(), b.vertices.begin(), b.vertices.end());
  for (std::int64_t t : b.triangles) a.triangles.push_back(t + offset);
  TwoSheets s;
  s.mesh = a.mesh();
  s.half = s.mesh.triangles.size() / 2;
  const Mesh& m = s.mesh;
  for (std::size_t f = 0; f < m.triangles.size(); ++f)
    for (int c = 0; c < 3; ++c) {
      const glm::vec3 p = m.vertices[m.triangles[f][c]] + glm::vec3(m.center);
      const bool right = f >= s.half;
      // Left sheet -> u in [0.05, 0.45]; right sheet -> u in [0.48, 0.88] (2 texels apart).
      s.uvs.push_back((right ? 0.48f : 0.05f) + 0.4f * (p.x - (right ? 1.5f : 0.0f)));
      s.uvs.push_back(0.1f + 0.4f * p.y);
    }
  return s;
}

TEST(UvIslands, SharedCornersJoinAndSeparateSheetsDoNot) {
  const TwoSheets s = two_sheets();
  const std::vector<std::int32_t> islands = uv_islands(s.mesh, s.uvs.data(), 1e-6);
  for (std::size_t f = 0; f < islands.size(); ++f) ASSERT_EQ(islands[f], f < s.half ? 0 : 1);
  // The split cube with one UV rectangle per side: the sides meet in space but not in UV.
  const Mesh cube = test::split_cube(3).mesh();
  std::vector<float> uvs;
  const std::size_t per_side = cube.triangles.size() / 6;
  for (std::size_t f = 0; f < cube.triangles.size(); ++f)
    for (int c = 0; c < 3; ++c) {
      const std::size_t side = f / per_side;
      const std::uint32_t v = cube.triangles[f][c] - static_cast<std::uint32_t>(side * 16);
      uvs.push_back(0.15f * side + 0.03f * (v % 4));
      uvs.push_back(0.03f * (v / 4));
    }
  const std::vector<std::int32_t> sides = uv_islands(cube, uvs.data(), 1e-6);
  for (std::size_t f = 0; f < sides.size(); ++f)
    ASSERT_EQ(sides[f], static_cast<std::int32_t>(f / per_side));
}

// The islands as the first, serial version labelled them: weld every vertex, then around each
// merged vertex join faces whose first corner there has the same UV; ids by first face.
std::vector<std::int32_t> reference_islands(const Mesh& mesh, const float* uvs, double tolerance) {
  const std::size_t m = mesh.triangles.size();
  Weld weld;
  if (tolerance >= 0.0) {
    weld =
        weld_vertices(mesh.vertices.data(), mesh.vertices.size(), weld_tolerance(mesh, tolerance));
  } else {
    for (std::uint32_t v = 0; v < mesh.vertices.size(); ++v) weld.merged.push_back(v);
    weld.count = static_cast<std::uint32_t>(mesh.vertices.size());
  }
  const std::vector<glm::uvec3> tris = welded_triangles(mesh, weld);
  const Adjacency vf = faces_of_vertices(tris.data(), tris.size(), weld.count);
  std::vector<std::uint32_t> parent(m);
  for (std::uint32_t f = 0; f < m; ++f) parent[f] = f;
  auto find = [&](std::uint32_t f) {
    while (parent[f] != f) f = parent[f];
    return f;
  };
  for (std::uint32_t v = 0; v < weld.count; ++v)
    for (std::uint32_t i = vf.offsets[v]; i < vf.offsets[v + 1]; ++i)
      for (std::uint32_t j = vf.offsets[v]; j < i; ++j) {
        auto uv = [&](std::uint32_t f) {
          for (int c = 0; c < 3; ++c)
            if (tris[f][c] == v)
              return std::make_pair(uvs[6 * f + 2 * c] + 0.0f, uvs[6 * f + 2 * c + 1] + 0.0f);
          return std::make_pair(0.0f, 0.0f);
        };
        if (uv(vf.items[i]) != uv(vf.items[j])) continue;
        const std::uint32_t a = find(vf.items[i]), b = find(vf.items[j]);
        parent[std::max(a, b)] = std::min(a, b);
      }
  std::vector<std::int32_t> island(m), id(m, -1);
  std::int32_t next = 0;
  for (std::uint32_t f = 0; f < m; ++f) {
    const std::uint32_t r = find(f);
    if (id[r] < 0) id[r] = next++;
    island[f] = id[r];
  }
  return island;
}

// A grid whose vertices on the column x = half are duplicated for the faces right of it (a
// normal seam, as glTF files split vertices), with continuous UVs.
struct SplitGrid {
  Mesh mesh;
  std::vector<float> uvs;
};

SplitGrid split_grid(int n) {
  test::Arrays a = test::grid(n, n, 1.0 / n);
  const std::int64_t count = static_cast<std::int64_t>(a.vertices.size() / 3);
  const int half = n / 2;
  for (int j = 0; j <= n; ++j) {
    const std::int64_t v = j * (n + 1) + half;
    a.vertices.insert(a.vertices.end(),
                      {a.vertices[3 * v], a.vertices[3 * v + 1], a.vertices[3 * v + 2]});
  }
  for (std::size_t f = 0; f < a.triangles.size() / 3; ++f) {
    std::int64_t* t = &a.triangles[3 * f];
    const bool right = (t[0] % (n + 1)) + (t[1] % (n + 1)) + (t[2] % (n + 1)) > 3 * half;
    for (int c = 0; c < 3; ++c)
      if (right && t[c] % (n + 1) == half) t[c] = count + t[c] / (n + 1);
  }
  SplitGrid g;
  g.mesh = a.mesh();
  planar_uvs(g.mesh, 0, 1, 0, 1, 0.1f, 0.9f, 0.1f, 0.9f, g.uvs);
  return g;
}

TEST(UvIslands, ASplitSeamWithOneUvJoinsThroughTheWeldOnly) {
  const SplitGrid g = split_grid(8);
  const UvIslands welded = label_uv_islands(g.mesh, g.uvs.data(), 1e-6, false, 2);
  EXPECT_EQ(welded.count, 1);
  EXPECT_FALSE(welded.merged.empty());  // the shared UVs of the split vertices asked for it
  const UvIslands apart = label_uv_islands(g.mesh, g.uvs.data(), -1.0, false, 2);
  EXPECT_EQ(apart.count, 2);
  EXPECT_EQ(apart.face_island, reference_islands(g.mesh, g.uvs.data(), -1.0));
}

TEST(UvIslands, OneUvLayoutForTwoSheetsNeedsNoWeld) {
  // Two sheets far apart with the same UVs (a mirrored model's halves share their layout):
  // the equal UVs belong to distant vertices, which no weld merges, so none runs.
  TwoSheets s = two_sheets();
  for (std::size_t i = 6 * s.half; i < s.uvs.size(); i += 2) s.uvs[i] -= 0.43f;
  for (std::size_t i = 0; i < 6 * s.half; ++i) s.uvs[6 * s.half + i] = s.uvs[i];
  const UvIslands islands = label_uv_islands(s.mesh, s.uvs.data(), 1e-6, false, 2);
  EXPECT_TRUE(islands.merged.empty());
  EXPECT_EQ(islands.count, 2);
  EXPECT_EQ(islands.face_island, reference_islands(s.mesh, s.uvs.data(), 1e-6));
}

TEST(UvIslands, TwoCornersOfOneFaceWithinTheWeldDistance) {
  // Face 0 has corners on vertices 0 and 1, a hair apart (one merged vertex, where face 0
  // counts through its first corner, UV (0, 0)); face 1 meets vertex 1 at face 0's second
  // UV. Merged, they share no UV: two islands. No two vertices share a UV, so only the
  // face's near corners tell that the weld matters.
  test::Arrays a;
  a.vertices = {0, 0, 0, 1e-9, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0};
  a.triangles = {0, 1, 2, 1, 3, 4};
  const Mesh mesh = a.mesh();
  const std::vector<float> uvs = {0.0f, 0.0f, 0.5f, 0.5f, 0.9f, 0.1f,   // face 0
                                  0.5f, 0.5f, 0.2f, 0.8f, 0.7f, 0.7f};  // face 1
  const std::vector<std::int32_t> expected = {0, 1};
  EXPECT_EQ(reference_islands(mesh, uvs.data(), 1e-6), expected);
  EXPECT_EQ(label_uv_islands(mesh, uvs.data(), 1e-6, false, 2).face_island, expected);
  // Not merged, vertex 1 joins them.
  EXPECT_EQ(label_uv_islands(mesh, uvs.data(), -1.0, false, 2).count, 1);
}

TEST(UvIslands, SameAsTheSerialLabellingOnAMessyMesh) {
  // Random faces over few vertices, a third of them duplicated at the same position,
  // corners with UVs from a small set (many equal), repeated corners in some faces, and
  // two corners of one face within the weld distance: every rule of the labelling at once.
  std::mt19937 rng(11);
  test::Arrays a;
  const int base = 1500;
  std::uniform_real_distribution<double> x(0.0, 1.0);
  for (int v = 0; v < base; ++v) a.vertices.insert(a.vertices.end(), {x(rng), x(rng), x(rng)});
  for (int v = 0; v < base / 3; ++v) {
    const int of = v * 3;
    a.vertices.insert(a.vertices.end(),
                      {a.vertices[3 * of], a.vertices[3 * of + 1], a.vertices[3 * of + 2]});
  }
  const std::int64_t near = static_cast<std::int64_t>(a.vertices.size() / 3);
  a.vertices.insert(a.vertices.end(), {a.vertices[0] + 1e-8, a.vertices[1], a.vertices[2]});
  const std::int64_t count = near + 1;
  std::uniform_int_distribution<std::int64_t> vertex(0, count - 1);
  std::uniform_int_distribution<int> uv_index(0, 2);
  std::vector<float> uvs;
  for (int f = 0; f < 2000; ++f) {
    std::int64_t t[3] = {vertex(rng), vertex(rng), vertex(rng)};
    if (f % 7 == 0) t[2] = t[0];
    if (f == 5) {
      t[0] = 0;
      t[1] = near;
    }
    for (int c = 0; c < 3; ++c) {
      a.triangles.push_back(t[c]);
      uvs.push_back(0.1f * uv_index(rng));
      uvs.push_back(f % 13 == 0 ? -0.0f : 0.0f);
    }
  }
  const Mesh mesh = a.mesh();
  for (double tolerance : {1e-6, -1.0, 0.0}) {
    const std::vector<std::int32_t> expected = reference_islands(mesh, uvs.data(), tolerance);
    const std::int32_t islands = *std::max_element(expected.begin(), expected.end()) + 1;
    ASSERT_GT(islands, 30);  // many islands, many joins: the rules decide
    ASSERT_LT(islands, 1000);
    for (unsigned threads : {1u, 2u, 7u})
      for (bool need_merged : {false, true})
        ASSERT_EQ(label_uv_islands(mesh, uvs.data(), tolerance, need_merged, threads).face_island,
                  expected)
            << tolerance << " " << threads << " " << need_merged;
  }
}

TEST(CornerGroups, EachMergedVertexsCornersInFaceOrder) {
  // Against a stable sort of (group, corner) pairs: meshes with few and many vertices (one
  // block of groups, and 256 blocks of many groups each), vertices no face uses (empty groups,
  // at the start, middle and end), with and without merging, on 1, 2 and 7 threads.
  std::mt19937 rng(5);
  for (int vertices : {5, 300, 70000}) {
    test::Arrays a;
    for (int v = 0; v < vertices; ++v)
      a.vertices.insert(a.vertices.end(), {double(v % 17), double(v % 5), double(v / 17)});
    std::uniform_int_distribution<std::int64_t> used(1, vertices - 2 > 1 ? vertices - 2 : 1);
    for (int f = 0; f < 3 * vertices; ++f)
      for (int c = 0; c < 3; ++c) a.triangles.push_back(used(rng));
    const Mesh mesh = a.mesh();
    const std::vector<float> uvs(6 * mesh.triangles.size(), 0.5f);
    for (double tolerance : {-1.0, 1e-6}) {
      const UvIslands islands = label_uv_islands(mesh, uvs.data(), tolerance, true, 2);
      const std::size_t keys = islands.merged.empty() ? mesh.vertices.size() : islands.merged_count;
      std::vector<std::pair<std::uint32_t, std::uint32_t>> expected;
      for (std::uint32_t corner = 0; corner < 3 * mesh.triangles.size(); ++corner) {
        const std::uint32_t v = mesh.triangles[corner / 3][corner % 3];
        expected.push_back({islands.merged.empty() ? v : islands.merged[v], corner});
      }
      std::stable_sort(expected.begin(), expected.end(),
                       [](auto x, auto y) { return x.first < y.first; });
      for (unsigned threads : {1u, 2u, 7u}) {
        const CornerGroups g = group_corners(mesh, islands, threads);
        ASSERT_EQ(g.first.size(), keys + 1);
        ASSERT_EQ(g.first.back(), expected.size());
        ASSERT_EQ(g.first.front(), 0u);
        for (std::size_t k = 0; k < keys; ++k) {
          ASSERT_LE(g.first[k], g.first[k + 1]);
          for (std::uint32_t j = g.first[k]; j < g.first[k + 1]; ++j)
            ASSERT_EQ(expected[j].first, k) << vertices << " " << threads;
        }
        for (std::size_t j = 0; j < expected.size(); ++j)
          ASSERT_EQ(g.corners[j], expected[j].second) << vertices << " " << threads;
      }
    }
  }
}

TEST(TextureSmoothing, LaterFacesWinOverlapsAndCentroidsFillOnlyEmptyTexels) {
  // Three copies of one UV triangle (values 1, 2, 3: the last is drawn), then two faces far
  // smaller than a texel inside it (covered: they draw nothing) and two more at one empty
  // texel (the first of them draws it). Radius 0, no margin: the image is the rasterisation.
  test::Arrays a = test::grid(1, 1);
  a.triangles = {0, 1, 2, 0, 1, 2, 0, 1, 2, 0, 1, 2, 0, 1, 2, 0, 1, 2, 0, 1, 2};
  const Mesh mesh = a.mesh();
  const float big[6] = {0.1f, 0.1f, 0.6f, 0.1f, 0.1f, 0.6f};
  std::vector<float> uvs;
  for (int k = 0; k < 3; ++k) uvs.insert(uvs.end(), big, big + 6);
  for (float at : {0.2f, 0.2f, 0.8f, 0.8f})
    uvs.insert(uvs.end(), {at, at, at + 0.001f, at, at, at + 0.001f});
  const std::vector<float> v = {1, 2, 3, 4, 5, 6, 7};
  TextureOptions o;
  o.width = o.height = 16;
  o.radius = 0.0;
  o.margin = 0;
  for (unsigned threads : {1u, 3u}) {
    o.threads = threads;
    const TextureSmoothing out =
        smooth_texture(mesh, PointKind::Faces, v.data(), uvs.data(), o, true);
    EXPECT_EQ(out.image[3 * 16 + 3], 3.0f);    // inside the big triangle
    EXPECT_EQ(out.image[12 * 16 + 12], 6.0f);  // the centroid of faces 5 and 6
    int drawn = 0;
    for (std::size_t t = 0; t < out.image.size(); ++t) {
      if (!out.mask[t]) continue;
      ++drawn;
      ASSERT_TRUE(out.image[t] == 3.0f || t == 12 * 16 + 12) << t;
    }
    EXPECT_GT(drawn, 10);
  }
}

TEST(TextureSmoothing, OverlappingLayoutSameForAnyThreadCount) {
  // Every face of a fine grid drawn over one quarter of the image twice (two copies of the
  // layout, shifted by a fraction of a texel): heavy overlaps, faces smaller than a texel,
  // face and vertex values.
  const Mesh mesh = test::grid(48, 48, 1.0 / 48).mesh();
  std::vector<float> uvs;
  planar_uvs(mesh, 0, 1, 0, 1, 0.1f, 0.5f, 0.1f, 0.5f, uvs);
  for (std::size_t i = 0; i < uvs.size() / 2; ++i) uvs[i] += 0.003f;
  const std::vector<float> fv = test::noisy(mesh.triangles.size(), 2.0f, 1.0f, 8);
  const std::vector<float> vv = test::noisy(mesh.vertices.size(), 2.0f, 1.0f, 9);
  for (PointKind kind : {PointKind::Faces, PointKind::Vertices}) {
    const float* v = kind == PointKind::Faces ? fv.data() : vv.data();
    TextureOptions o;
    o.width = o.height = 80;
    o.radius = 3.0;
    o.threads = 1;
    const TextureSmoothing one = smooth_texture(mesh, kind, v, uvs.data(), o, true);
    for (unsigned threads : {2u, 5u}) {
      o.threads = threads;
      const TextureSmoothing many = smooth_texture(mesh, kind, v, uvs.data(), o, true);
      EXPECT_EQ(one.image, many.image);
      EXPECT_EQ(one.mask, many.mask);
      EXPECT_EQ(one.values, many.values);
    }
  }
}

TEST(TextureSmoothing, NothingCrossesBetweenIslands) {
  const TwoSheets s = two_sheets();
  std::vector<float> v(s.mesh.triangles.size(), 1.0f);
  std::fill(v.begin() + s.half, v.end(), 5.0f);
  TextureOptions o;
  o.width = o.height = 64;
  o.radius = 8.0;  // four times the gap
  const TextureSmoothing out =
      smooth_texture(s.mesh, PointKind::Faces, v.data(), s.uvs.data(), o, true);
  for (std::size_t f = 0; f < v.size(); ++f) ASSERT_NEAR(out.values[f], v[f], 1e-5f) << f;
  // The image: each island holds its own value, margins included.
  ASSERT_EQ(out.image.size(), 64u * 64u);
  for (std::size_t t = 0; t < out.image.size(); ++t) {
    if (!out.mask[t]) {
      ASSERT_EQ(out.image[t], 0.0f);
      continue;
    }
    const float x = out.image[t];
    ASSERT_TRUE(std::fabs(x - 1.0f) < 1e-5f || std::fabs(x - 5.0f) < 1e-5f) << t << " " << x;
  }
}

TEST(TextureSmoothing, ConstantExactRadiusZeroIdentityAndInRange) {
  const TwoSheets s = two_sheets();
  const std::size_t m = s.mesh.triangles.size();
  TextureOptions o;
  o.width = o.height = 128;
  const std::vector<float> c(m, 0.7f);
  EXPECT_EQ(smooth_texture(s.mesh, PointKind::Faces, c.data(), s.uvs.data(), o, false).values, c);
  const std::vector<float> v = test::noisy(m, 2.0f, 1.0f, 3);
  o.radius = 0.0;
  EXPECT_EQ(smooth_texture(s.mesh, PointKind::Faces, v.data(), s.uvs.data(), o, false).values, v);
  o.radius = 6.0;
  const auto [lo, hi] = std::minmax_element(v.begin(), v.end());
  const std::vector<float> b =
      smooth_texture(s.mesh, PointKind::Faces, v.data(), s.uvs.data(), o, false).values;
  EXPECT_LT(test::variance(b), 0.3 * test::variance(v));
  for (float x : b) {
    ASSERT_GE(x, *lo);
    ASSERT_LE(x, *hi);
  }
}

TEST(TextureSmoothing, EdgesAndCornersOnTexelCentresBelongToOneFace) {
  // A grid whose UV corners fall exactly on texel centres (every 4 texels), so that many
  // centres lie on shared edges and corners: each must be drawn by exactly one face (radius 0
  // then gives every face back its own value), and the interior has no hole.
  const Mesh mesh = test::grid(8, 8, 1.0 / 8).mesh();
  std::vector<float> uvs;
  planar_uvs(mesh, 0, 1, 0, 1, 8.5f / 64, 40.5f / 64, 8.5f / 64, 40.5f / 64, uvs);
  const std::vector<float> v = test::noisy(mesh.triangles.size(), 2.0f, 1.0f, 12);
  TextureOptions o;
  o.width = o.height = 64;
  o.radius = 0.0;
  o.margin = 0;
  const TextureSmoothing out =
      smooth_texture(mesh, PointKind::Faces, v.data(), uvs.data(), o, true);
  EXPECT_EQ(out.values, v);
  for (int y = 9; y < 40; ++y)
    for (int x = 9; x < 40; ++x) ASSERT_TRUE(out.mask[y * 64 + x]) << x << " " << y;
}

TEST(TextureSmoothing, VertexValues) {
  const Mesh mesh = test::grid(16, 16, 1.0 / 16).mesh();
  std::vector<float> uvs;
  planar_uvs(mesh, 0, 1, 0, 1, 0.05f, 0.95f, 0.05f, 0.95f, uvs);
  const std::vector<float> v = test::noisy(mesh.vertices.size(), 1.0f, 0.5f, 4);
  const std::vector<float> c(mesh.vertices.size(), 0.1f);
  TextureOptions o;
  o.width = o.height = 128;
  o.radius = 8.0;  // a grid square is 7 texels wide
  EXPECT_EQ(smooth_texture(mesh, PointKind::Vertices, c.data(), uvs.data(), o, false).values, c);
  const std::vector<float> s =
      smooth_texture(mesh, PointKind::Vertices, v.data(), uvs.data(), o, false).values;
  const auto [lo, hi] = std::minmax_element(v.begin(), v.end());
  EXPECT_LT(test::variance(s), 0.3 * test::variance(v));
  for (float x : s) {
    ASSERT_GE(x, *lo);
    ASSERT_LE(x, *hi);
  }
}

TEST(TextureSmoothing, BilateralKeepsAStep) {
  // One island, left half 0 and right half 1 (with a little noise): a Gaussian blurs the step,
  // the bilateral filter keeps it.
  const Mesh mesh = test::grid(32, 8, 1.0 / 32).mesh();
  std::vector<float> uvs;
  planar_uvs(mesh, 0, 1, 0, 0.25f, 0.0f, 1.0f, 0.0f, 0.25f, uvs);
  std::vector<float> v = test::noisy(mesh.triangles.size(), 0.0f, 0.01f, 5);
  for (std::size_t f = 0; f < v.size(); ++f) {
    const glm::uvec3 t = mesh.triangles[f];
    const float x = (mesh.vertices[t.x].x + mesh.vertices[t.y].x + mesh.vertices[t.z].x) / 3.0f;
    if (x > 0.0f) v[f] += 1.0f;  // the mesh is centred: x > 0 is the right half
  }
  TextureOptions o;
  o.width = o.height = 256;
  o.radius = 16.0;
  const auto gauss = smooth_texture(mesh, PointKind::Faces, v.data(), uvs.data(), o, false).values;
  o.bilateral = true;
  const auto bilateral =
      smooth_texture(mesh, PointKind::Faces, v.data(), uvs.data(), o, false).values;
  double gauss_error = 0.0, bilateral_error = 0.0;
  for (std::size_t f = 0; f < v.size(); ++f) {
    const float step = v[f] > 0.5f ? 1.0f : 0.0f;
    gauss_error = std::max(gauss_error, double(std::fabs(gauss[f] - step)));
    bilateral_error = std::max(bilateral_error, double(std::fabs(bilateral[f] - step)));
  }
  EXPECT_GT(gauss_error, 0.2);
  EXPECT_LT(bilateral_error, 0.05);
}

TEST(TextureSmoothing, TinyAndOutsideFacesKeepAValue) {
  // Faces far smaller than a texel, and one outside the image: no NaN, values kept or read.
  const Mesh mesh = test::grid(4, 4, 0.25).mesh();
  std::vector<float> uvs;
  planar_uvs(mesh, 0, 1, 0, 1, 0.5f, 0.5001f, 0.5f, 0.5001f, uvs);
  for (int k = 0; k < 6; ++k) uvs[k] += 3.0f;  // face 0 outside [0, 1]
  const std::vector<float> v = test::noisy(mesh.triangles.size(), 1.0f, 0.5f, 6);
  TextureOptions o;
  o.width = o.height = 32;
  const auto s = smooth_texture(mesh, PointKind::Faces, v.data(), uvs.data(), o, false).values;
  EXPECT_EQ(s[0], v[0]);
  for (float x : s) ASSERT_TRUE(std::isfinite(x));
}

TEST(TextureSmoothing, SameResultForAnyThreadCount) {
  const TwoSheets s = two_sheets();
  const std::vector<float> v = test::noisy(s.mesh.triangles.size(), 2.0f, 1.0f, 7);
  TextureOptions one, many;
  one.width = one.height = many.width = many.height = 96;
  one.threads = 1;
  many.threads = 6;
  EXPECT_EQ(smooth_texture(s.mesh, PointKind::Faces, v.data(), s.uvs.data(), one, true).image,
            smooth_texture(s.mesh, PointKind::Faces, v.data(), s.uvs.data(), many, true).image);
}

TEST(TextureSmoothing, RejectsBadInput) {
  const TwoSheets s = two_sheets();
  std::vector<float> v(s.mesh.triangles.size(), 1.0f);
  TextureOptions o;
  o.width = 0;
  EXPECT_THROW(smooth_texture(s.mesh, PointKind::Faces, v.data(), s.uvs.data(), o, false),
               std::invalid_argument);
  std::vector<float> uvs = s.uvs;
  uvs[7] = NAN;
  EXPECT_THROW(
      smooth_texture(s.mesh, PointKind::Faces, v.data(), uvs.data(), TextureOptions(), false),
      std::invalid_argument);
}

}  // namespace
}  // namespace sdf
