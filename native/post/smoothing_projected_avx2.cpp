// SPDX-License-Identifier: GPL-3.0-or-later
// AVX2 is enabled per function (SDF_AVX2), not for the file, as in bvh8_traverse_avx2.cpp.
// No fused multiply-add anywhere (-ffp-contract=off, and no FMA intrinsic): every lane rounds
// as kern::sdf_gather_sphere does. The scalar code's comparisons are mirrored with their NaN
// behaviour (a > b false on NaN: _CMP_GT_OQ; its negation: _CMP_NGT_UQ), and its
// sdf_min/sdf_max (a < b ? a : b) are exactly _mm256_min_ps/_mm256_max_ps.
#include "post/smoothing_projected_avx2.h"

#include "util/cpu_features.h"
#include "util/test_overrides.h"

#if SDF_X86_SIMD
#include <immintrin.h>

#define SDF_AVX2 __attribute__((target("avx2")))

namespace sdf {

namespace {

// Lane masks as vectors, from the 8 bits a stack entry keeps.
SDF_AVX2 inline __m256 mask_of(unsigned bits) {
  const __m256i lane_bits = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
  const __m256i set = _mm256_and_si256(_mm256_set1_epi32(static_cast<int>(bits)), lane_bits);
  return _mm256_castsi256_ps(_mm256_cmpeq_epi32(set, lane_bits));
}

// Lanes 0-3 / 4-7 of a float mask as a double mask.
SDF_AVX2 inline __m256d low_half(__m256 mask) {
  return _mm256_castsi256_pd(_mm256_cvtepi32_epi64(_mm_castps_si128(_mm256_castps256_ps128(mask))));
}
SDF_AVX2 inline __m256d high_half(__m256 mask) {
  return _mm256_castsi256_pd(
      _mm256_cvtepi32_epi64(_mm_castps_si128(_mm256_extractf128_ps(mask, 1))));
}

// kern::sdf_cube_fraction_in_sphere per lane: every branch computed, the scalar code's choice
// blended in (lanes of a branch not taken may hold inf or NaN; they are never selected).
SDF_AVX2 inline __m256 cube_fraction(__m256 side, __m256 d, __m256 r) {
  const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.0f);
  const __m256 sign = _mm256_set1_ps(-0.0f);
  const __m256 rho = _mm256_mul_ps(_mm256_set1_ps(0.62035049f), side);
  const __m256 r_plus = _mm256_add_ps(r, rho), r_minus = _mm256_sub_ps(r, rho);
  const __m256 none =
      _mm256_or_ps(_mm256_cmp_ps(r, zero, _CMP_NGT_UQ), _mm256_cmp_ps(d, r_plus, _CMP_GE_OQ));
  const __m256 ball = _mm256_mul_ps(_mm256_mul_ps(rho, rho), rho);
  const __m256 nested = _mm256_cmp_ps(d, _mm256_andnot_ps(sign, r_minus), _CMP_LE_OQ);
  const __m256 r3 = _mm256_mul_ps(_mm256_mul_ps(r, r), r);
  const __m256 nested_value = _mm256_blendv_ps(_mm256_min_ps(one, _mm256_div_ps(r3, ball)), one,
                                               _mm256_cmp_ps(r, rho, _CMP_GE_OQ));
  const __m256 s = _mm256_sub_ps(r_plus, d);
  const __m256 inner =
      _mm256_sub_ps(_mm256_add_ps(_mm256_mul_ps(d, d),
                                  _mm256_mul_ps(_mm256_mul_ps(_mm256_set1_ps(2.0f), d), r_plus)),
                    _mm256_mul_ps(_mm256_mul_ps(_mm256_set1_ps(3.0f), r_minus), r_minus));
  const __m256 lens = _mm256_div_ps(_mm256_mul_ps(_mm256_mul_ps(s, s), inner),
                                    _mm256_mul_ps(_mm256_set1_ps(16.0f), d));
  const __m256 lens_value = _mm256_min_ps(one, _mm256_max_ps(zero, _mm256_div_ps(lens, ball)));
  return _mm256_blendv_ps(_mm256_blendv_ps(lens_value, nested_value, nested), zero, none);
}

}  // namespace

bool projected_avx2_supported() {
  // Tests act out a CPU without AVX2 (as for the 8-wide tree, bvh8_supported) to run the
  // scalar gather on the machines they have.
  if (test_overrides().cpu_without_avx2) return false;
  return cpu_features().avx2;
}

SDF_AVX2 void smooth_packet_avx2(const PointOctreeNode* nodes, const glm::vec4* points,
                                 const std::uint32_t* index, int lanes, float radius_scale,
                                 float lo, float hi, float* out) {
  alignas(32) float px[8], py[8], pz[8], pr[8], pv[8];
  for (int l = 0; l < 8; ++l) {
    const glm::vec4 p = points[index[l < lanes ? l : 0]];  // idle lanes copy lane 0, unused
    px[l] = p.x;
    py[l] = p.y;
    pz[l] = p.z;
    pv[l] = p.w;
    pr[l] = radius_scale * p.w;  // as the scalar kernel rounds it
  }
  const __m256 x = _mm256_load_ps(px), y = _mm256_load_ps(py), z = _mm256_load_ps(pz);
  const __m256 r = _mm256_load_ps(pr), r2 = _mm256_mul_ps(r, r);
  const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.0f);
  const __m256 sign = _mm256_set1_ps(-0.0f), sqrt3 = _mm256_set1_ps(1.7320508f);
  __m256d sum_lo = _mm256_setzero_pd(), sum_hi = _mm256_setzero_pd();
  __m256d weight_lo = _mm256_setzero_pd(), weight_hi = _mm256_setzero_pd();

  struct Entry {
    std::uint32_t node;
    std::uint32_t lanes;  // bit l: lane l visits the node
  };
  Entry stack[SDF_POINT_STACK];
  int top = 0;
  stack[top++] = {0, (1u << lanes) - 1u};
  while (top > 0) {
    const Entry e = stack[--top];
    const PointOctreeNode& node = nodes[e.node];
    const __m256 h = _mm256_set1_ps(node.half_side);
    const __m256 ox = _mm256_sub_ps(x, _mm256_set1_ps(node.center[0]));
    const __m256 oy = _mm256_sub_ps(y, _mm256_set1_ps(node.center[1]));
    const __m256 oz = _mm256_sub_ps(z, _mm256_set1_ps(node.center[2]));
    // Distance from each sphere's centre to the cube: lanes where it exceeds the radius skip.
    const __m256 ux = _mm256_max_ps(_mm256_sub_ps(_mm256_andnot_ps(sign, ox), h), zero);
    const __m256 uy = _mm256_max_ps(_mm256_sub_ps(_mm256_andnot_ps(sign, oy), h), zero);
    const __m256 uz = _mm256_max_ps(_mm256_sub_ps(_mm256_andnot_ps(sign, oz), h), zero);
    const __m256 out2 = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(ux, ux), _mm256_mul_ps(uy, uy)),
                                      _mm256_mul_ps(uz, uz));
    const __m256 near = _mm256_and_ps(mask_of(e.lanes), _mm256_cmp_ps(out2, r2, _CMP_NGT_UQ));
    const unsigned near_bits = static_cast<unsigned>(_mm256_movemask_ps(near));
    if (!near_bits) continue;
    const __m256 d = _mm256_sqrt_ps(_mm256_add_ps(
        _mm256_add_ps(_mm256_mul_ps(ox, ox), _mm256_mul_ps(oy, oy)), _mm256_mul_ps(oz, oz)));
    const __m256 whole = _mm256_and_ps(
        near, _mm256_cmp_ps(_mm256_add_ps(d, _mm256_mul_ps(sqrt3, h)), r, _CMP_LE_OQ));
    const unsigned whole_bits = static_cast<unsigned>(_mm256_movemask_ps(whole));
    __m256 fraction = one, take = whole;
    if (node.first_child >= 0) {
      const unsigned open = near_bits & ~whole_bits;
      if (open)  // pushed first to last: popped last to first, as the scalar walk
        for (std::uint32_t c = 0; c < node.child_count; ++c)
          stack[top++] = {static_cast<std::uint32_t>(node.first_child) + c, open};
      if (!whole_bits) continue;
    } else {
      const __m256 f = cube_fraction(_mm256_mul_ps(_mm256_set1_ps(2.0f), h), d, r);
      const __m256 cut = _mm256_andnot_ps(whole, near);
      take = _mm256_or_ps(whole, _mm256_and_ps(cut, _mm256_cmp_ps(f, zero, _CMP_GT_OQ)));
      if (!_mm256_movemask_ps(take)) continue;
      fraction = _mm256_blendv_ps(f, one, whole);
    }
    // w = count * fraction, sum += w * mean, weight += w, in double, on the taking lanes.
    const __m256d count = _mm256_set1_pd(static_cast<double>(node.count));
    const __m256d mean = _mm256_set1_pd(static_cast<double>(node.mean));
    const __m256d w_lo = _mm256_mul_pd(count, _mm256_cvtps_pd(_mm256_castps256_ps128(fraction)));
    const __m256d w_hi = _mm256_mul_pd(count, _mm256_cvtps_pd(_mm256_extractf128_ps(fraction, 1)));
    const __m256d t_lo = low_half(take), t_hi = high_half(take);
    sum_lo = _mm256_blendv_pd(sum_lo, _mm256_add_pd(sum_lo, _mm256_mul_pd(w_lo, mean)), t_lo);
    sum_hi = _mm256_blendv_pd(sum_hi, _mm256_add_pd(sum_hi, _mm256_mul_pd(w_hi, mean)), t_hi);
    weight_lo = _mm256_blendv_pd(weight_lo, _mm256_add_pd(weight_lo, w_lo), t_lo);
    weight_hi = _mm256_blendv_pd(weight_hi, _mm256_add_pd(weight_hi, w_hi), t_hi);
  }
  // mean = (float)(sum / weight), clamped to [lo, hi]; the point's own value where it gathered
  // nothing (weight not > 0).
  const __m256 mean = _mm256_set_m128(_mm256_cvtpd_ps(_mm256_div_pd(sum_hi, weight_hi)),
                                      _mm256_cvtpd_ps(_mm256_div_pd(sum_lo, weight_lo)));
  const __m256 clamped = _mm256_min_ps(_mm256_set1_ps(hi), _mm256_max_ps(_mm256_set1_ps(lo), mean));
  const __m256d zero_d = _mm256_setzero_pd();
  const unsigned gathered_bits =
      static_cast<unsigned>(_mm256_movemask_pd(_mm256_cmp_pd(weight_lo, zero_d, _CMP_GT_OQ))) |
      static_cast<unsigned>(_mm256_movemask_pd(_mm256_cmp_pd(weight_hi, zero_d, _CMP_GT_OQ))) << 4;
  const __m256 gathered = mask_of(gathered_bits);
  alignas(32) float result[8];
  _mm256_store_ps(result, _mm256_blendv_ps(_mm256_load_ps(pv), clamped, gathered));
  for (int l = 0; l < lanes; ++l) out[index[l]] = result[l];
}

}  // namespace sdf

#else

namespace sdf {

bool projected_avx2_supported() { return false; }

void smooth_packet_avx2(const PointOctreeNode*, const glm::vec4*, const std::uint32_t*, int, float,
                        float, float, float*) {}

}  // namespace sdf

#endif
