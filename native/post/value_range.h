// SPDX-License-Identifier: GPL-3.0-or-later
// The range of a field of values and its first bad value, on parallel_for: each smoothing
// method rejects a field with a bad value (not finite; for projected smoothing also negative)
// naming the first, and keeps its results within [lo, hi].
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <vector>

#include "util/parallel.h"

namespace sdf {

struct ValueRange {
  float lo, hi;           // meaningful only without a bad value
  std::size_t first_bad;  // the lowest index i with bad(values[i]); n if none
};

// Chunks find their range and first bad value; the first chunk with one names it, so the
// error is the one a serial scan would give.
template <class Bad>
ValueRange value_range(const float* values, std::size_t n, unsigned threads, Bad&& bad) {
  constexpr std::size_t kChunk = std::size_t(1) << 15;
  constexpr float kInf = std::numeric_limits<float>::infinity();
  std::vector<ValueRange> per_chunk((n + kChunk - 1) / kChunk);
  parallel_for(n, kChunk, threads, [&](std::size_t begin, std::size_t end) {
    ValueRange r{kInf, -kInf, n};
    for (std::size_t i = begin; i < end; ++i) {
      if (bad(values[i])) {
        r.first_bad = i;
        break;
      }
      r.lo = std::min(r.lo, values[i]);
      r.hi = std::max(r.hi, values[i]);
    }
    per_chunk[begin / kChunk] = r;
  });
  ValueRange all{kInf, -kInf, n};
  for (const ValueRange& r : per_chunk) {
    if (r.first_bad < n) return r;
    all.lo = std::min(all.lo, r.lo);
    all.hi = std::max(all.hi, r.hi);
  }
  return all;
}

// A lambda, not a function: passed as a function it was called through a pointer per value
// (twice as slow as the serial loop it replaced).
inline constexpr auto not_finite = [](float x) { return !std::isfinite(x); };

}  // namespace sdf
