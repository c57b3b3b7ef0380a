// SPDX-License-Identifier: GPL-3.0-or-later
#include <gtest/gtest.h>

#include <limits>
#include <stdexcept>

#include "test_meshes.h"

namespace sdf {
namespace {

TEST(MeshValidation, CentresOnTheBoundingBox) {
  test::Arrays a = test::box(2.0, 4.0, 6.0);
  for (std::size_t i = 0; i < a.vertices.size(); i += 3) a.vertices[i] += 1000.0;
  const Mesh m = a.mesh();
  EXPECT_DOUBLE_EQ(m.center.x, 1000.0);
  EXPECT_DOUBLE_EQ(m.max_extent, 6.0);
  EXPECT_FLOAT_EQ(m.vertices[0].x, -1.0f);  // float precision kept far from the origin
  EXPECT_FLOAT_EQ(minimum_closeness(m), 6.0f * 2e-5f);
}

TEST(MeshValidation, RejectsIndexOutOfRangeAnywhere) {
  test::Arrays a = test::box(1, 1, 1);
  a.triangles[17] = 8;  // in the middle, equal to the vertex count
  EXPECT_THROW(a.mesh(), std::invalid_argument);
  a.triangles[17] = -1;
  EXPECT_THROW(a.mesh(), std::invalid_argument);
}

TEST(MeshValidation, RejectsNonFiniteAndEmpty) {
  test::Arrays a = test::box(1, 1, 1);
  a.vertices[10] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(a.mesh(), std::invalid_argument);
  a.vertices[10] = std::numeric_limits<double>::infinity();
  EXPECT_THROW(a.mesh(), std::invalid_argument);
  EXPECT_THROW(make_mesh(nullptr, 0, nullptr, 0), std::invalid_argument);
  const double v[3] = {0, 0, 0};
  EXPECT_THROW(make_mesh(v, 1, nullptr, 0), std::invalid_argument);
}

// Corners are numbered in 32 bits: a count above 2^32 / 3 triangles is refused before any
// triangle is read (the array here holds one).
TEST(MeshValidation, RejectsMoreTrianglesThanCornerNumbersReach) {
  const double v[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  const std::int64_t t[3] = {0, 1, 2};
  EXPECT_NO_THROW(make_mesh(v, 3, t, 1));
  EXPECT_THROW(make_mesh(v, 3, t, std::size_t{0xffffffffu} / 3 + 1), std::invalid_argument);
}

TEST(MeshValidation, FaceNormalsPointOutOfTheBox) {
  const Mesh m = test::box(1, 1, 1).mesh();
  for (std::size_t f = 0; f < m.triangles.size(); ++f) {
    const glm::uvec3 t = m.triangles[f];
    const glm::vec3 centroid = (m.vertices[t.x] + m.vertices[t.y] + m.vertices[t.z]) / 3.0f;
    EXPECT_GT(glm::dot(face_area_normal(m, f), centroid), 0.0f) << "face " << f;
  }
}

}  // namespace
}  // namespace sdf

namespace sdf {
namespace {

TEST(MeshValidation, RejectsMeshesWiderThanTheFloatRange) {
  // Finite doubles, but past what float arithmetic on the centred mesh can hold.
  const double far[9] = {1e300, 0, 0, 0, 1, 0, 0, 0, 1};
  const std::int64_t tri[3] = {0, 1, 2};
  EXPECT_THROW(make_mesh(far, 3, tri, 1), std::invalid_argument);
  const double wide[9] = {-3e38, 0, 0, 3e38, 1, 0, 0, 0, 1};
  EXPECT_THROW(make_mesh(wide, 3, tri, 1), std::invalid_argument);
  const double fine[9] = {-1e29, 0, 0, 1e29, 1, 0, 0, 0, 1};
  EXPECT_NO_THROW(make_mesh(fine, 3, tri, 1));
}

}  // namespace
}  // namespace sdf
