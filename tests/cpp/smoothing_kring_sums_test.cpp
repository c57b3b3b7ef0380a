// SPDX-License-Identifier: GPL-3.0-or-later
#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "post/smoothing_kring_sums.h"

namespace sdf {
namespace {

// Items whose masks range from one point to all 64, values of mixed sign and size, added
// over several rings to running sums that do not start at zero.
std::vector<RingItem> random_items(std::size_t n, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> value(-3.0f, 7.0f);
  std::vector<RingItem> items(n);
  for (RingItem& item : items) {
    const int density = static_cast<int>(rng() % 4);  // AND of up to 4 words: 50% .. 6% bits
    std::uint64_t points = rng();
    for (int i = 0; i < density; ++i) points &= rng();
    item = {points | (std::uint64_t(1) << (rng() % 64)), value(rng)};
  }
  return items;
}

TEST(KringSums, ScalarAddsEachItemToItsPoints) {
  const std::vector<RingItem> items = {{0b101, 2.0f}, {0b110, -1.0f}};
  double sum[64] = {}, weight[64] = {};
  add_ring_scalar(items.data(), items.size(), 0.5, sum, weight);
  EXPECT_EQ(sum[0], 1.0);
  EXPECT_EQ(sum[1], -0.5);
  EXPECT_EQ(sum[2], 0.5);
  EXPECT_EQ(weight[2], 1.0);
  EXPECT_EQ(weight[3], 0.0);
}

TEST(KringSums, Avx512AgreesBitForBit) {
  if (!add_ring_avx512_supported()) GTEST_SKIP() << "no AVX-512 on this CPU";
  double sum_a[64], weight_a[64], sum_b[64], weight_b[64];
  for (int b = 0; b < 64; ++b) sum_a[b] = sum_b[b] = weight_a[b] = weight_b[b] = 0.1 * b;
  const double ring_weights[] = {0.8824969, 0.6065307, 0.3246525, 0.1353353};
  for (int r = 0; r < 4; ++r) {
    const std::vector<RingItem> items = random_items(500, 11 + r);
    add_ring_scalar(items.data(), items.size(), ring_weights[r], sum_a, weight_a);
    add_ring_avx512(items.data(), items.size(), ring_weights[r], sum_b, weight_b);
  }
  for (int b = 0; b < 64; ++b) {
    EXPECT_EQ(sum_a[b], sum_b[b]) << b;
    EXPECT_EQ(weight_a[b], weight_b[b]) << b;
  }
}

}  // namespace
}  // namespace sdf
