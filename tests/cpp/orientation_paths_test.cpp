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

#include "orientation_reference.h"
#include "orientation_test_meshes.h"
#include "prepare/orientation.h"
#include "prepare/orientation_edges.h"
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

bool some_edge_disagrees(const test::Arrays& a) { return EdgeUses(a.mesh(), 2).any_same(); }

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

std::size_t flipped(const test::Arrays& a) {
  return run(a, [](Mesh& m) { return orient(m, Orientation::Auto, 2); }).report.flipped_faces;
}

// A closed box of side `side` around the origin, wound outward unless `inward`.
test::Arrays shell(double side, bool inward) {
  test::Arrays a = test::box(side, side, side);
  if (inward) reverse_every(a, 1);
  return a;
}

// Every path agrees and reverses nothing; with every face reversed, every path agrees and
// turns the whole mesh back (the enclosed parts with the parts around them).
void expect_kept_and_turned_as_a_whole(test::Arrays a) {
  expect_all_paths_agree(a);
  EXPECT_EQ(flipped(a), 0u);
  reverse_every(a, 1);
  expect_all_paths_agree(a);
  EXPECT_EQ(flipped(a), a.triangles.size() / 3);
}

TEST(OrientationPaths, AHollowSolidsInnerWallStaysInward) {
  // A box with a toroidal cavity: the torus, wound inward, is the cavity's wall. Judged
  // alone (negative volume) it was turned outward: thicknesses came out ~4x too large.
  test::Arrays a = shell(6.0, false);
  test::Arrays cavity = torus(60, 40, 0.0, 31);
  reverse_every(cavity, 1);
  test::append(a, cavity);
  expect_kept_and_turned_as_a_whole(a);
}

TEST(OrientationPaths, ACavityWithTheSolidsBoxStaysInward) {
  // An octahedral cavity whose corners touch the cube's faces: the two boxes are equal, and
  // the larger volume (not the box) says which encloses which, in either order of the parts.
  test::Arrays cavity;
  cavity.vertices = {3, 0, 0, -3, 0, 0, 0, 3, 0, 0, -3, 0, 0, 0, 3, 0, 0, -3};
  cavity.triangles = {0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5};
  reverse_every(cavity, 1);  // wound inward (the list above is outward)
  test::Arrays cube_first = shell(6.0, false), cavity_first = cavity;
  test::append(cube_first, cavity);
  test::append(cavity_first, shell(6.0, false));
  for (const test::Arrays& a : {cube_first, cavity_first}) {
    expect_all_paths_agree(a);
    EXPECT_EQ(flipped(a), 0u);
  }
}

TEST(OrientationPaths, ManyCavitiesInOneSolid) {
  // 27 small boxes in a large one, every other wound inward (cavities) or outward (solids
  // inside): one encloser for many parts, its faces read once for all of them.
  test::Arrays a = shell(20.0, false);
  int k = 0;
  for (int x = -1; x <= 1; ++x)
    for (int y = -1; y <= 1; ++y)
      for (int z = -1; z <= 1; ++z, ++k) {
        test::Arrays small = test::box(1.0 + 0.1 * k / 27.0, 1.0, 1.3);
        if (k % 2) reverse_every(small, 1);
        for (std::size_t i = 0; i < small.vertices.size(); i += 3) {
          small.vertices[i] += 5.0 * x + 0.3 * y;
          small.vertices[i + 1] += 5.0 * y + 0.2 * z;
          small.vertices[i + 2] += 5.0 * z + 0.1 * x;
        }
        test::append(a, small);
      }
  expect_kept_and_turned_as_a_whole(a);
}

TEST(OrientationPaths, ASolidInsideASolidKeepsItsWinding) {
  // A torus wound outward inside a box: a separate solid (an eye in a head), or a cavity wound
  // the wrong way; nothing tells them apart, so the winding given stands.
  test::Arrays a = shell(6.0, false);
  test::append(a, torus(60, 40, 0.0, 32));
  expect_all_paths_agree(a);
  EXPECT_EQ(flipped(a), 0u);
}

TEST(OrientationPaths, NestedShellsFollowTheOutermost) {
  // Box 8 outward, box 6 inward (a cavity), a torus outward in the cavity (a solid again),
  // and beside them an inside-out torus (alone: turned outward).
  test::Arrays a = shell(8.0, false);
  test::append(a, shell(6.0, true));
  test::append(a, torus(40, 30, 0.0, 33));
  test::Arrays beside = torus(40, 30, 10.0, 34);
  reverse_every(beside, 1);
  const std::size_t nested_faces = a.triangles.size() / 3;
  test::append(a, beside);
  expect_all_paths_agree(a);
  EXPECT_EQ(flipped(a), a.triangles.size() / 3 - nested_faces);
  // All inside out but the torus beside: the nest turns as a whole, the torus not at all.
  reverse_every(a, 1);
  expect_all_paths_agree(a);
  EXPECT_EQ(flipped(a), nested_faces);
}

TEST(OrientationPaths, AnOpenBoxEnclosesNothing) {
  // A box without its top around an inside-out torus: a ray leaving through the opening
  // crosses the box an even number of times, so the torus is judged alone and turned.
  test::Arrays a = shell(6.0, false);
  // box(): the quad {4, 5, 7, 6} is the top (z = +side / 2), triangles 2 and 3.
  a.triangles.erase(a.triangles.begin() + 6, a.triangles.begin() + 12);
  const std::size_t box_faces = a.triangles.size() / 3;
  test::Arrays inner = torus(40, 30, 0.0, 35);
  reverse_every(inner, 1);
  test::append(a, inner);
  expect_all_paths_agree(a);
  EXPECT_EQ(flipped(a), a.triangles.size() / 3 - box_faces);
}

// Every face on vertices of its own (a triangle soup made of a mesh: an STL's, a CAD export's
// sides): faces meet where their corners' positions do.
test::Arrays unwelded(const test::Arrays& a) {
  test::Arrays out;
  for (std::int64_t v : a.triangles) {
    for (int c = 0; c < 3; ++c) out.vertices.push_back(a.vertices[3 * v + c]);
    out.triangles.push_back(static_cast<std::int64_t>(out.triangles.size()));
  }
  return out;
}

TEST(OrientationPaths, FacesMeetAcrossUnweldedSeams) {
  test::Arrays a = unwelded(torus(120, 80, 0.0, 14));
  reverse_every(a, 7);
  expect_all_paths_agree(a);
  EXPECT_EQ(flipped(a), (a.triangles.size() / 3 + 6) / 7);
  reverse_every(a, 1);  // inside out, with every 7th face outward: all put back outward
  expect_all_paths_agree(a);
  EXPECT_EQ(flipped(a), a.triangles.size() / 3 - (a.triangles.size() / 3 + 6) / 7);
}

TEST(OrientationPaths, TriangleSoupAgreesWithTheReference) {
  // Separate triangles, many overlapping: 20k parts, boxes and volumes per part.
  expect_all_paths_agree(test::soup(20000, 3));
}

}  // namespace
}  // namespace sdf
