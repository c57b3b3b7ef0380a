// SPDX-License-Identifier: GPL-3.0-or-later
// ConcurrentParityUnionFind under contention. A tree joins its items by bridges only, so a
// link lost to a race (one root hung under two others at once, one link overwriting the
// other) would leave the tree in two sets for good: every item must end under item 0 with
// its bit the xor of the bits along the tree's path from item 0.
#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>
#include <random>
#include <vector>

#include "util/concurrent_parity_union_find.h"
#include "util/parallel.h"

namespace sdf {
namespace {

struct Edge {
  std::uint32_t a, b, differ;
};

TEST(ConcurrentParityUnionFind, RandomTreeJoinedByManyThreads) {
  const std::uint32_t n = 1u << 19;
  for (unsigned seed : {1u, 2u, 3u}) {
    std::mt19937 rng(seed);
    // A random recursive tree (node i hangs under a random earlier node) on shuffled labels,
    // so that a set often meets sets with smaller roots on several sides at once.
    std::vector<std::uint32_t> label(n), bit_of(n, 0);
    std::iota(label.begin(), label.end(), 0u);
    std::shuffle(label.begin(), label.end(), rng);
    std::vector<Edge> edges;
    for (std::uint32_t i = 1; i < n; ++i) {
      const std::uint32_t parent = rng() % i, differ = rng() & 1u;
      bit_of[i] = bit_of[parent] ^ differ;
      edges.push_back({label[i], label[parent], differ});
    }
    std::shuffle(edges.begin(), edges.end(), rng);
    std::vector<std::uint32_t> expected(n);  // per label, its bit relative to label 0's
    const std::uint32_t zero =
        static_cast<std::uint32_t>(std::find(label.begin(), label.end(), 0u) - label.begin());
    for (std::uint32_t i = 0; i < n; ++i) expected[label[i]] = bit_of[i] ^ bit_of[zero];

    ConcurrentParityUnionFind sets(n, 8);
    // Small chunks on more threads than cores: threads are preempted mid-union.
    parallel_for(edges.size(), 64, 8, [&](std::size_t begin, std::size_t end) {
      for (std::size_t i = begin; i < end; ++i)
        ASSERT_TRUE(sets.unite(edges[i].a, edges[i].b, edges[i].differ));
    });
    std::size_t wrong_root = 0, wrong_bit = 0;
    for (std::uint32_t v = 0; v < n; ++v) {
      const ConcurrentParityUnionFind::Found found = sets.find(v);
      wrong_root += found.root != 0;
      wrong_bit += found.parity != expected[v];
    }
    EXPECT_EQ(wrong_root, 0u) << "seed " << seed;
    EXPECT_EQ(wrong_bit, 0u) << "seed " << seed;
    // An edge closing a cycle is consistent only with the bit the tree already implies.
    const std::uint32_t v = n / 2;
    EXPECT_FALSE(sets.unite(0, v, expected[v] ^ 1u));
    EXPECT_TRUE(sets.unite(v, 0, expected[v]));
  }
}

}  // namespace
}  // namespace sdf
