// SPDX-License-Identifier: GPL-3.0-or-later
// Four floats handled at once, for the BVH builder's inner loops (binning, bounds): SSE2 where
// the compiler offers it (every x86-64), plain loops elsewhere. Lane 3 is along for the ride
// and never read back. Both paths do the same IEEE single-precision operations, so bins and
// splits come out the same on any machine.
#pragma once

#include <algorithm>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace sdf::bvh_build {

#if defined(__SSE2__)
struct Float4 {
  __m128 v;
  // Reads p[0..3]: callers point into a 16-byte group (a PrimRef's lo + id, or hi + pad).
  static Float4 load(const float* p) { return {_mm_loadu_ps(p)}; }
  static Float4 splat(float x) { return {_mm_set1_ps(x)}; }
  static Float4 set(float x, float y, float z) { return {_mm_setr_ps(x, y, z, 0.0f)}; }
  float operator[](int i) const {
    alignas(16) float f[4];
    _mm_store_ps(f, v);
    return f[i];
  }
  friend Float4 operator+(Float4 a, Float4 b) { return {_mm_add_ps(a.v, b.v)}; }
  friend Float4 operator-(Float4 a, Float4 b) { return {_mm_sub_ps(a.v, b.v)}; }
  friend Float4 operator*(Float4 a, Float4 b) { return {_mm_mul_ps(a.v, b.v)}; }
  friend Float4 min(Float4 a, Float4 b) { return {_mm_min_ps(a.v, b.v)}; }
  friend Float4 max(Float4 a, Float4 b) { return {_mm_max_ps(a.v, b.v)}; }
  // Truncates toward zero into out[0..3] (values are clamped to a small range first).
  void truncate(int* out) const {
    _mm_storeu_si128(reinterpret_cast<__m128i*>(out), _mm_cvttps_epi32(v));
  }
  float x() const { return _mm_cvtss_f32(v); }
  Float4 yzx() const { return {_mm_shuffle_ps(v, v, _MM_SHUFFLE(3, 0, 2, 1))}; }
  // (x + y) + z, in that order.
  float sum3() const {
    const __m128 y = _mm_shuffle_ps(v, v, _MM_SHUFFLE(1, 1, 1, 1));
    const __m128 z = _mm_shuffle_ps(v, v, _MM_SHUFFLE(2, 2, 2, 2));
    return _mm_cvtss_f32(_mm_add_ss(_mm_add_ss(v, y), z));
  }
};
#else
struct Float4 {
  float f[4];
  // Reads p[0..2] only: lane 3 would be the PrimRef's id or pad, an integer read as a float
  // (and past the vec3 it points into); the SSE path carries those bits but never uses them.
  static Float4 load(const float* p) { return {{p[0], p[1], p[2], 0.0f}}; }
  static Float4 splat(float x) { return {{x, x, x, x}}; }
  static Float4 set(float x, float y, float z) { return {{x, y, z, 0.0f}}; }
  float operator[](int i) const { return f[i]; }
  template <typename Op>
  static Float4 each(Float4 a, Float4 b, Op op) {
    return {{op(a.f[0], b.f[0]), op(a.f[1], b.f[1]), op(a.f[2], b.f[2]), op(a.f[3], b.f[3])}};
  }
  friend Float4 operator+(Float4 a, Float4 b) {
    return each(a, b, [](float x, float y) { return x + y; });
  }
  friend Float4 operator-(Float4 a, Float4 b) {
    return each(a, b, [](float x, float y) { return x - y; });
  }
  friend Float4 operator*(Float4 a, Float4 b) {
    return each(a, b, [](float x, float y) { return x * y; });
  }
  // Same operand order as minps/maxps: the second operand when either is NaN.
  friend Float4 min(Float4 a, Float4 b) {
    return each(a, b, [](float x, float y) { return x < y ? x : y; });
  }
  friend Float4 max(Float4 a, Float4 b) {
    return each(a, b, [](float x, float y) { return x > y ? x : y; });
  }
  void truncate(int* out) const {
    for (int i = 0; i < 4; ++i) out[i] = static_cast<int>(f[i]);
  }
  float x() const { return f[0]; }
  Float4 yzx() const { return {{f[1], f[2], f[0], f[3]}}; }
  float sum3() const { return (f[0] + f[1]) + f[2]; }
};
#endif

}  // namespace sdf::bvh_build
