/* SPDX-License-Identifier: GPL-3.0-or-later */
/* Ray directions in a cone around a point's inward axis, generated where they are used
 * (paper 4.2: no stored rays or weights). A direction is built in a local frame whose z is the
 * cone axis, then rotated into world space with the point's tangent frame. */
#ifndef SDF_RAYS_H
#define SDF_RAYS_H

#include "sdf_layout.h"

SDF_KERNEL_BEGIN

/* pi * (3 - sqrt(5)): the golden angle, used by spherical Fibonacci and by CGAL's Vogel disk. */
#define SDF_GOLDEN_ANGLE 2.39996322972865332f
#define SDF_TWO_PI 6.28318530717958648f

/* Hash of Jarzynski and Olano (JCGT 2020, "pcg_hash"): cheap, good enough for ray jitter, and
 * stateless, so any ray of any point can be generated on its own on any device. */
SDF_INLINE sdf_uint32 sdf_hash(sdf_uint32 x) {
  sdf_uint32 state = x * 747796405u + 2891336453u;
  sdf_uint32 word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
  return (word >> 22u) ^ word;
}

/* A uniform float in [0, 1) for (seed, point, ray, dimension). */
SDF_INLINE float sdf_uniform(sdf_uint32 seed, sdf_uint32 point, sdf_uint32 ray, sdf_uint32 dim) {
  sdf_uint32 h = sdf_hash(seed ^ sdf_hash(point ^ sdf_hash(ray * 2u + dim)));
  return (float)(h >> 8) * (1.0f / 16777216.0f);
}

/* Direction i of n in the local frame (z = cone axis) for a cone of half-angle with the given
 * cosine and sine.
 * - Fibonacci: spherical Fibonacci points restricted to the cone's cap (paper 4.2, Keinert et
 *   al.): equal-area bands in z, golden-angle steps in azimuth. Deterministic, the same set for
 *   every point, no ray exactly on the axis.
 * - Random: uniform over the cap (uniform z, uniform azimuth), hashed from (seed, point, ray).
 * - CGAL: CGAL's Vogel disk sampler (Disk_samplers.h, not uniform: radius i/n, biased to the
 *   centre, sample 0 on the axis) mapped as cos(half) * axis + sin(half) * disk point
 *   (SDF_calculation.h), then normalised. */
SDF_INLINE float3 sdf_ray_local(int sampling, int i, int n, float cos_half, float sin_half,
                                sdf_uint32 seed, sdf_uint32 point) {
  if (sampling == SDF_SAMPLING_CGAL) {
    float radius = (float)i / (float)n;
    float q = (float)i * SDF_GOLDEN_ANGLE;
    float3 v = make_float3(sin_half * radius * cos(q), sin_half * radius * sin(q), cos_half);
    return normalize(v);
  }
  float z, phi;
  if (sampling == SDF_SAMPLING_RANDOM) {
    z = 1.0f - sdf_uniform(seed, point, (sdf_uint32)i, 0u) * (1.0f - cos_half);
    phi = SDF_TWO_PI * sdf_uniform(seed, point, (sdf_uint32)i, 1u);
  } else {
    z = 1.0f - ((float)i + 0.5f) / (float)n * (1.0f - cos_half);
    phi = (float)i * SDF_GOLDEN_ANGLE;
  }
  float r = sqrt(fmax(0.0f, (1.0f - z) * (1.0f + z)));
  return make_float3(r * cos(phi), r * sin(phi), z);
}

/* Angle between a local direction and the cone axis; atan2 stays accurate near the axis,
 * where acos(z) does not. */
SDF_INLINE float sdf_ray_angle(float3 dir_local) {
  return atan2(sqrt(dir_local.x * dir_local.x + dir_local.y * dir_local.y), dir_local.z);
}

/* The smallest angle a ray's weight uses (weight = 1 / angle, paper section 3): the angle of the
 * innermost Fibonacci ray, acos(1 - (1 - cos_half) / (2n)). Fibonacci rays never go below it;
 * a random ray nearer the axis (or CGAL's on-axis sample) weighs as that innermost ray instead
 * of infinitely. Written as 2 asin(sqrt(x / 2)) with x = 1 - cos, accurate for tiny angles. */
SDF_INLINE float sdf_angle_floor(int n, float cos_half) {
  float x = 0.5f * (1.0f - cos_half) / (float)n;
  return 2.0f * asin(sqrt(0.5f * x));
}

/* Orthonormal tangent frame (b1, b2) for a unit axis n: Duff et al., "Building an Orthonormal
 * Basis, Revisited" (JCGT 2017). Branch-free apart from the sign, continuous except at n.z = -1. */
SDF_INLINE void sdf_frame_duff(float3 n, float3* b1, float3* b2) {
  float sign = copysign(1.0f, n.z);
  float a = -1.0f / (sign + n.z);
  float b = n.x * n.y * a;
  *b1 = make_float3(1.0f + sign * n.x * n.x * a, sign * b, -sign * n.x);
  *b2 = make_float3(b, sign + n.y * n.y * a, -n.y);
}

/* CGAL's frame: Plane_3(center, n).base1() and base2() = cross(n, base1), both normalised
 * (Cartesian/function_objects.h, Construct_base_vector_3). Exact zero tests, as CGAL has. */
SDF_INLINE void sdf_frame_cgal(float3 n, float3* b1, float3* b2) {
  float3 base1;
  float a = fabs(n.x), b = fabs(n.y), c = fabs(n.z);
  if (n.x == 0.0f) {
    base1 = make_float3(1.0f, 0.0f, 0.0f);
  } else if (n.y == 0.0f) {
    base1 = make_float3(0.0f, 1.0f, 0.0f);
  } else if (n.z == 0.0f) {
    base1 = make_float3(0.0f, 0.0f, 1.0f);
  } else if (a <= b && a <= c) {
    base1 = make_float3(0.0f, -n.z, n.y);
  } else if (b <= a && b <= c) {
    base1 = make_float3(-n.z, 0.0f, n.x);
  } else {
    base1 = make_float3(-n.y, n.x, 0.0f);
  }
  *b1 = normalize(base1);
  *b2 = normalize(cross(n, base1));
}

SDF_INLINE void sdf_frame(int sampling, float3 n, float3* b1, float3* b2) {
  if (sampling == SDF_SAMPLING_CGAL) {
    sdf_frame_cgal(n, b1, b2);
  } else {
    sdf_frame_duff(n, b1, b2);
  }
}

SDF_INLINE float3 sdf_to_world(float3 dir_local, float3 b1, float3 b2, float3 n) {
  return dir_local.x * b1 + dir_local.y * b2 + dir_local.z * n;
}

SDF_KERNEL_END

#endif /* SDF_RAYS_H */
