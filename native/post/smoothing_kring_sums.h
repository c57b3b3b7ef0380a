// SPDX-License-Identifier: GPL-3.0-or-later
// The k-ring walk's inner sum (smoothing_kring.cpp): the items a ring adds to a batch of up
// to 64 points, each item with the mask of the points whose ring holds it, go into every
// such point's weighted sum and weight. About 250 (point, item) pairs per point at k = 6,
// so this loop was half of the walk; the AVX-512 version keeps the 64 sums in registers and
// adds an item to all its points with 8 masked adds, whatever their number.
#pragma once

#include <cstddef>
#include <cstdint>

namespace sdf {

// One item of a ring: bit b of `points` set when batch point b gains it in this ring.
struct RingItem {
  std::uint64_t points;
  float value;
};

// One item: sum[b] += w * value and weight[b] += w for each bit b of its mask.
inline void add_item(const RingItem& item, double w, double* sum, double* weight) {
  const double wx = w * static_cast<double>(item.value);
  for (std::uint64_t bits = item.points; bits; bits &= bits - 1) {
    const int b = __builtin_ctzll(bits);
    sum[b] += wx;
    weight[b] += w;
  }
}

// add_item on each item in order; sum and weight hold 64 entries (the AVX-512 version reads
// and writes all of them, whatever the batch's size). Both versions make the same additions in the
// same order on every point, so they agree bit for bit. add_ring_avx512 only where
// add_ring_avx512_supported().
void add_ring_scalar(const RingItem* items, std::size_t count, double w, double* sum,
                     double* weight);
bool add_ring_avx512_supported();
void add_ring_avx512(const RingItem* items, std::size_t count, double w, double* sum,
                     double* weight);

}  // namespace sdf
