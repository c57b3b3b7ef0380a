// SPDX-License-Identifier: GPL-3.0-or-later
// compute_field, the whole call: a double-sided mesh gives each face and vertex of its back
// its front's values (the front cast alone, bit for bit, on vertices of its own too); the
// progress only grows; smoothing and normalisation run on the field the twins complete.
#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

#include "pipeline/field.h"
#include "test_meshes.h"

namespace sdf {
namespace {

MeshArrays view(const test::Arrays& a) {
  return {a.vertices.data(), a.vertices.size() / 3, a.triangles.data(), a.triangles.size() / 3};
}

// The box's faces again, reversed (b, a, c for a, b, c); with own_vertices, on vertices of
// their own at the same positions (the back of a mesh exported double-sided).
test::Arrays double_sided(const test::Arrays& front, bool own_vertices) {
  test::Arrays a = front;
  const std::int64_t offset =
      own_vertices ? static_cast<std::int64_t>(front.vertices.size() / 3) : 0;
  if (own_vertices)
    a.vertices.insert(a.vertices.end(), front.vertices.begin(), front.vertices.end());
  for (std::size_t f = 0; f < front.triangles.size(); f += 3)
    a.triangles.insert(a.triangles.end(),
                       {front.triangles[f + 1] + offset, front.triangles[f] + offset,
                        front.triangles[f + 2] + offset});
  return a;
}

FieldOptions options_for(PointKind points, SmoothingMethod smoothing) {
  FieldOptions o;
  o.cast.points = points;
  o.smoothing.method = smoothing;
  o.smoothing.kring.k = 1;
  return o;
}

TEST(Field, DoubleSidedFacesTakeTheFrontsValues) {
  const test::Arrays front = test::box(1.0, 2.0, 3.0);
  for (bool own : {false, true}) {
    const test::Arrays both = double_sided(front, own);
    const FieldOptions o = options_for(PointKind::Faces, SmoothingMethod::Kring);
    const Field alone = compute_field(view(front), o);
    const Field whole = compute_field(view(both), o);
    const std::size_t m = front.triangles.size() / 3;
    ASSERT_EQ(whole.twin_faces, m);
    ASSERT_EQ(whole.values.size(), 2 * m);
    for (std::size_t f = 0; f < 2 * m; ++f) {
      EXPECT_EQ(whole.cast.raw[f], alone.cast.raw[f % m]) << f;
      EXPECT_EQ(whole.values[f], alone.values[f % m]) << f;
      EXPECT_EQ(whole.cast.valid_rays[f], alone.cast.valid_rays[f % m]) << f;
    }
  }
}

TEST(Field, BackVerticesOfTheirOwnTakeTheFrontVerticesValues) {
  const test::Arrays front = test::box(1.0, 2.0, 3.0);
  const test::Arrays both = double_sided(front, true);
  const FieldOptions o = options_for(PointKind::Vertices, SmoothingMethod::None);
  const Field alone = compute_field(view(front), o);
  const Field whole = compute_field(view(both), o);
  const std::size_t n = front.vertices.size() / 3;
  ASSERT_EQ(whole.values.size(), 2 * n);
  for (std::size_t v = 0; v < 2 * n; ++v) EXPECT_EQ(whole.values[v], alone.values[v % n]) << v;
}

TEST(Field, ProgressOnlyGrowsAndEndsAtOne) {
  const test::Arrays both = double_sided(test::box(1.0, 1.0, 1.0), false);
  std::vector<double> told;
  const ProgressFn progress = [&](double f) {
    told.push_back(f);
    return true;
  };
  compute_field(view(both), options_for(PointKind::Faces, SmoothingMethod::Kring), progress);
  ASSERT_FALSE(told.empty());
  EXPECT_TRUE(std::is_sorted(told.begin(), told.end()));
  EXPECT_EQ(told.back(), 1.0);
}

TEST(Field, NormalizedSpansTheUnitInterval) {
  const Field f = compute_field(view(test::box(1.0, 2.0, 3.0)),
                                options_for(PointKind::Faces, SmoothingMethod::None));
  ASSERT_EQ(f.normalized.size(), f.values.size());
  EXPECT_EQ(*std::min_element(f.normalized.begin(), f.normalized.end()), 0.0f);
  EXPECT_EQ(*std::max_element(f.normalized.begin(), f.normalized.end()), 1.0f);
  EXPECT_EQ(f.values, f.cast.raw);  // no smoothing: the field is the cast
}

}  // namespace
}  // namespace sdf
