// SPDX-License-Identifier: GPL-3.0-or-later
// Prefix sums and run starts on parallel_for, for the setup of the k-ring smoothing and the
// weld (offsets of compressed lists): a serial pass over a million counts was one of the
// stages that took as long on 16 cores as on one.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "util/parallel.h"

namespace sdf {

// Items per block of the scans: enough work per block to be worth a thread.
constexpr std::size_t kScanBlock = std::size_t(1) << 16;

// In place, a[i] becomes a[0] + ... + a[i] (integers: the same sums in any order). Sums per
// block, then each block's prefix from the sum of the blocks before it.
template <class T>
void inclusive_scan(T* a, std::size_t n, unsigned threads) {
  const std::size_t blocks = (n + kScanBlock - 1) / kScanBlock;
  std::vector<T> base(blocks + 1, T(0));
  parallel_for(blocks, 1, threads, [&](std::size_t b0, std::size_t b1) {
    for (std::size_t b = b0; b < b1; ++b) {
      T sum(0);
      for (std::size_t i = b * kScanBlock; i < std::min(n, (b + 1) * kScanBlock); ++i) sum += a[i];
      base[b + 1] = sum;
    }
  });
  for (std::size_t b = 0; b < blocks; ++b) base[b + 1] += base[b];
  parallel_for(blocks, 1, threads, [&](std::size_t b0, std::size_t b1) {
    for (std::size_t b = b0; b < b1; ++b) {
      T sum = base[b];
      for (std::size_t i = b * kScanBlock; i < std::min(n, (b + 1) * kScanBlock); ++i)
        a[i] = sum += a[i];
    }
  });
}

// For items sorted by a key in [0, keys): start[k] = the first item whose key is >= k, for
// k in [0, keys] (start[keys] = n), so the items of key k are [start[k], start[k + 1]).
// Each entry is written by the one item after the gap it closes, so blocks run in parallel.
template <class KeyOf>
void run_starts(std::size_t n, std::size_t keys, unsigned threads, KeyOf&& key_of,
                std::uint32_t* start) {
  if (n == 0) {
    std::fill(start, start + keys + 1, 0u);
    return;
  }
  parallel_for(n, kScanBlock, threads, [&](std::size_t begin, std::size_t end) {
    std::size_t previous = begin == 0 ? 0 : key_of(begin - 1) + 1;
    for (std::size_t i = begin; i < end; ++i) {
      const std::size_t key = key_of(i);
      for (std::size_t k = previous; k <= key; ++k) start[k] = static_cast<std::uint32_t>(i);
      previous = key + 1;
    }
    if (end == n)
      for (std::size_t k = previous; k <= keys; ++k) start[k] = static_cast<std::uint32_t>(n);
  });
}

// The indices i in [0, n) for which keep(i) holds, increasing. Blocks count theirs, then
// write them after the blocks before them (keep is called twice per index: keep it cheap).
template <class Keep>
std::vector<std::uint32_t> indices_where(std::size_t n, unsigned threads, Keep&& keep) {
  const std::size_t blocks = (n + kScanBlock - 1) / kScanBlock;
  std::vector<std::uint32_t> first(blocks + 1, 0u);
  parallel_for(blocks, 1, threads, [&](std::size_t b0, std::size_t b1) {
    for (std::size_t b = b0; b < b1; ++b) {
      std::uint32_t kept = 0;
      for (std::size_t i = b * kScanBlock; i < std::min(n, (b + 1) * kScanBlock); ++i)
        kept += keep(i);
      first[b + 1] = kept;
    }
  });
  for (std::size_t b = 0; b < blocks; ++b) first[b + 1] += first[b];
  std::vector<std::uint32_t> out(first[blocks]);
  parallel_for(blocks, 1, threads, [&](std::size_t b0, std::size_t b1) {
    for (std::size_t b = b0; b < b1; ++b) {
      std::uint32_t at = first[b];
      for (std::size_t i = b * kScanBlock; i < std::min(n, (b + 1) * kScanBlock); ++i)
        if (keep(i)) out[at++] = static_cast<std::uint32_t>(i);
    }
  });
  return out;
}

}  // namespace sdf
