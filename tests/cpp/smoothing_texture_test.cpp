// SPDX-License-Identifier: GPL-3.0-or-later
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "smoothing_texture.h"
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
  for (std::size_t f = 0; f < sides.size(); ++f) ASSERT_EQ(sides[f], static_cast<std::int32_t>(f / per_side));
}

TEST(TextureSmoothing, NothingCrossesBetweenIslands) {
  const TwoSheets s = two_sheets();
  std::vector<float> v(s.mesh.triangles.size(), 1.0f);
  std::fill(v.begin() + s.half, v.end(), 5.0f);
  TextureOptions o;
  o.width = o.height = 64;
  o.radius = 8.0;  // four times the gap
  const TextureSmoothing out = smooth_texture(s.mesh, PointKind::Faces, v.data(), s.uvs.data(), o, true);
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
  const std::vector<float> b = smooth_texture(s.mesh, PointKind::Faces, v.data(), s.uvs.data(), o, false).values;
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
  const TextureSmoothing out = smooth_texture(mesh, PointKind::Faces, v.data(), uvs.data(), o, true);
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
  const std::vector<float> s = smooth_texture(mesh, PointKind::Vertices, v.data(), uvs.data(), o, false).values;
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
  const auto bilateral = smooth_texture(mesh, PointKind::Faces, v.data(), uvs.data(), o, false).values;
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
  EXPECT_THROW(smooth_texture(s.mesh, PointKind::Faces, v.data(), s.uvs.data(), o, false), std::invalid_argument);
  std::vector<float> uvs = s.uvs;
  uvs[7] = NAN;
  EXPECT_THROW(smooth_texture(s.mesh, PointKind::Faces, v.data(), uvs.data(), TextureOptions(), false),
               std::invalid_argument);
}

}  // namespace
}  // namespace sdf
