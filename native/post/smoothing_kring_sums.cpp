// SPDX-License-Identifier: GPL-3.0-or-later
// AVX-512 is enabled for one function by attribute (as bvh8_traverse_avx2.cpp does for AVX2),
// and picked at run time.
#include "post/smoothing_kring_sums.h"

#include "util/cpu_features.h"

#if SDF_X86_SIMD
#include <immintrin.h>
#endif

namespace sdf {

void add_ring_scalar(const RingItem* items, std::size_t count, double w, double* sum,
                     double* weight) {
  for (std::size_t i = 0; i < count; ++i) add_item(items[i], w, sum, weight);
}

#if SDF_X86_SIMD

bool add_ring_avx512_supported() { return cpu_features().avx512f; }

// 64 sums and 64 weights in 16 registers of 8 doubles; an item's mask, 8 bits at a time,
// selects the lanes of each register that add (w x, w). Masked-off lanes keep their value,
// so each lane sees exactly the scalar loop's additions.
// Clang 18 and later split the 512-bit registers off AVX-512 (evex512), and refuse 512-bit
// vectors in a function enabled for avx512f alone; GCC before 14 knows no such feature.
#if defined(__clang__) && __clang_major__ >= 18
#define SDF_TARGET_AVX512F "avx512f,evex512"
#else
#define SDF_TARGET_AVX512F "avx512f"
#endif
__attribute__((target(SDF_TARGET_AVX512F))) void add_ring_avx512(const RingItem* items,
                                                                 std::size_t count, double w,
                                                                 double* sum, double* weight) {
  __m512d s[8], t[8];
  for (int j = 0; j < 8; ++j) {
    s[j] = _mm512_loadu_pd(sum + 8 * j);
    t[j] = _mm512_loadu_pd(weight + 8 * j);
  }
  const __m512d ww = _mm512_set1_pd(w);
  for (std::size_t i = 0; i < count; ++i) {
    const __m512d wx = _mm512_set1_pd(w * static_cast<double>(items[i].value));
    const std::uint64_t bits = items[i].points;
    for (int j = 0; j < 8; ++j) {
      const __mmask8 lanes = static_cast<__mmask8>(bits >> (8 * j));
      s[j] = _mm512_mask_add_pd(s[j], lanes, s[j], wx);
      t[j] = _mm512_mask_add_pd(t[j], lanes, t[j], ww);
    }
  }
  for (int j = 0; j < 8; ++j) {
    _mm512_storeu_pd(sum + 8 * j, s[j]);
    _mm512_storeu_pd(weight + 8 * j, t[j]);
  }
}

#else

bool add_ring_avx512_supported() { return false; }

void add_ring_avx512(const RingItem* items, std::size_t count, double w, double* sum,
                     double* weight) {
  add_ring_scalar(items, count, w, sum, weight);
}

#endif

}  // namespace sdf
