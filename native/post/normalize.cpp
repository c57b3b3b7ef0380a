// SPDX-License-Identifier: GPL-3.0-or-later
#include "post/normalize.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>

#include "util/parallel.h"

namespace sdf {

namespace {

// Shapira et al.'s log normalisation log(a x + 1) / log(a + 1), with their a = 4.
constexpr double kLogStrength = 4.0;
// A million values take about a millisecond a pass on one core: chunks this size keep the
// thread hand-out negligible.
constexpr std::size_t kGrain = 1 << 16;

}  // namespace

template <class T>
void normalize(const T* values, std::size_t n, Normalization method, unsigned threads, float* out) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  bool nan = false;
  std::mutex merge;
  parallel_for(n, kGrain, threads, [&](std::size_t begin, std::size_t end) {
    double l = std::numeric_limits<double>::infinity(), h = -l;
    bool has_nan = false;
    for (std::size_t i = begin; i < end; ++i) {
      const double x = static_cast<double>(values[i]);
      has_nan |= std::isnan(x);
      l = std::min(l, x);
      h = std::max(h, x);
    }
    std::lock_guard<std::mutex> lock(merge);
    lo = std::min(lo, l);
    hi = std::max(hi, h);
    nan |= has_nan;
  });
  if (nan || !(hi > lo)) {
    std::fill(out, out + n, 0.0f);
    return;
  }
  const double range = hi - lo, log_scale = std::log1p(kLogStrength);
  // The same operations, in the same order, as the numpy expression this replaced:
  // (v - lo) / (hi - lo), then log1p(4 x) / log1p(4), clipped to [0, 1], rounded to float.
  parallel_for(n, kGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      double x = (static_cast<double>(values[i]) - lo) / range;
      if (method == Normalization::Log) x = std::log1p(x * kLogStrength) / log_scale;
      // np.clip's order: a NaN (an infinite value over an infinite range) stays NaN.
      out[i] = static_cast<float>(x < 0.0 ? 0.0 : (x > 1.0 ? 1.0 : x));
    }
  });
}

template void normalize<float>(const float*, std::size_t, Normalization, unsigned, float*);
template void normalize<double>(const double*, std::size_t, Normalization, unsigned, float*);

}  // namespace sdf
