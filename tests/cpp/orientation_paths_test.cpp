// SPDX-License-Identifier: GPL-3.0-or-later
// orient(Auto) is parallel and skips the propagation when every manifold edge already runs
// opposite ways in its two faces. Neither may change a result: checked against the serial
// reference (orientation_reference.h), against the path without the shortcut, and across
// thread counts, on meshes large enough to span many parallel chunks.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <vector>

#include "orientation.h"
#include "orientation_edges.h"
#include "orientation_reference.h"
#include "orientation_test_meshes.h"
#include "test_meshes.h"

namespace sdf {
namespace {

using test::awkward_mesh;
using test::reverse_every;
using test::torus;

struct Oriented {
  UninitializedVector<glm::uvec3> triangles;
  OrientationReport report;
};

template <class Orient>
Oriented run(const test::Arrays& a, Orient&& orient_it) {
  Mesh mesh = a.mesh();
  Oriented out;
  out.report = orient_it(mesh);
  out.triangles = mesh.triangles;
  return out;
}

void expect_same(const Oriented& expected, const Oriented& actual) {
  EXPECT_EQ(expected.report.flipped_faces, actual.report.flipped_faces);
  EXPECT_EQ(expected.report.parts, actual.report.parts);
  ASSERT_EQ(expected.triangles.size(), actual.triangles.size());
  std::size_t differing = 0;
  for (std::size_t f = 0; f < expected.triangles.size(); ++f)
    differing += expected.triangles[f] != actual.triangles[f];
  EXPECT_EQ(differing, 0u);
}

// Every way of running Auto gives the reference's faces and report.
void expect_all_paths_agree(const test::Arrays& a) {
  const Oriented reference = run(a, [](Mesh& m) { return test::reference_orient_auto(m); });
  for (unsigned threads : {1u, 2u, 5u}) {
    SCOPED_TRACE(threads);
    expect_same(reference, run(a, [&](Mesh& m) { return orient(m, Orientation::Auto, threads); }));
    expect_same(reference,
                run(a, [&](Mesh& m) { return orient_auto_without_fast_path(m, threads); }));
  }
}

bool some_edge_disagrees(const test::Arrays& a) {
  return manifold_edge_neighbours(a.mesh(), 2).any_same;
}

TEST(OrientationPaths, ConsistentMeshTakesTheFastPathAndAgrees) {
  const test::Arrays a = torus(300, 200, 0.0, 11);  // 120k faces, shuffled
  EXPECT_FALSE(some_edge_disagrees(a));
  expect_all_paths_agree(a);
  EXPECT_EQ(run(a, [](Mesh& m) { return orient(m, Orientation::Auto, 2); }).report.flipped_faces,
            0u);
}

TEST(OrientationPaths, InsideOutMeshIsReversedWhole) {
  test::Arrays a = torus(300, 200, 0.0, 12);
  reverse_every(a, 1);
  EXPECT_FALSE(some_edge_disagrees(a));  // consistent, just inward: the fast path still applies
  expect_all_paths_agree(a);
  EXPECT_EQ(run(a, [](Mesh& m) { return orient(m, Orientation::Auto, 2); }).report.flipped_faces,
            a.triangles.size() / 3);
}

TEST(OrientationPaths, SomeFlippedFacesTakeTheGeneralPathAndAgree) {
  test::Arrays a = torus(300, 200, 0.0, 13);
  reverse_every(a, 97);
  EXPECT_TRUE(some_edge_disagrees(a));
  expect_all_paths_agree(a);
  EXPECT_EQ(run(a, [](Mesh& m) { return orient(m, Orientation::Auto, 2); }).report.flipped_faces,
            (a.triangles.size() / 3 + 96) / 97);
}

TEST(OrientationPaths, AwkwardMeshAgreesWithTheReference) {
  const test::Arrays a = awkward_mesh();
  EXPECT_TRUE(some_edge_disagrees(a));
  expect_all_paths_agree(a);
  EXPECT_EQ(run(a, [](Mesh& m) { return orient(m, Orientation::Auto, 3); }).report.parts, 4u);
}

TEST(OrientationPaths, TriangleSoupAgreesWithTheReference) {
  // Separate triangles, many overlapping: 20k parts, boxes and volumes per part.
  expect_all_paths_agree(test::soup(20000, 3));
}

}  // namespace
}  // namespace sdf
