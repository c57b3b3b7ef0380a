/* SPDX-License-Identifier: GPL-3.0-or-later */
/* Where a face's rays start and how their cone is turned: the centroid, the unit inward axis
 * and the tangent the ray set starts from in azimuth. The host's sampling
 * (native/prepare/sampling.h) and the cast kernels on a device-built tree (sdf_start_of_face in
 * sdf_kernels.cl) both compute them here, in one order of operations, so they agree bit for bit. */
#ifndef SDF_FACE_POINT_H
#define SDF_FACE_POINT_H

#include "common/sdf_compat.h"

SDF_KERNEL_BEGIN

/* std::max's rule, written out: (a < b) ? b : a. */
SDF_INLINE float sdf_larger(float a, float b) { return a < b ? b : a; }

/* Unit vector, or zero when the direction is undefined (zero or not finite). Divided by its
 * largest component first: squaring a cross product (edge length to the fourth) would
 * overflow or underflow float for edges past ~4e9 or below ~5e-12 (found by fuzzing). */
SDF_INLINE float3 sdf_unit_or_zero(float3 v) {
  float big = sdf_larger(fabs(v.x), sdf_larger(fabs(v.y), fabs(v.z)));
  if (!(big > 0.0f) || !isfinite(big)) return make_float3(0.0f, 0.0f, 0.0f);
  v = make_float3(v.x / big, v.y / big, v.z / big);
  float length = sqrt(sdf_dot(v, v));
  return make_float3(v.x / length, v.y / length, v.z / length);
}

/* A unit vector perpendicular to unit `axis`, for points whose mesh gives no tangent: the
 * direction of cross(axis, g) for a fixed, deliberately skewed g. Continuous except where the
 * axis is parallel to g, a direction no mesh normal takes in practice (axis-aligned normals,
 * common in CAD, are far from it). g = (1, 2, 3) / sqrt(14); only an axis within ~1e-3 rad of
 * +-g switches to a second direction (a cap no real normal hits by accident). */
SDF_INLINE float3 sdf_fallback_tangent(float3 axis) {
  float3 c = sdf_cross(axis, make_float3(0.26726124f, 0.53452248f, 0.80178373f));
  if (sdf_dot(c, c) > 1e-6f) return sdf_normalize(c);
  return sdf_normalize(sdf_cross(axis, make_float3(-0.80178373f, 0.26726124f, 0.53452248f)));
}

/* The part of `edge` perpendicular to unit `axis`, normalised; sdf_fallback_tangent() when that
 * part vanishes, zero when the axis is zero. */
SDF_INLINE float3 sdf_tangent_from_edge(float3 axis, float3 edge) {
  if (axis.x == 0.0f && axis.y == 0.0f && axis.z == 0.0f) return make_float3(0.0f, 0.0f, 0.0f);
  float3 unit_edge = sdf_unit_or_zero(edge);
  float along = sdf_dot(unit_edge, axis);
  float3 t = make_float3(unit_edge.x - along * axis.x, unit_edge.y - along * axis.y,
                         unit_edge.z - along * axis.z);
  if (sqrt(sdf_dot(t, t)) > 1e-6f) return sdf_normalize(t);
  return sdf_fallback_tangent(axis);
}

/* The face (a, b, c)'s centroid, and its unit inward axis: minus the normal of
 * cross(b - a, c - a) (zero for a zero-area face). */
SDF_INLINE void sdf_face_origin_axis(float3 a, float3 b, float3 c, float3* origin, float3* axis) {
  float third = 1.0f / 3.0f;
  float3 sum = make_float3(a.x + b.x + c.x, a.y + b.y + c.y, a.z + b.z + c.z);
  *origin = make_float3(sum.x * third, sum.y * third, sum.z * third);
  float3 n = sdf_unit_or_zero(sdf_cross(make_float3(b.x - a.x, b.y - a.y, b.z - a.z),
                                        make_float3(c.x - a.x, c.y - a.y, c.z - a.z)));
  *axis = make_float3(-n.x, -n.y, -n.z);
}

/* The same and the face's tangent, from its first edge b - a. */
SDF_INLINE void sdf_face_point(float3 a, float3 b, float3 c, float3* origin, float3* axis,
                               float3* tangent) {
  sdf_face_origin_axis(a, b, c, origin, axis);
  *tangent = sdf_tangent_from_edge(*axis, make_float3(b.x - a.x, b.y - a.y, b.z - a.z));
}

SDF_KERNEL_END

#endif /* SDF_FACE_POINT_H */
