// SPDX-License-Identifier: GPL-3.0-or-later
// A minimum part size: a small segment joins the neighbour it shares the longest boundary
// with, separate solids never join, and a share of 0 changes nothing.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>
#include <vector>

#include "segment/segmentation.h"
#include "segment/small_segments.h"
#include "segment_test_meshes.h"

namespace {

using namespace sdf::segment;

// A flat grid of unit cells, each two triangles; cell (i, j) at x in [i, i+1], y in [j, j+1]
// gives faces 2 (j * columns + i) and the next one.
struct Grid {
  sdf::test::Arrays arrays;
  int columns, rows;
  Grid(int columns_, int rows_, double x0 = 0.0) : columns(columns_), rows(rows_) {
    for (int j = 0; j <= rows; ++j)
      for (int i = 0; i <= columns; ++i)
        arrays.vertices.insert(arrays.vertices.end(), {x0 + i, double(j), 0.0});
    for (int j = 0; j < rows; ++j)
      for (int i = 0; i < columns; ++i) {
        const std::int64_t a = j * (columns + 1) + i, b = a + 1, c = a + columns + 1, d = c + 1;
        arrays.triangles.insert(arrays.triangles.end(), {a, b, d, a, d, c});
      }
  }
  std::size_t faces() const { return arrays.triangles.size() / 3; }
};

// Labels per face from a label per cell.
std::vector<int> per_face(const std::vector<int>& cells) {
  std::vector<int> faces;
  for (int c : cells) faces.insert(faces.end(), {c, c});
  return faces;
}

struct Joined {
  std::vector<int> segments;
  std::size_t count;
};

Joined join(const sdf::test::Arrays& a, std::vector<int> segments, std::size_t count,
            const std::vector<double>& values, double share) {
  const std::size_t n = a.triangles.size() / 3, nv = a.vertices.size() / 3;
  const FaceGraph graph = build_face_graph(a.triangles.data(), n, nv, 1);
  const std::vector<double> areas = face_areas(a.vertices.data(), a.triangles.data(), n, 1);
  count = join_small_segments(graph, a.vertices.data(), a.triangles.data(), areas.data(),
                              values.data(), n, share, segments.data(), count);
  return {segments, count};
}

// A 10 x 4 grid: a block on the left (0), one on the right (2), and between them a 1 x 2
// piece (1) at rows 0-1 of column `column`; the column's rows 2-3 belong to the block on
// the same side as the piece's longer boundary. Values: 1, 2, 3 for the three.
std::vector<int> three_blocks(int column, int owner) {
  std::vector<int> cells;
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 10; ++i) {
      int s = i < column ? 0 : 2;
      if (i == column) s = j < 2 ? 1 : owner;
      cells.push_back(s);
    }
  return per_face(cells);
}

std::vector<double> values_of(const std::vector<int>& segments) {
  std::vector<double> values;
  for (int s : segments) values.push_back(1.0 + s);
  return values;
}

TEST(SegmentSmallSegments, ASmallPieceJoinsItsLongestBoundary) {
  const Grid grid(10, 4);
  // The piece shares 3 units with the left block (its side and top), 2 with the right one.
  const auto left = three_blocks(4, 0);
  const Joined a = join(grid.arrays, left, 3, values_of(left), 0.1);
  ASSERT_EQ(a.count, 2u);
  for (std::size_t f = 0; f < left.size(); ++f) EXPECT_EQ(a.segments[f], left[f] == 2 ? 1 : 0);
  // The other way round: the top of its column belongs to the right block.
  const auto right = three_blocks(4, 2);
  const Joined b = join(grid.arrays, right, 3, values_of(right), 0.1);
  ASSERT_EQ(b.count, 2u);
  for (std::size_t f = 0; f < right.size(); ++f) EXPECT_EQ(b.segments[f], right[f] == 0 ? 0 : 1);
}

TEST(SegmentSmallSegments, RenumberedByMeanValue) {
  const Grid grid(10, 4);
  const auto labels = three_blocks(4, 2);
  // The piece is the thinnest and joins the right block, whose mean stays above the left's
  // only while the right block is thick enough: here it falls below it.
  std::vector<double> values;
  for (int s : labels) values.push_back(s == 0 ? 1.0 : s == 1 ? -20.0 : 2.0);
  const Joined j = join(grid.arrays, labels, 3, values, 0.1);
  ASSERT_EQ(j.count, 2u);
  for (std::size_t f = 0; f < labels.size(); ++f) EXPECT_EQ(j.segments[f], labels[f] == 0 ? 1 : 0);
}

TEST(SegmentSmallSegments, ZeroOrNothingBelowChangesNothing) {
  const Grid grid(10, 4);
  const auto labels = three_blocks(4, 0);
  for (double share : {0.0, 0.04}) {  // the piece is 2 of 40 cells: 5%
    const Joined j = join(grid.arrays, labels, 3, values_of(labels), share);
    EXPECT_EQ(j.count, 3u);
    EXPECT_EQ(j.segments, labels);
  }
}

TEST(SegmentSmallSegments, JoinsUntilOneIsLeftButNeverAcrossSolids) {
  Grid grid(10, 4);
  const auto labels = three_blocks(4, 0);
  EXPECT_EQ(join(grid.arrays, labels, 3, values_of(labels), 0.99).count, 1u);
  // A separate unit square beside the grid, far below the share: a segment of its own.
  const Grid square(1, 1, 20.0);
  const auto offset = static_cast<std::int64_t>(grid.arrays.vertices.size() / 3);
  grid.arrays.vertices.insert(grid.arrays.vertices.end(), square.arrays.vertices.begin(),
                              square.arrays.vertices.end());
  for (std::int64_t i : square.arrays.triangles) grid.arrays.triangles.push_back(i + offset);
  std::vector<int> with_square = labels;
  with_square.insert(with_square.end(), {3, 3});
  for (double share : {0.1, 0.99}) {
    const Joined j = join(grid.arrays, with_square, 4, values_of(with_square), share);
    EXPECT_EQ(j.count, share < 0.5 ? 3u : 2u);
    const int square_label = j.segments.back();
    for (std::size_t f = 0; f < labels.size(); ++f) EXPECT_NE(j.segments[f], square_label);
  }
}

sdf::test::Arrays two_dumbbells(std::vector<double>& values, double scale) {
  std::vector<double> thickness;
  sdf::test::Arrays a = sdf::test::dumbbell(&thickness);
  const std::size_t faces = thickness.size(), vertices = a.vertices.size() / 3;
  for (std::size_t i = 0; i < 3 * vertices; ++i)
    a.vertices.push_back(a.vertices[i] * scale + (i % 3 == 1 ? 5.0 : 0.0));
  for (std::size_t i = 0; i < 3 * faces; ++i)
    a.triangles.push_back(a.triangles[i] + static_cast<std::int64_t>(vertices));
  values = thickness;
  for (std::size_t f = 0; f < faces; ++f) values.push_back(thickness[f] * scale);
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 0.1);
  for (double& v : values) v += noise(rng);
  return a;
}

Segmentation run(const sdf::test::Arrays& a, const std::vector<double>& values, double share) {
  SegmentOptions o;
  o.clusters = 5;
  o.smoothness = 0.0;  // the mixture's own labels: speckled by the noise
  o.min_segment_area = share;
  return segment_mesh(a.vertices.data(), a.vertices.size() / 3, a.triangles.data(),
                      a.triangles.size() / 3, values.data(), o);
}

TEST(SegmentSmallSegments, InTheStage) {
  // Two noisy dumbbells, the second a tenth of the first's size: many small pieces.
  // (Ties by lowest index make the joins the same on every run.)
  std::vector<double> values;
  const sdf::test::Arrays a = two_dumbbells(values, 0.1);
  const std::size_t n = values.size(), half = n / 2;
  const Segmentation off = run(a, values, 0.0);
  EXPECT_EQ(off.segments, run(a, values, 0.0).segments);
  const double share = 0.02;
  const Segmentation s = run(a, values, share);
  EXPECT_LT(s.segment_count, off.segment_count);
  EXPECT_EQ(s.clusters, off.clusters);  // clusters stay the graph cut's
  ASSERT_EQ(s.segments.size(), n);
  std::set<int> first, second;
  for (std::size_t f = 0; f < n; ++f) {
    ASSERT_GE(s.segments[f], 0);
    ASSERT_LT(s.segments[f], static_cast<int>(s.segment_count));
    (f < half ? first : second).insert(s.segments[f]);
  }
  for (int label : second) EXPECT_EQ(first.count(label), 0u);  // never across solids
  EXPECT_EQ(first.size() + second.size(), s.segment_count);
  // Every part of the large solid is at least the share; the small solid (1% of the area)
  // is one segment, below the share, kept.
  double total = 0.0;
  for (double area : s.stats.area) total += area;
  for (int label : first) EXPECT_GE(s.stats.area[static_cast<std::size_t>(label)], share * total);
  EXPECT_EQ(second.size(), 1u);
  // Segments stay numbered by ascending mean value.
  EXPECT_TRUE(std::is_sorted(s.stats.mean_value.begin(), s.stats.mean_value.end()));
}

TEST(SegmentSmallSegments, ABadShareIsRefused) {
  std::vector<double> values;
  const sdf::test::Arrays a = two_dumbbells(values, 0.5);
  for (double share : {-0.1, 1.0, 2.0, std::nan("")})
    EXPECT_THROW(run(a, values, share), std::invalid_argument);
}

}  // namespace
