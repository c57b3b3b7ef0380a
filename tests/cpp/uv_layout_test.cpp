// SPDX-License-Identifier: GPL-3.0-or-later
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <stdexcept>
#include <vector>

#include "post/smoothing_texture.h"
#include "post/smoothing_texture_pages.h"
#include "post/uv_islands.h"
#include "post/uv_layout.h"
#include "post/uv_plan.h"
#include "smoothing_test_meshes.h"

namespace sdf {
namespace {

// Two 8 x 8 grids apart in space; sheet s's UVs: its (x, y) scaled into [0.1, 0.5]^2, then
// moved by (du[s], dv[s]) (and, for `mirror`, the second sheet mirrored in u).
struct Sheets {
  Mesh mesh;
  std::vector<float> uvs;
  std::size_t half = 0;
};

Sheets two_sheets(float du1, float dv1, float shift_u1 = 0.0f, bool mirror = false) {
  test::Arrays a = test::grid(8, 8, 0.125);
  const test::Arrays b = test::grid(8, 8, 0.125, 1.5, 0.0);
  const std::int64_t offset = static_cast<std::int64_t>(a.vertices.size() / 3);
  a.vertices.insert(a.vertices.end(), b.vertices.begin(), b.vertices.end());
  for (std::int64_t t : b.triangles) a.triangles.push_back(t + offset);
  Sheets s;
  s.mesh = a.mesh();
  s.half = s.mesh.triangles.size() / 2;
  for (std::size_t f = 0; f < s.mesh.triangles.size(); ++f)
    for (int c = 0; c < 3; ++c) {
      const glm::vec3 p = s.mesh.vertices[s.mesh.triangles[f][c]] + glm::vec3(s.mesh.center);
      const bool second = f >= s.half;
      float x = p.x - (second ? 1.5f : 0.0f);
      if (second && mirror) x = 1.0f - x;
      s.uvs.push_back(0.1f + 0.4f * x + (second ? du1 + shift_u1 : 0.0f));
      s.uvs.push_back(0.1f + 0.4f * p.y + (second ? dv1 : 0.0f));
    }
  return s;
}

UvLayout layout_of(const Sheets& s) {
  return layout_uvs(s.uvs.data(), uv_islands(s.mesh, s.uvs.data(), 1e-6), 0);
}

TEST(UvLayout, TileNumbersFollowTheUdimConvention) {
  EXPECT_EQ(uv_tile(0.5, 0.5), 1001);
  EXPECT_EQ(uv_tile(1.5, 0.2), 1002);
  EXPECT_EQ(uv_tile(9.99, 0.0), 1010);
  EXPECT_EQ(uv_tile(0.5, 1.5), 1011);
  EXPECT_EQ(uv_tile(9.5, 99.5), 2000);
  EXPECT_EQ(uv_tile(-0.01, 0.5), 0);
  EXPECT_EQ(uv_tile(10.0, 0.5), 0);
  EXPECT_EQ(uv_tile(0.5, -0.01), 0);
  EXPECT_EQ(uv_tile(0.5, 100.0), 0);
}

TEST(UvLayout, SheetsApartInOneSquareAreOnePage) {
  const Sheets s = two_sheets(0.45f, 0.0f);  // second sheet at u in [0.55, 0.95]
  const UvLayout layout = layout_of(s);
  EXPECT_TRUE(layout.single_square());
  EXPECT_EQ(layout.faces_overlapping, 0u);
  EXPECT_EQ(layout.faces_outside, 0u);
}

TEST(UvLayout, EachTileIsAPageAndItsUvsMoveExactlyIntoTheSquare) {
  const Sheets s = two_sheets(2.0f, 1.0f);  // tile 1013
  const UvLayout layout = layout_of(s);
  ASSERT_EQ(layout.pages.size(), 2u);
  EXPECT_EQ(layout.pages[0].tile, 1001);
  EXPECT_EQ(layout.pages[1].tile, 1013);
  EXPECT_EQ(layout.pages[1].column(), 2);
  EXPECT_EQ(layout.pages[1].row(), 1);
  EXPECT_EQ(layout.faces_overlapping, 0u);  // same place, other tiles: no overlap
  const std::vector<float> second = page_uvs(layout, s.uvs.data(), 1, 0);
  for (std::size_t f = 0; f < s.mesh.triangles.size(); ++f) {
    ASSERT_EQ(layout.face_page[f], f < s.half ? 0 : 1);
    for (int k = 0; k < 6; ++k) {
      if (f < s.half) {
        ASSERT_EQ(second[6 * f + k], -4.0f);  // other pages' faces: outside the square
      } else {
        ASSERT_EQ(second[6 * f + k], s.uvs[6 * f + k] - (k % 2 ? 1.0f : 2.0f));  // exact
      }
    }
  }
}

TEST(UvLayout, StackedAndMirroredShellsGoOnLayersOfTheirOwn) {
  for (bool mirror : {false, true}) {
    const Sheets s = two_sheets(0.0f, 0.0f, 0.0f, mirror);
    const UvLayout layout = layout_of(s);
    ASSERT_EQ(layout.pages.size(), 2u) << mirror;
    EXPECT_EQ(layout.pages[0].tile, 1001);
    EXPECT_EQ(layout.pages[1].tile, 1001);
    EXPECT_EQ(layout.pages[1].layer, 1);
    EXPECT_EQ(layout.faces_overlapping, s.mesh.triangles.size());
    for (std::size_t f = 0; f < s.mesh.triangles.size(); ++f)
      ASSERT_EQ(layout.face_page[f], f < s.half ? 0 : 1);
  }
}

TEST(UvLayout, OverlapsBelowTheShareAreNotCounted) {
  // The second sheet moved right so that only a sliver of each face in its first column
  // overlaps the first sheet's last column: 0.5% of a face's width, under kOverlapShare.
  const float cell = 0.4f / 8;
  const Sheets sliver = two_sheets(0.4f - 0.005f * cell, 0.0f);
  EXPECT_EQ(layout_of(sliver).faces_overlapping, 0u);
  EXPECT_TRUE(layout_of(sliver).single_square());
  // A quarter of a column: the faces of the two columns that meet overlap.
  const Sheets quarter = two_sheets(0.4f - 0.25f * cell, 0.0f);
  const UvLayout layout = layout_of(quarter);
  EXPECT_EQ(layout.pages.size(), 2u);
  EXPECT_GT(layout.faces_overlapping, 0u);
  EXPECT_LE(layout.faces_overlapping, 4u * 8u);  // the two columns' faces at most
}

TEST(UvLayout, ASoupOfOverlappingFacesIsDrawnAsLaidOut) {
  // 3000 faces, each its own island, with random UVs over the square: every face's box meets
  // most others', past the search's budget; one page, marked unparted.
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> unit(0.0f, 0.999f);
  const std::size_t m = 3000;
  std::vector<float> uvs(6 * m);
  for (float& x : uvs) x = unit(rng);
  std::vector<std::int32_t> islands(m);
  for (std::size_t f = 0; f < m; ++f) islands[f] = static_cast<std::int32_t>(f);
  const UvLayout layout = layout_uvs(uvs.data(), islands, 0);
  EXPECT_TRUE(layout.overlaps_unparted);
  EXPECT_TRUE(layout.single_square());
  EXPECT_GT(layout.faces_overlapping, 0u);
}

// Stacked sheets smoothed on their pages: each sheet's values are those of smoothing it alone
// (here: alone means the other sheet moved far into another tile).
TEST(SmoothTexturePages, StackedSheetsDoNotMix) {
  const Sheets stacked = two_sheets(0.0f, 0.0f);
  const Sheets apart = two_sheets(3.0f, 0.0f);  // tile 1004
  const std::size_t m = stacked.mesh.triangles.size();
  std::vector<float> values(m);
  for (std::size_t f = 0; f < m; ++f)
    values[f] = (f < stacked.half ? 1.0f : 5.0f) + 0.01f * (f % 7);
  TextureOptions o;
  o.width = o.height = 64;
  auto run = [&](const Sheets& s, std::vector<float>& out) {
    out.resize(m);
    const UvLayout layout = layout_of(s);
    auto page = [&](const float* uvs, bool keep, const ProgressFn& p, float* into) {
      return smooth_texture(s.mesh, PointKind::Faces, values.data(), uvs, o, keep, p, 0.0, 1.0,
                            nullptr, into);
    };
    return smooth_texture_pages(s.mesh, PointKind::Faces, values.data(), s.uvs.data(), layout, true,
                                0, nullptr, page, out.data());
  };
  std::vector<float> a, b;
  const TextureSmoothing on_layers = run(stacked, a);
  const TextureSmoothing on_tiles = run(apart, b);
  EXPECT_EQ(a, b);
  float lo = 10.0f, hi = 0.0f;
  for (std::size_t f = 0; f < stacked.half; ++f) lo = std::min(lo, a[f]), hi = std::max(hi, a[f]);
  EXPECT_GE(lo, 1.0f);
  EXPECT_LE(hi, 1.07f);                   // never pulled toward the other sheet's 5
  ASSERT_EQ(on_layers.tiles.size(), 1u);  // the layers laid over each other in tile 1001
  ASSERT_EQ(on_tiles.tiles.size(), 2u);
  EXPECT_EQ(on_tiles.tiles[1].tile, 1004);
  EXPECT_EQ(on_layers.tiles[0].image.size(), 64u * 64u);
}

TEST(UvPlan, HoldsTheIslandsAndTheLayoutAndFitsTheFacesItWasFoundFor) {
  // The second sheet's UVs on the first's: the plan's layout is layout_uvs' on its islands.
  const Sheets s = two_sheets(0.0f, 0.0f);
  const UvPlan plan = plan_uvs(s.mesh, s.uvs.data(), 1e-6, false, 0);
  const UvLayout direct = layout_of(s);
  EXPECT_EQ(plan.face_count, s.mesh.triangles.size());
  EXPECT_EQ(plan.islands.count, 2);
  EXPECT_EQ(plan.layout.face_page, direct.face_page);
  EXPECT_EQ(plan.layout.faces_overlapping, direct.faces_overlapping);
  EXPECT_EQ(plan.layout.pages.size(), 2u);
  const std::size_t faces = s.mesh.triangles.size(), vertices = s.mesh.vertices.size();
  const float* uvs = s.uvs.data();
  EXPECT_TRUE(plan_fits(plan, faces, vertices, uvs, 1e-6, false));
  EXPECT_FALSE(plan_fits(plan, s.half, vertices, uvs, 1e-6, false));
  EXPECT_FALSE(plan_fits(plan, faces, vertices + 1, uvs, 1e-6, false));  // another mesh
  EXPECT_FALSE(plan_fits(plan, faces, vertices, nullptr, 1e-6, false));  // UVs not known
  std::vector<float> moved = s.uvs;
  moved[3] += 0.25f;  // other UVs
  EXPECT_FALSE(plan_fits(plan, faces, vertices, moved.data(), 1e-6, false));
  EXPECT_FALSE(plan_fits(plan, faces, vertices, uvs, 1e-4, false));
  EXPECT_FALSE(plan_fits(plan, faces, vertices, uvs, 1e-6, true));
  EXPECT_TRUE(plan_fits(plan_uvs(s.mesh, uvs, 1e-6, true, 0), faces, vertices, uvs, 1e-6, true));
  std::vector<float> bad = s.uvs;
  bad[7] = std::nanf("");
  EXPECT_THROW(plan_uvs(s.mesh, bad.data(), 1e-6, false, 0), std::invalid_argument);
}

TEST(TextureSmoothing, ACancelStopsTheDrawingOfALargeImage) {
  // Progress is asked while the image is drawn, not only between stages: a cancel there
  // stops the work (at 4096^2 drawing took half a second between two calls).
  const Sheets s = two_sheets(0.45f, 0.0f);
  std::vector<float> values(s.mesh.triangles.size(), 1.0f);
  TextureOptions o;
  o.width = o.height = 2048;
  o.radius = 0.0;
  std::vector<double> asked;
  auto stop_in_drawing = [&](double fraction) {
    asked.push_back(fraction);
    return !(fraction > 0.0 && fraction < 0.1);
  };
  EXPECT_THROW(smooth_texture(s.mesh, PointKind::Faces, values.data(), s.uvs.data(), o, false,
                              stop_in_drawing),
               Cancelled);
  ASSERT_FALSE(asked.empty());
  EXPECT_GT(asked.back(), 0.0);
  EXPECT_LT(asked.back(), 0.1);  // stopped while drawing, before the dilation (0.1 on)
}

}  // namespace
}  // namespace sdf
