// SPDX-License-Identifier: GPL-3.0-or-later
// reversed_twins against a brute-force reading of its contract (every pair of faces compared),
// on meshes that plant each kind of coincident face.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <tuple>
#include <vector>

#include "mesh/mesh_twins.h"
#include "test_meshes.h"

namespace sdf {
namespace {

using Found = std::vector<std::tuple<std::uint32_t, std::uint32_t, int>>;

Found as_list(const ReversedTwins& t) {
  Found out;
  for (std::size_t i = 0; i < t.dropped.size(); ++i)
    out.emplace_back(t.dropped[i], t.twin[i], t.corner[i]);
  return out;
}

// The contract, read literally: the faces at each set of three distinct positions; where both
// windings are among them, each face wound against the lowest is left out for it, but only
// when every face with area of its part (faces joined by shared vertex indices) lies in such a
// group.
Found brute_force(const Mesh& mesh) {
  const std::size_t m = mesh.triangles.size();
  auto pos = [&](std::size_t f, int k) { return mesh.vertices[mesh.triangles[f][k]]; };
  auto distinct = [&](std::size_t f) {
    return pos(f, 0) != pos(f, 1) && pos(f, 1) != pos(f, 2) && pos(f, 0) != pos(f, 2);
  };
  auto at = [&](std::size_t f, int k, std::size_t g) {
    for (int j = 0; j < 3; ++j)
      if (pos(f, k) == pos(g, j)) return j;
    return -1;
  };
  auto same = [&](std::size_t f, std::size_t g) {
    return distinct(f) && distinct(g) && at(f, 0, g) >= 0 && at(f, 1, g) >= 0 && at(f, 2, g) >= 0;
  };
  auto reversed = [&](std::size_t f, std::size_t g) {
    return at(f, 1, g) == (at(f, 0, g) + 2) % 3;
  };
  Found pairs;
  std::vector<char> paired(m, 0);
  for (std::size_t f = 0; f < m; ++f) {
    std::size_t lowest = f;
    for (std::size_t g = 0; g < f && lowest == f; ++g)
      if (same(f, g)) lowest = g;
    if (lowest != f) continue;  // grouped with its lowest face
    std::vector<std::size_t> group{f};
    bool mixed = false;
    for (std::size_t g = f + 1; g < m; ++g)
      if (same(g, f)) {
        group.push_back(g);
        if (reversed(g, f)) {
          mixed = true;
          pairs.emplace_back(static_cast<std::uint32_t>(g), static_cast<std::uint32_t>(f),
                             at(g, 0, f));
        }
      }
    if (mixed)
      for (std::size_t g : group) paired[g] = 1;
  }
  std::vector<std::size_t> parent(mesh.vertices.size());
  for (std::size_t v = 0; v < parent.size(); ++v) parent[v] = v;
  auto root = [&](std::size_t v) {
    while (parent[v] != v) v = parent[v];
    return v;
  };
  for (std::size_t f = 0; f < m; ++f)
    for (int k = 1; k < 3; ++k) parent[root(mesh.triangles[f][k])] = root(mesh.triangles[f][0]);
  std::vector<char> single(parent.size(), 0);
  for (std::size_t f = 0; f < m; ++f)
    if (!paired[f] && face_area_normal(mesh, f) != glm::vec3(0.0f))
      single[root(mesh.triangles[f][0])] = 1;
  Found out;
  for (const auto& pair : pairs)
    if (!single[root(mesh.triangles[std::get<0>(pair)][0])]) out.push_back(pair);
  std::sort(out.begin(), out.end());
  return out;
}

ReversedTwins find(const test::Arrays& a, unsigned threads) {
  return reversed_twins(a.mesh(), threads);
}

TEST(ReversedTwins, NoneOnASingleSidedBox) {
  EXPECT_TRUE(find(test::box(1, 2, 3), 0).dropped.empty());
}

// The box and its faces again, reversed: once on the same vertices, once on copies of them.
TEST(ReversedTwins, FindsADoubleSidedBoxOnSharedAndSplitVertices) {
  for (bool split : {false, true}) {
    test::Arrays a = test::box(1, 2, 3);
    const std::int64_t offset = split ? 8 : 0;
    if (split) a.vertices.insert(a.vertices.end(), a.vertices.begin(), a.vertices.end());
    const std::size_t n = a.triangles.size();
    for (std::size_t i = 0; i < n; i += 3)
      a.triangles.insert(a.triangles.end(), {a.triangles[i + 1] + offset, a.triangles[i] + offset,
                                             a.triangles[i + 2] + offset});
    const ReversedTwins t = find(a, 0);
    ASSERT_EQ(t.dropped.size(), 12u) << "split " << split;
    for (std::size_t i = 0; i < 12; ++i) {
      EXPECT_EQ(t.dropped[i], 12 + i);
      EXPECT_EQ(t.twin[i], i);
      EXPECT_EQ(t.corner[i], 1);  // corner 0 of (b, a, c) is corner 1 of (a, b, c)
    }
    EXPECT_EQ(as_list(t), brute_force(a.mesh()));
  }
}

// Coincident faces of every kind among random ones, on 1, 2 and 8 threads.
TEST(ReversedTwins, AgreesWithEveryPairComparedOnPlantedMeshes) {
  std::mt19937 rng(7);
  for (int round = 0; round < 20; ++round) {
    test::Arrays a = test::soup(300, 100 + round);
    std::uniform_int_distribution<int> face(0, 299), kind(0, 5);
    for (int i = 0; i < 120; ++i) {
      const int f = face(rng);
      const std::int64_t t0 = a.triangles[3 * f], t1 = a.triangles[3 * f + 1],
                         t2 = a.triangles[3 * f + 2];
      auto copy = [&](std::int64_t v) {  // the same position on a vertex of its own
        const std::int64_t c = static_cast<std::int64_t>(a.vertices.size() / 3);
        a.vertices.insert(a.vertices.end(),
                          {a.vertices[3 * v], a.vertices[3 * v + 1], a.vertices[3 * v + 2]});
        return c;
      };
      switch (kind(rng)) {
        case 0: a.triangles.insert(a.triangles.end(), {t0, t2, t1}); break;  // reversed
        case 1: a.triangles.insert(a.triangles.end(), {t1, t0, t2}); break;  // reversed
        case 2: a.triangles.insert(a.triangles.end(), {t1, t2, t0}); break;  // same way
        case 3: a.triangles.insert(a.triangles.end(), {copy(t2), copy(t1), copy(t0)}); break;
        case 4: a.triangles.insert(a.triangles.end(), {copy(t0), copy(t1), copy(t2)}); break;
        default: a.triangles.insert(a.triangles.end(), {t0, t0, t1}); break;  // degenerate
      }
    }
    // A twin listed before the face it mirrors.
    const std::int64_t first = a.triangles[0], second = a.triangles[1], third = a.triangles[2];
    a.triangles.insert(a.triangles.begin(), {first, third, second});
    const Found expected = brute_force(a.mesh());
    ASSERT_FALSE(expected.empty());
    for (unsigned threads : {1u, 2u, 8u})
      EXPECT_EQ(as_list(find(a, threads)), expected) << "round " << round << ", " << threads;
    // The same mesh with some faces reversed, and told which: the caller's twins and corners.
    Mesh turned = a.mesh();
    std::vector<std::uint8_t> reversed(turned.triangles.size());
    for (std::size_t f = 0; f < reversed.size(); ++f) {
      reversed[f] = rng() % 3 == 0;
      if (reversed[f]) std::swap(turned.triangles[f].y, turned.triangles[f].z);
    }
    EXPECT_EQ(as_list(reversed_twins(turned, 2, reversed.data())), expected) << "round " << round;
    EXPECT_NE(as_list(reversed_twins(turned, 2)), expected) << "round " << round;
  }
}

// Several chunks of work (the table is filled in parallel, each chunk its own pipeline): every
// third face of 40000 doubled at the end, reversed, on vertices of its own.
TEST(ReversedTwins, FindsEveryPlantedTwinAcrossChunksOfWork) {
  test::Arrays a = test::soup(40000, 11);
  Found expected;
  for (std::int64_t f = 0; f < 40000; f += 3) {
    const std::int64_t c = static_cast<std::int64_t>(a.vertices.size() / 3);
    for (int k : {2, 1, 0})  // corners c, c + 1, c + 2 at the face's corners 2, 1, 0
      for (int d = 0; d < 3; ++d) a.vertices.push_back(a.vertices[3 * a.triangles[3 * f + k] + d]);
    a.triangles.insert(a.triangles.end(), {c, c + 1, c + 2});
    expected.emplace_back(static_cast<std::uint32_t>(a.triangles.size() / 3 - 1),
                          static_cast<std::uint32_t>(f), 2);
  }
  for (unsigned threads : {1u, 2u, 8u}) EXPECT_EQ(as_list(find(a, threads)), expected) << threads;
}

// Two boxes meeting at a wall: each wall face has a reversed twin in the other box, but each
// box has faces away from the wall: no part is doubled, no face is left out. The first box
// doubled (its faces again, reversed, on vertices of their own) is.
TEST(ReversedTwins, SolidsMeetingAtAWallAreNotDoubleSided) {
  test::Arrays a = test::box(1, 1, 1);
  test::Arrays b = test::box(1, 1, 1);
  for (std::size_t i = 0; i < b.vertices.size(); i += 3) b.vertices[i] += 1.0;  // x = 0.5 shared
  const std::int64_t offset = static_cast<std::int64_t>(a.vertices.size() / 3);
  a.vertices.insert(a.vertices.end(), b.vertices.begin(), b.vertices.end());
  for (std::int64_t i : b.triangles) a.triangles.push_back(i + offset);
  EXPECT_TRUE(brute_force(a.mesh()).empty());
  EXPECT_TRUE(find(a, 2).dropped.empty());
  const std::int64_t back = static_cast<std::int64_t>(a.vertices.size() / 3);
  const std::vector<double> first(a.vertices.begin(), a.vertices.begin() + 24);
  a.vertices.insert(a.vertices.end(), first.begin(), first.end());
  for (std::size_t i = 0; i < 36; i += 3)
    a.triangles.insert(a.triangles.end(), {a.triangles[i] + back, a.triangles[i + 2] + back,
                                           a.triangles[i + 1] + back});
  const ReversedTwins t = find(a, 2);
  ASSERT_EQ(t.dropped.size(), 12u);
  EXPECT_EQ(t.dropped.front(), 24u);
  EXPECT_EQ(as_list(t), brute_force(a.mesh()));
}

// -0 and +0 are one place: a mesh centred on the origin keeps the sign of a zero.
TEST(ReversedTwins, ReadsMinusZeroAsZero) {
  test::Arrays a;
  a.vertices = {0.0,  0.0,  0.0,  1.0,  0.0,  0.0,  0.0,  1.0,  0.0,  -0.0, -0.0,
                -0.0, -1.0, -1.0, -1.0, -1.0, -0.9, -1.0, -0.9, -1.0, -1.0};
  a.triangles = {0, 1, 2, 3, 2, 1, 4, 5, 6};  // the last, apart, centres the box on 0
  const ReversedTwins t = find(a, 0);
  ASSERT_EQ(t.dropped.size(), 1u);
  EXPECT_EQ(t.dropped[0], 1u);
  EXPECT_EQ(t.twin[0], 0u);
  EXPECT_EQ(t.corner[0], 0);
}

}  // namespace
}  // namespace sdf
