// SPDX-License-Identifier: GPL-3.0-or-later
// reversed_twins against a brute-force reading of its contract (every pair of faces compared),
// on meshes that plant each kind of coincident face.
#include <gtest/gtest.h>

#include <random>
#include <tuple>
#include <vector>

#include "mesh_twins.h"
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

// The contract, pair by pair: face f is dropped for the lowest face g < f at the same three
// distinct positions, when g runs the other way.
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
  Found out;
  for (std::size_t f = 0; f < m; ++f) {
    if (!distinct(f)) continue;
    for (std::size_t g = 0; g < f; ++g) {
      if (!distinct(g) || at(f, 0, g) < 0 || at(f, 1, g) < 0 || at(f, 2, g) < 0) continue;
      const int c0 = at(f, 0, g);
      if (at(f, 1, g) == (c0 + 2) % 3)
        out.emplace_back(static_cast<std::uint32_t>(f), static_cast<std::uint32_t>(g), c0);
      break;  // the lowest face at these positions decides
    }
  }
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
        case 0: a.triangles.insert(a.triangles.end(), {t0, t2, t1}); break;        // reversed
        case 1: a.triangles.insert(a.triangles.end(), {t1, t0, t2}); break;        // reversed
        case 2: a.triangles.insert(a.triangles.end(), {t1, t2, t0}); break;        // same way
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
  }
}

// -0 and +0 are one place: a mesh centred on the origin keeps the sign of a zero.
TEST(ReversedTwins, ReadsMinusZeroAsZero) {
  test::Arrays a;
  a.vertices = {0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, -0.0, -0.0, 0.0, -1.0, -1.0, -1.0};
  a.triangles = {0, 1, 2, 3, 2, 1, 4, 1, 2};
  const ReversedTwins t = find(a, 0);
  ASSERT_EQ(t.dropped.size(), 1u);
  EXPECT_EQ(t.dropped[0], 1u);
  EXPECT_EQ(t.twin[0], 0u);
  EXPECT_EQ(t.corner[0], 0);
}

}  // namespace
}  // namespace sdf
