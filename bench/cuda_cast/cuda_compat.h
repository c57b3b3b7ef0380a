/* SPDX-License-Identifier: GPL-3.0-or-later */
/* Benchmark tool, never part of the product: kernels/sdf_compat.h's vocabulary for CUDA, so that
 * the shared kernel headers (kernels/sdf_bvh_traverse.h, sdf_reduce.h, ...) compile unchanged
 * as CUDA device code, for profiling with Nsight Compute (which does not see OpenCL kernels).
 * Include this before any kernel header: it takes sdf_compat.h's include guard, so that header
 * is skipped. Build with nvcc --fmad=false (and the default IEEE division and square root), the
 * CUDA counterpart of FP_CONTRACT OFF and -cl-fp32-correctly-rounded-divide-sqrt, so a ray
 * computes to the same bits as on the CPU engine. */
#ifndef SDF_COMPAT_H
#define SDF_COMPAT_H

#include <cmath>
#include <cstdint>
#include <cuda_runtime.h>

#define SDF_KERNEL_BEGIN
#define SDF_KERNEL_END
#define SDF_INLINE static __device__ __forceinline__
#define SDF_GLOBAL
#define SDF_STATIC_ASSERT(cond, msg) static_assert(cond, msg)
typedef int sdf_int32;
typedef unsigned int sdf_uint32;
typedef double sdf_wide;

/* OpenCL's float3 arithmetic, component by component in the same order. */
static __device__ __forceinline__ float3 operator+(float3 a, float3 b) {
  return make_float3(a.x + b.x, a.y + b.y, a.z + b.z);
}
static __device__ __forceinline__ float3 operator-(float3 a, float3 b) {
  return make_float3(a.x - b.x, a.y - b.y, a.z - b.z);
}
static __device__ __forceinline__ float3 operator*(float s, float3 a) {
  return make_float3(s * a.x, s * a.y, s * a.z);
}
static __device__ __forceinline__ float3 operator*(float3 a, float s) {
  return make_float3(a.x * s, a.y * s, a.z * s);
}
/* 16-byte loads through the read-only cache (the OpenCL kernels' arguments are const
 * restrict, which gives NVIDIA's OpenCL compiler the same LDG.E.128.CONSTANT). */
typedef float4 sdf_float4;
typedef int4 sdf_int4;
typedef int2 sdf_int2;
#define sdf_load4(p, i) __ldg((p) + (i))
#define sdf_make_int4(a, b, c, d) make_int4((a), (b), (c), (d))
#define sdf_make_int2(a, b) make_int2((a), (b))
#define sdf_as_int(x) __float_as_int(x)
#define sdf_as_float(x) __int_as_float(x)
#define sdf_min(a, b) fminf((a), (b))
#define sdf_max(a, b) fmaxf((a), (b))

SDF_INLINE float sdf_dot(float3 a, float3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
SDF_INLINE float3 sdf_cross(float3 a, float3 b) {
  return make_float3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
SDF_INLINE float3 sdf_normalize(float3 v) {
  float inv = 1.0f / sqrtf(sdf_dot(v, v));
  return make_float3(v.x * inv, v.y * inv, v.z * inv);
}

#endif /* SDF_COMPAT_H */
