// SPDX-License-Identifier: GPL-3.0-or-later
// Step 1 of orient(Auto), the patches: the parallel version (a union-find carrying each
// face's winding relative to its set's root) must give the serial walk's flips face for face
// wherever it accepts a mesh, and must refuse the meshes where only the walk's order defines
// the result; both must match the first-written reference (orientation_reference.h).
#include <gtest/gtest.h>

#include <vector>

#include "orientation_reference.h"
#include "orientation_test_meshes.h"
#include "prepare/orientation_edges.h"
#include "prepare/orientation_parts.h"
#include "prepare/orientation_patches.h"

namespace sdf {
namespace {

std::size_t count_differing(const std::vector<char>& a, const std::vector<char>& b) {
  std::size_t differing = a.size() == b.size() ? 0 : a.size() + b.size();
  for (std::size_t f = 0; f < a.size() && f < b.size(); ++f)
    differing += (a[f] != 0) != (b[f] != 0);
  return differing;
}

// Accepted by the parallel version on every thread count, with the serial flips.
// Edges by their ends' positions, as orient() finds them.
std::vector<char> reference_flips(const Mesh& mesh) {
  return test::reference_consistent_flips(mesh, test::reference_weld_exact(mesh));
}

void expect_parallel_agrees(const test::Arrays& a) {
  const Mesh mesh = a.mesh();
  const UninitializedVector<std::uint32_t> same_place = weld_exact(mesh, 2);
  const EdgeUses edges(mesh, 2, same_place.data());
  const std::vector<char> serial = patch_flips_serial(mesh, edges.neighbours(2));
  EXPECT_EQ(count_differing(serial, reference_flips(mesh)), 0u);
  for (unsigned threads : {1u, 2u, 5u}) {
    SCOPED_TRACE(threads);
    const std::optional<std::vector<char>> parallel = patch_flips_parallel(mesh, edges, threads);
    ASSERT_TRUE(parallel.has_value());
    EXPECT_EQ(count_differing(*parallel, serial), 0u);
    EXPECT_EQ(count_differing(patch_flips(mesh, edges, threads), serial), 0u);
  }
}

// Refused by the parallel version; patch_flips then gives the walk's flips, the reference's.
void expect_left_to_the_walk(const Mesh& mesh) {
  const UninitializedVector<std::uint32_t> same_place = weld_exact(mesh, 2);
  const EdgeUses edges(mesh, 2, same_place.data());
  EXPECT_FALSE(patch_flips_parallel(mesh, edges, 2).has_value());
  const std::vector<char> serial = patch_flips_serial(mesh, edges.neighbours(3));
  EXPECT_EQ(count_differing(serial, reference_flips(mesh)), 0u);
  EXPECT_EQ(count_differing(patch_flips(mesh, edges, 3), serial), 0u);
}

std::size_t count_flipped(const std::vector<char>& flip) {
  std::size_t n = 0;
  for (char c : flip) n += c != 0;
  return n;
}

TEST(OrientationPatches, ScatteredFlipsAreUndone) {
  test::Arrays a = test::torus(300, 200, 0.0, 21);  // 120k faces, shuffled
  test::reverse_every(a, 3);
  expect_parallel_agrees(a);
  const Mesh mesh = a.mesh();
  const std::vector<char> flip = patch_flips(mesh, EdgeUses(mesh, 2), 2);
  EXPECT_EQ(count_flipped(flip), mesh.triangles.size() / 3);  // the third reversed, no more
}

TEST(OrientationPatches, TheLargerAreaKeepsItsWinding) {
  // Two of three faces reversed: the patch takes the reversed winding (the torus is then
  // inside out; step 2 turns it back) and flips the third that was not.
  test::Arrays a = test::torus(120, 80, 0.0, 22);
  test::reverse_every(a, 3, 0);
  test::reverse_every(a, 3, 1);
  expect_parallel_agrees(a);
  const Mesh mesh = a.mesh();
  const std::vector<char> flip = patch_flips(mesh, EdgeUses(mesh, 2), 2);
  EXPECT_EQ(count_flipped(flip), mesh.triangles.size() / 3);
  for (std::size_t f = 2; f < mesh.triangles.size(); f += 3) EXPECT_TRUE(flip[f]) << f;
}

TEST(OrientationPatches, ManyPatchesAndASeam) {
  // Three tori in grid order and shuffled, one inside out, one with an unwelded seam (two
  // patches in one part), faces flipped in each; and a soup of lone triangles (a patch each).
  test::Arrays a = test::torus(60, 40, 0.0, 0);
  test::reverse_every(a, 7);
  test::Arrays inside_out = test::torus(30, 20, 3.0, 23);
  test::reverse_every(inside_out, 1);
  test::reverse_every(inside_out, 5, 2);
  test::append(a, inside_out);
  test::append(a, test::soup(3000, 4));
  test::Arrays seam = test::torus(40, 30, -3.0, 0);
  const std::int64_t base = static_cast<std::int64_t>(seam.vertices.size() / 3);
  for (int j = 0; j < 30; ++j)
    seam.vertices.insert(seam.vertices.end(), seam.vertices.begin() + 3 * j,
                         seam.vertices.begin() + 3 * j + 3);
  for (std::size_t f = 39 * 30 * 2; f < seam.triangles.size() / 3; ++f)
    for (int k = 0; k < 3; ++k)
      if (seam.triangles[3 * f + k] < 30) seam.triangles[3 * f + k] += base;
  test::reverse_every(seam, 11, 3);
  test::append(a, seam);
  expect_parallel_agrees(a);
}

TEST(OrientationPatches, ATieKeepsTheFirstFacesWinding) {
  // A square of two triangles of equal area, one reversed: the areas tie, and the patch keeps
  // the winding of its first face (where the walk starts, the union-find's root).
  for (int reversed : {0, 1}) {
    SCOPED_TRACE(reversed);
    test::Arrays a;
    a.vertices = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
    a.triangles = {0, 1, 2, 0, 2, 3};
    test::reverse_every(a, 2, reversed);
    expect_parallel_agrees(a);
    const Mesh mesh = a.mesh();
    const std::vector<char> flip = patch_flips(mesh, EdgeUses(mesh, 2), 2);
    EXPECT_EQ(flip, (std::vector<char>{0, 1}));
  }
}

// What join_patches must accept, defined on the lists: every listed neighbour lists its face
// back with the same bit, and no cycle of lists asks a face to be both ways (a walk that
// gives each face a bit meets no contradiction).
bool lists_define_patches(const EdgeNeighbours& edges) {
  const std::size_t n = edges.face.size() / 3;
  for (std::size_t slot = 0; slot < 3 * n; ++slot) {
    const std::uint32_t g = edges.face[slot];
    if (g == kNoNeighbour) continue;
    bool listed_back = false;
    for (int k = 0; k < 3; ++k)
      listed_back |= edges.face[3 * std::size_t{g} + k] == slot / 3 &&
                     edges.same[3 * std::size_t{g} + k] == edges.same[slot];
    if (!listed_back) return false;
  }
  std::vector<int> bit(n, -1);
  for (std::size_t seed = 0; seed < n; ++seed) {
    if (bit[seed] >= 0) continue;
    std::vector<std::size_t> queue{seed};
    bit[seed] = 0;
    while (!queue.empty()) {
      const std::size_t f = queue.back();
      queue.pop_back();
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t g = edges.face[3 * f + k];
        if (g == kNoNeighbour) continue;
        const int want = bit[f] ^ edges.same[3 * f + k];
        if (bit[g] < 0) {
          bit[g] = want;
          queue.push_back(g);
        } else if (bit[g] != want) {
          return false;
        }
      }
    }
  }
  return true;
}

TEST(OrientationPatches, JoiningAcceptsExactlyWhatTheListsDefine) {
  // join_patches reads the edge uses, not the lists: it must accept a mesh exactly when the
  // lists made from the same uses are mutual and orientable.
  auto mesh_of = [](std::vector<double> vertices, std::vector<std::int64_t> triangles) {
    test::Arrays a;
    a.vertices = std::move(vertices);
    a.triangles = std::move(triangles);
    return a;
  };
  const std::vector<double> square = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 0, 0, 1};
  test::Arrays reversed_torus = test::torus(30, 20, 0.0, 5);
  test::reverse_every(reversed_torus, 3);
  const std::vector<std::pair<const char*, test::Arrays>> cases = {
      {"reversed torus", reversed_torus},
      {"awkward", test::awkward_mesh()},
      {"moebius", test::moebius_strip(0.0)},
      {"edge used twice", mesh_of(square, {0, 1, 0, 0, 1, 2})},
      {"duplicate face, same winding", mesh_of(square, {0, 1, 2, 0, 1, 2})},
      {"duplicate face, opposite winding", mesh_of(square, {0, 1, 2, 0, 2, 1})},
      {"fin of three faces", mesh_of(square, {0, 1, 2, 1, 0, 3, 0, 1, 4})},
      {"two faces sharing two edges both ways", mesh_of(square, {0, 1, 2, 1, 0, 2})},
      {"a face's corners repeated", mesh_of(square, {0, 0, 0, 0, 1, 2, 2, 1, 3})},
  };
  for (const auto& [name, arrays] : cases) {
    SCOPED_TRACE(name);
    const Mesh mesh = arrays.mesh();
    const EdgeUses edges(mesh, 2);
    const bool defined = lists_define_patches(edges.neighbours(2));
    for (unsigned threads : {1u, 3u}) {
      ConcurrentParityUnionFind sets(mesh.triangles.size(), threads);
      EXPECT_EQ(edges.join_patches(sets, threads), defined) << threads << " threads";
    }
  }
}

TEST(OrientationPatches, AFaceUsingItsEdgeTwiceIsLeftToTheWalk) {
  // (0, 1, 0) uses the edge 0-1 both ways, and so lists the face across it twice with
  // opposite bits (that face lists it not at all): the parallel version refuses.
  test::Arrays a;
  a.vertices = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  for (const std::vector<std::int64_t>& faces :
       {std::vector<std::int64_t>{0, 1, 0, 0, 1, 2}, std::vector<std::int64_t>{0, 1, 2, 0, 1, 0}}) {
    a.triangles = faces;
    expect_left_to_the_walk(a.mesh());
  }
}

TEST(OrientationPatches, OnlyTheSerialWalkDefinesAwkwardMeshes) {
  // A Moebius strip (no winding agrees all round) among degenerate and non-manifold faces:
  // the parallel version refuses; patch_flips falls back to the walk.
  expect_left_to_the_walk(test::awkward_mesh().mesh());
}

TEST(OrientationPatches, AMoebiusStripAloneIsRefused) {
  expect_left_to_the_walk(test::moebius_strip(0.0).mesh());
}

}  // namespace
}  // namespace sdf
