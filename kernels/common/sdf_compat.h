/* SPDX-License-Identifier: GPL-3.0-or-later */
/* The vocabulary shared by the C++ core and the OpenCL kernels (Cycles' compat.h idea).
 * Kernel headers write only these names, so the same source compiles as C++ (the CPU engine,
 * with GLM vectors) and as OpenCL C 1.2 (the OpenCL engine). Rules for shared code: no
 * templates, no references, no namespaces inside; wrap declarations in SDF_KERNEL_BEGIN/END. */
#ifndef SDF_COMPAT_H
#define SDF_COMPAT_H

#ifdef __OPENCL_VERSION__

/* The same arithmetic as the host: no fused multiply-adds (the C++ core is built with
 * -ffp-contract=off), so a ray computes to the same bits on every device. With correctly rounded
 * division and square root (a build option) and the vector helpers below written out,
 * OpenCL results equal the CPU engine's except where a device's sin/cos enter (random
 * sampling). */
#pragma OPENCL FP_CONTRACT OFF

#define SDF_KERNEL_BEGIN
#define SDF_KERNEL_END
#define SDF_INLINE static inline
#define SDF_GLOBAL __global
#define SDF_STATIC_ASSERT(cond, msg)
typedef int sdf_int32;
typedef uint sdf_uint32;
typedef long sdf_int64;
typedef ulong sdf_uint64;
#define make_float3(x, y, z) ((float3)((x), (y), (z)))
#define sdf_vmin(a, b) fmin((a), (b))
#define sdf_vmax(a, b) fmax((a), (b))
#define sdf_min(a, b) fmin((a), (b))
#define sdf_max(a, b) fmax((a), (b))
/* Element i of an array of 16-byte units (BVH nodes and triangles, see sdf_bvh_traverse.h): one
 * 16-byte load where the array is typed float4 from the kernel argument on (NVIDIA's compiler
 * split a float4 load through a cast float pointer into four), and reinterpretations between
 * int and float bits. */
typedef float4 sdf_float4;
#define sdf_load4(p, i) ((p)[i])
typedef int4 sdf_int4;
#define sdf_make_int4(a, b, c, d) ((int4)((a), (b), (c), (d)))
typedef int2 sdf_int2;
#define sdf_make_int2(a, b) ((int2)((a), (b)))
#define sdf_as_int(x) as_int(x)
#define sdf_as_float(x) as_float(x)
/* Wide accumulators (sums over many terms): double where the device has it, as on the host. */
#ifdef cl_khr_fp64
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
typedef double sdf_wide;
/* Code that must compute in double to give the host's bits (texture rasterisation) exists
 * only where this is defined; the host always has it. */
#define SDF_HAVE_DOUBLE 1
#else
typedef float sdf_wide;
#endif

#else /* C++ */

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>

// Also defined for every target by CMake (sdf_core's public definitions): a file that includes
// GLM before this header must see the same vector types, or the two disagree on glm::vec3.
#ifndef GLM_FORCE_XYZW_ONLY
#define GLM_FORCE_XYZW_ONLY
#endif
#include <glm/glm.hpp>

#define SDF_KERNEL_BEGIN \
  namespace sdf {        \
  namespace kern {
#define SDF_KERNEL_END \
  }                    \
  }
#define SDF_INLINE inline
#define SDF_GLOBAL
#define SDF_STATIC_ASSERT(cond, msg) static_assert(cond, msg)

namespace sdf {
namespace kern {
typedef glm::vec3 float3;
typedef std::int32_t sdf_int32;
typedef std::uint32_t sdf_uint32;
typedef std::int64_t sdf_int64;
typedef std::uint64_t sdf_uint64;
typedef double sdf_wide;
#define SDF_HAVE_DOUBLE 1
inline float3 make_float3(float x, float y, float z) { return float3(x, y, z); }
inline float3 sdf_vmin(float3 a, float3 b) { return glm::min(a, b); }
inline float3 sdf_vmax(float3 a, float3 b) { return glm::max(a, b); }
// Plain compares, not std::fmin: without -ffast-math, fmin is a library call (NaN rules), and
// the box test runs these a dozen times per node. NaN-free inputs give the same result.
inline float sdf_min(float a, float b) { return a < b ? a : b; }
inline float sdf_max(float a, float b) { return a > b ? a : b; }
typedef glm::vec4 sdf_float4;
inline sdf_float4 sdf_load4(const sdf_float4* p, std::ptrdiff_t i) {
  sdf_float4 v;
  std::memcpy(&v, reinterpret_cast<const char*>(p) + 16 * i, sizeof v);
  return v;
}
typedef glm::ivec2 sdf_int2;
inline sdf_int2 sdf_make_int2(sdf_int32 a, sdf_int32 b) { return sdf_int2(a, b); }
typedef glm::ivec4 sdf_int4;
inline sdf_int4 sdf_make_int4(sdf_int32 a, sdf_int32 b, sdf_int32 c, sdf_int32 d) {
  return sdf_int4(a, b, c, d);
}
inline sdf_int32 sdf_as_int(float x) {
  sdf_int32 i;
  std::memcpy(&i, &x, sizeof i);
  return i;
}
inline float sdf_as_float(sdf_int32 i) {
  float x;
  std::memcpy(&x, &i, sizeof x);
  return x;
}
using std::acos;
using std::asin;
using std::atan2;
using std::ceil;
using std::copysign;
using std::cos;
using std::exp;
using std::fabs;
using std::floor;
using std::fma;
using std::fmax;
using std::fmin;
using std::isfinite;
using std::ldexp;
using std::sin;
using std::sqrt;
}  // namespace kern
}  // namespace sdf

#endif

SDF_KERNEL_BEGIN

/* Vector helpers written out term by term, in one order, instead of the built-ins: OpenCL's
 * dot, cross and normalize may fuse or approximate differently on each device. */
SDF_INLINE float sdf_dot(float3 a, float3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
SDF_INLINE float3 sdf_cross(float3 a, float3 b) {
  return make_float3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
SDF_INLINE float3 sdf_normalize(float3 v) {
  float inv = 1.0f / sqrt(sdf_dot(v, v));
  return make_float3(v.x * inv, v.y * inv, v.z * inv);
}

/* Floats as ints that compare in the same order (negatives' magnitude bits flipped), for
 * atomic minima and maxima on the device and reading them back on the host; the mapping is
 * its own inverse. */
SDF_INLINE sdf_int32 sdf_ordered_int(float x) {
  sdf_int32 i = sdf_as_int(x);
  return i >= 0 ? i : i ^ 0x7fffffff;
}
SDF_INLINE float sdf_ordered_float(sdf_int32 i) {
  return sdf_as_float(i >= 0 ? i : i ^ 0x7fffffff);
}

SDF_KERNEL_END

#endif /* SDF_COMPAT_H */
