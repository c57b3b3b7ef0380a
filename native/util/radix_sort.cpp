// SPDX-License-Identifier: GPL-3.0-or-later
#include "util/radix_sort.h"

#include <algorithm>

#include "util/parallel.h"

namespace sdf {

namespace {

// 11-bit digits: a 30-bit Morton code sorts in 3 passes, and 2048 counters per block stay in
// L1. Blocks of at least 64k items: below that, the per-block histograms cost more than the
// parallelism gives.
constexpr int kMaxDigitBits = 11;
constexpr std::size_t kMinItemsPerBlock = 1 << 16;

}  // namespace

void radix_sort_by_bits(UninitializedVector<std::uint64_t>& items, int low_bit, int key_bits,
                        unsigned threads) {
  const std::size_t n = items.size();
  if (n < 2 || key_bits <= 0) return;
  const int passes = (key_bits + kMaxDigitBits - 1) / kMaxDigitBits;
  const int digit_bits = (key_bits + passes - 1) / passes;
  const std::size_t buckets = std::size_t{1} << digit_bits;
  const std::size_t blocks = std::max<std::size_t>(
      1, std::min<std::size_t>(resolve_threads(threads), n / kMinItemsPerBlock));
  auto block_begin = [&](std::size_t b) { return n * b / blocks; };

  UninitializedVector<std::uint64_t> scratch(n);
  // counts[b * buckets + d]: items of block b with digit d; then where block b writes them.
  std::vector<std::size_t> counts(blocks * buckets);
  for (int pass = 0; pass < passes; ++pass) {
    const int shift = low_bit + pass * digit_bits;
    const int width = std::min(digit_bits, low_bit + key_bits - shift);
    const std::uint64_t mask = (std::uint64_t{1} << width) - 1;
    parallel_for(blocks, 1, threads, [&](std::size_t b0, std::size_t b1) {
      for (std::size_t b = b0; b < b1; ++b) {
        std::size_t* count = &counts[b * buckets];
        std::fill(count, count + buckets, 0);
        for (std::size_t i = block_begin(b); i < block_begin(b + 1); ++i)
          ++count[(items[i] >> shift) & mask];
      }
    });
    // Bucket-major, block-minor offsets keep equal digits in input order (stability).
    std::size_t total = 0;
    bool one_bucket = false;
    for (std::size_t d = 0; d < buckets; ++d) {
      std::size_t in_bucket = 0;
      for (std::size_t b = 0; b < blocks; ++b) {
        const std::size_t c = counts[b * buckets + d];
        counts[b * buckets + d] = total;
        total += c;
        in_bucket += c;
      }
      one_bucket |= in_bucket == n;
    }
    if (one_bucket) continue;  // every item has the same digit: this pass would copy only
    parallel_for(blocks, 1, threads, [&](std::size_t b0, std::size_t b1) {
      for (std::size_t b = b0; b < b1; ++b) {
        std::size_t* next = &counts[b * buckets];
        for (std::size_t i = block_begin(b); i < block_begin(b + 1); ++i)
          scratch[next[(items[i] >> shift) & mask]++] = items[i];
      }
    });
    items.swap(scratch);
  }
}

}  // namespace sdf
