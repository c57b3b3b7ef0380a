// SPDX-License-Identifier: GPL-3.0-or-later
// compute() builds the BVH on a thread of its own while the calling thread orients the mesh
// (which reverses faces in place) and samples its points (threads = 0), or after them (a set
// thread count): the values must be those of the mesh wound right from the start, bit for
// bit, either way.
#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <utility>
#include <vector>

#include "pipeline/sdf.h"
#include "test_meshes.h"

namespace sdf {
namespace {

// A closed box whose every side is an n x n grid of quads (two triangles each), wound
// outward: 12 n^2 faces, enough that the build and the orientation both take a while.
test::Arrays grid_box(int n) {
  test::Arrays a;
  auto vertex = [&](double x, double y, double z) {
    a.vertices.insert(a.vertices.end(), {x, y, z});
    return static_cast<std::int64_t>(a.vertices.size() / 3 - 1);
  };
  // Each side: an origin corner and two edge directions whose cross product points outward.
  const double sides[6][9] = {{-1, -1, 1, 1, 0, 0, 0, 1, 0},  {-1, -1, -1, 0, 1, 0, 1, 0, 0},
                              {-1, -1, -1, 0, 0, 1, 0, 1, 0}, {1, -1, -1, 0, 1, 0, 0, 0, 1},
                              {-1, -1, -1, 1, 0, 0, 0, 0, 1}, {-1, 1, -1, 0, 0, 1, 1, 0, 0}};
  for (const auto& s : sides) {
    std::vector<std::int64_t> index((n + 1) * (n + 1));
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) {
        const double u = 2.0 * i / n, v = 2.0 * j / n;
        index[j * (n + 1) + i] = vertex(s[0] + u * s[3] + v * s[6], s[1] + u * s[4] + v * s[7],
                                        s[2] + u * s[5] + v * s[8]);
      }
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const std::int64_t p = index[j * (n + 1) + i], q = index[j * (n + 1) + i + 1],
                           r = index[(j + 1) * (n + 1) + i + 1], t = index[(j + 1) * (n + 1) + i];
        a.triangles.insert(a.triangles.end(), {p, q, r, p, r, t});
      }
  }
  return a;
}

Options options_for(Orientation orientation, unsigned threads) {
  Options options;
  options.rays = 8;
  options.orientation = orientation;
  options.threads = threads;
  return options;
}

bool same_bits(const std::vector<float>& a, const std::vector<float>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

double stage(const Output& out, const std::string& name) {
  for (const auto& [stage_name, seconds] : out.timings)
    if (stage_name == name) return seconds;
  return -1.0;
}

TEST(ComputePipeline, ReversedFacesGiveTheValuesOfTheMeshWoundRight) {
  const test::Arrays right = grid_box(40);
  test::Arrays messy = right;
  std::size_t reversed = 0;
  for (std::size_t f = 0; f < messy.triangles.size() / 3; f += 7, ++reversed)
    std::swap(messy.triangles[3 * f + 1], messy.triangles[3 * f + 2]);
  const Output clean = compute(right.mesh(), options_for(Orientation::AsIs, 0));
  EXPECT_TRUE(clean.orientation.reversed.empty());  // nothing reversed, nothing listed
  EXPECT_GT(stage(clean, "build"), 0.0);
  EXPECT_GE(stage(clean, "build wait"), 0.0);
  for (unsigned threads : {0u, 3u}) {  // beside orientation, then after it
    const Output fixed = compute(messy.mesh(), options_for(Orientation::Auto, threads));
    EXPECT_EQ(fixed.orientation.flipped_faces, reversed);
    ASSERT_EQ(fixed.orientation.reversed.size(), messy.triangles.size() / 3);
    for (std::size_t f = 0; f < fixed.orientation.reversed.size(); ++f)
      ASSERT_EQ(fixed.orientation.reversed[f], f % 7 == 0 ? 1 : 0) << "face " << f;
    EXPECT_TRUE(same_bits(fixed.raw, clean.raw)) << threads << " threads";
    // Trusting the messy winding changes values: the test reverses something that matters.
    const Output trusted = compute(messy.mesh(), options_for(Orientation::AsIs, threads));
    EXPECT_FALSE(same_bits(trusted.raw, clean.raw));
  }
}

TEST(ComputePipeline, FlipGivesTheValuesOfTheMeshWoundRight) {
  const test::Arrays right = grid_box(30);
  test::Arrays inside_out = right;
  for (std::size_t f = 0; f < inside_out.triangles.size() / 3; ++f)
    std::swap(inside_out.triangles[3 * f + 1], inside_out.triangles[3 * f + 2]);
  const Output clean = compute(right.mesh(), options_for(Orientation::AsIs, 2));
  const Output flipped = compute(inside_out.mesh(), options_for(Orientation::Flip, 0));
  EXPECT_EQ(flipped.orientation.flipped_faces, inside_out.triangles.size() / 3);
  EXPECT_TRUE(same_bits(flipped.raw, clean.raw));
}

// A double-sided box (its faces again, reversed) stops at its twins, in every orientation, and
// is cast without them when asked: the values of the single-sided box.
TEST(ComputePipeline, ReversedTwinsStopTheRunAndSayWhich) {
  const test::Arrays single = grid_box(10);
  test::Arrays both = single;
  const std::size_t faces = single.triangles.size() / 3;
  for (std::size_t f = 0; f < faces; ++f)
    both.triangles.insert(
        both.triangles.end(),
        {single.triangles[3 * f], single.triangles[3 * f + 2], single.triangles[3 * f + 1]});
  for (Orientation orientation : {Orientation::Auto, Orientation::AsIs, Orientation::Flip}) {
    const Output out = compute(both.mesh(), options_for(orientation, 2));
    ASSERT_EQ(out.twins.dropped.size(), faces);
    EXPECT_TRUE(out.raw.empty());
    EXPECT_EQ(out.twins.dropped.front(), faces);
    EXPECT_EQ(out.twins.twin.back(), faces - 1);
    EXPECT_EQ(out.twins.corner.front(), 0);  // corner 0 of (a, c, b) is corner 0 of (a, b, c)
    EXPECT_GE(stage(out, "twins"), 0.0);
  }
  Options ignoring = options_for(Orientation::AsIs, 2);
  ignoring.find_twins = false;
  const Output cast_all = compute(both.mesh(), ignoring);
  EXPECT_EQ(cast_all.raw.size(), 2 * faces);
  const Output clean = compute(single.mesh(), options_for(Orientation::AsIs, 2));
  EXPECT_TRUE(clean.twins.empty());
  const std::vector<float> first_side(cast_all.raw.begin(), cast_all.raw.begin() + faces);
  // Cast with its twins, a face sees the far wall's two coincident faces: some rays keep the
  // wrong one (the reason compute() stops).
  EXPECT_FALSE(same_bits(first_side, clean.raw));
}

TEST(ComputePipeline, ARunCancelledDuringTheBackgroundBuildEndsCleanly) {
  // Cancelled at the report after 'prepare' (the second), while the build may still run: the
  // run waits for it before unwinding, so no thread is left reading a freed mesh (ASan and
  // TSan builds check), and the next run works.
  int calls = 0;
  const ProgressFn stop_at_second = [&](double) { return ++calls < 2; };
  const test::Arrays box = grid_box(60);
  EXPECT_THROW(compute(box.mesh(), options_for(Orientation::Auto, 0), stop_at_second), Cancelled);
  EXPECT_EQ(calls, 2);
  EXPECT_FALSE(compute(box.mesh(), options_for(Orientation::Auto, 0)).raw.empty());
}

}  // namespace
}  // namespace sdf
