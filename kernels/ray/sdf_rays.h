/* SPDX-License-Identifier: GPL-3.0-or-later */
/* Ray directions in a cone around a point's inward axis, generated where they are used
 * (paper 4.2: no stored rays or weights). A direction is built in a local frame whose z is the
 * cone axis, then rotated into world space with the point's tangent frame. */
#ifndef SDF_RAYS_H
#define SDF_RAYS_H

#include "common/sdf_layout.h"

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

/* Direction i of n in the local frame (z = cone axis) for a cone whose half-angle has the
 * given 1 - cos (passed instead of the cosine: for a narrow cone, cos rounds to 1 in float and
 * every ray would collapse onto the axis) and sine.
 * - Fibonacci: spherical Fibonacci points restricted to the cone's cap (paper 4.2, Keinert et
 *   al.): equal-area bands in z, golden-angle steps in azimuth. Deterministic, the same set for
 *   every point, no ray exactly on the axis.
 * - Random: uniform over the cap (uniform z, uniform azimuth), hashed from (seed, point, ray).
 * - CGAL: CGAL's Vogel disk sampler (Disk_samplers.h, not uniform: radius i/n, biased to the
 *   centre, sample 0 on the axis) mapped as cos(half) * axis + sin(half) * disk point
 *   (SDF_calculation.h), then normalised. */
SDF_INLINE float3 sdf_ray_local(int sampling, int i, int n, float one_minus_cos_half,
                                float sin_half, sdf_uint32 seed, sdf_uint32 point) {
  if (sampling == SDF_SAMPLING_CGAL) {
    float radius = (float)i / (float)n;
    float q = (float)i * SDF_GOLDEN_ANGLE;
    float3 v = make_float3(sin_half * radius * cos(q), sin_half * radius * sin(q),
                           1.0f - one_minus_cos_half);
    return sdf_normalize(v);
  }
  float one_minus_z, phi;
  if (sampling == SDF_SAMPLING_RANDOM) {
    one_minus_z = sdf_uniform(seed, point, (sdf_uint32)i, 0u) * one_minus_cos_half;
    phi = SDF_TWO_PI * sdf_uniform(seed, point, (sdf_uint32)i, 1u);
  } else {
    one_minus_z = ((float)i + 0.5f) / (float)n * one_minus_cos_half;
    phi = (float)i * SDF_GOLDEN_ANGLE;
  }
  float r = sqrt(fmax(0.0f, one_minus_z * (2.0f - one_minus_z)));
  return make_float3(r * cos(phi), r * sin(phi), 1.0f - one_minus_z);
}

/* Angle between a local direction and the cone axis; atan2 stays accurate near the axis,
 * where acos(z) does not. */
SDF_INLINE float sdf_ray_angle(float3 dir_local) {
  return atan2(sqrt(dir_local.x * dir_local.x + dir_local.y * dir_local.y), dir_local.z);
}

/* The tangent frame for points that carry their own tangent (from their mesh edge, so the ray
 * set turns with the mesh: rotating a mesh rotates its rays, and the values stay put). */
SDF_INLINE void sdf_frame_from_tangent(float3 n, float3 tangent, float3* b1, float3* b2) {
  *b1 = tangent;
  *b2 = sdf_cross(n, tangent);
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
  *b1 = sdf_normalize(base1);
  *b2 = sdf_normalize(sdf_cross(n, base1));
}

/* CGAL sampling reproduces CGAL's frame; the others turn with the mesh. */
SDF_INLINE void sdf_frame(int sampling, float3 n, float3 tangent, float3* b1, float3* b2) {
  if (sampling == SDF_SAMPLING_CGAL) {
    sdf_frame_cgal(n, b1, b2);
  } else {
    sdf_frame_from_tangent(n, tangent, b1, b2);
  }
}

SDF_INLINE float3 sdf_to_world(float3 dir_local, float3 b1, float3 b2, float3 n) {
  return dir_local.x * b1 + dir_local.y * b2 + dir_local.z * n;
}

SDF_KERNEL_END

#endif /* SDF_RAYS_H */
