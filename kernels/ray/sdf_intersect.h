/* SPDX-License-Identifier: GPL-3.0-or-later */
/* Ray-triangle intersection (Moller and Trumbore 1997; paper 4.2) and ray-box slabs. */
#ifndef SDF_INTERSECT_H
#define SDF_INTERSECT_H

#include "common/sdf_layout.h"

SDF_KERNEL_BEGIN

/* The nearest hit found so far along a ray. det < 0 means the ray leaves the solid through the
 * hit face: det = dot(e1, cross(d, e2)) = -dot(d, cross(e1, e2)), and cross(e1, e2) is the
 * outward normal of a counter-clockwise triangle. So the exit test is one sign, no normal. */
typedef struct SdfHit {
  float t;
  float det;
  sdf_int32 id;
} SdfHit;

/* A hit that counts for the SDF: the ray leaves the solid through it (det < 0, above). */
SDF_INLINE int sdf_exit_hit(SdfHit hit) { return hit.det < 0.0f && hit.t < INFINITY; }

/* No hit yet: t = INFINITY. */
SDF_INLINE SdfHit sdf_no_hit(void) {
  SdfHit hit;
  hit.t = INFINITY;
  hit.det = 0.0f;
  hit.id = -1;
  return hit;
}

SDF_INLINE float3 sdf_tri_v0(SDF_GLOBAL const SdfTriangle* tri) {
  return make_float3(tri->v0_x, tri->v0_y, tri->v0_z);
}
SDF_INLINE float3 sdf_tri_e1(SDF_GLOBAL const SdfTriangle* tri) {
  return make_float3(tri->e1_x, tri->e1_y, tri->e1_z);
}
SDF_INLINE float3 sdf_tri_e2(SDF_GLOBAL const SdfTriangle* tri) {
  return make_float3(tri->e2_x, tri->e2_y, tri->e2_z);
}

/* Updates *hit when the ray o + t d meets the triangle at tmin < t < hit->t, or at t equal to
 * hit->t with a smaller triangle id: ties (a ray through a shared edge, a triangle doubled
 * with opposite winding) then go to the same triangle whatever order a structure visits them
 * in, so every engine and acceleration structure agrees. A zero-area triangle has det == 0
 * and is never hit.
 * Triangles are grown by SDF_BARYCENTRIC_SLACK in barycentric terms: float32 Moller-Trumbore
 * is not watertight, and a ray through a shared edge was measured to miss both triangles
 * (u + v = 1 + 2.4e-6 on one, v = -1.7e-7 on the other), losing the ray. 1e-5 of a triangle's
 * size is far below any thickness the SDF resolves. */
#define SDF_BARYCENTRIC_SLACK 1e-5f
SDF_INLINE void sdf_intersect_values(float3 o, float3 d, float tmin, float3 v0, float3 e1,
                                     float3 e2, sdf_int32 id, SdfHit* hit) {
  float3 p = sdf_cross(d, e2);
  float det = sdf_dot(e1, p);
  if (det == 0.0f) return;
  float inv_det = 1.0f / det;
  float3 s = o - v0;
  float u = sdf_dot(s, p) * inv_det;
  if (u < -SDF_BARYCENTRIC_SLACK || u > 1.0f + SDF_BARYCENTRIC_SLACK) return;
  float3 q = sdf_cross(s, e1);
  float v = sdf_dot(d, q) * inv_det;
  if (v < -SDF_BARYCENTRIC_SLACK || u + v > 1.0f + SDF_BARYCENTRIC_SLACK) return;
  float t = sdf_dot(e2, q) * inv_det;
  /* !(t > tmin) also turns away a NaN t (1 / det overflowing on a vanishingly small
   * triangle), which every other comparison here would let through. */
  if (!(t > tmin) || t > hit->t || (t == hit->t && id >= hit->id)) return;
  hit->t = t;
  hit->det = det;
  hit->id = id;
}

/* The same on a triangle in memory. */
SDF_INLINE void sdf_intersect_triangle(float3 o, float3 d, float tmin,
                                       SDF_GLOBAL const SdfTriangle* tri, SdfHit* hit) {
  sdf_intersect_values(o, d, tmin, sdf_tri_v0(tri), sdf_tri_e1(tri), sdf_tri_e2(tri), tri->id, hit);
}

/* The entry distance from a box's slab distances along x, y and z (either end first), or
 * INFINITY when the slabs do not overlap in [0, tmax]. */
SDF_INLINE float sdf_slab_entry(float tx0, float tx1, float ty0, float ty1, float tz0, float tz1,
                                float tmax) {
  float t_near =
      sdf_max(sdf_max(sdf_min(tx0, tx1), sdf_min(ty0, ty1)), sdf_max(sdf_min(tz0, tz1), 0.0f));
  float t_far =
      sdf_min(sdf_min(sdf_max(tx0, tx1), sdf_max(ty0, ty1)), sdf_min(sdf_max(tz0, tz1), tmax));
  return t_near <= t_far ? t_near : INFINITY;
}

/* Entry distance of the ray into a node's box, or INFINITY when it misses the box or enters
 * beyond tmax. inv_d holds 1/d with zero components replaced by a huge finite value. */
SDF_INLINE float sdf_box_entry_values(float3 lo, float3 hi, float3 o, float3 inv_d, float tmax) {
  return sdf_slab_entry((lo.x - o.x) * inv_d.x, (hi.x - o.x) * inv_d.x, (lo.y - o.y) * inv_d.y,
                        (hi.y - o.y) * inv_d.y, (lo.z - o.z) * inv_d.z, (hi.z - o.z) * inv_d.z,
                        tmax);
}

/* The same from o * inv_d (o_inv), each slab distance one fused multiply-add: lo * inv_d - o_inv
 * rounds once where (lo - o) * inv_d rounds twice; bvh_margin.h's growth covers both. */
SDF_INLINE float sdf_box_entry_fused(float3 lo, float3 hi, float3 o_inv, float3 inv_d, float tmax) {
  return sdf_slab_entry(fma(lo.x, inv_d.x, -o_inv.x), fma(hi.x, inv_d.x, -o_inv.x),
                        fma(lo.y, inv_d.y, -o_inv.y), fma(hi.y, inv_d.y, -o_inv.y),
                        fma(lo.z, inv_d.z, -o_inv.z), fma(hi.z, inv_d.z, -o_inv.z), tmax);
}

/* The same on a node in memory. */
SDF_INLINE float sdf_box_entry(SDF_GLOBAL const SdfBvhNode* node, float3 o, float3 inv_d,
                               float tmax) {
  return sdf_box_entry_values(make_float3(node->lo_x, node->lo_y, node->lo_z),
                              make_float3(node->hi_x, node->hi_y, node->hi_z), o, inv_d, tmax);
}

/* 1 / d for the ray o + t d, where a component is zero or so small (|1 / d| beyond `big`) that
 * o * (1 / d) could overflow, a huge value of its sign instead: slab tests take
 * plane * inv - o * inv (or (plane - o) * inv), so o * inv must stay finite. big is 1e30 within
 * about 1e8 units of the centre, 1e38 / |o| beyond: a fixed 1e30 overflowed past ~3e8 units
 * and lost every ray along an axis (and 1 / d of a component like 5e-29, a face's axis off by
 * round-off, overflowed sooner). Treating such a component as zero is safe: the ray's line
 * then stays within the boxes' margin (2^-20 of the largest coordinate, bvh_margin.h) of
 * where it started on that axis, and every slab it runs inside is still at least margin * big,
 * about 1e32, away. */
SDF_INLINE float sdf_safe_inverse_1(float d, float big) {
  float inv = 1.0f / d;
  return fabs(d) > 1e-30f && fabs(inv) <= big ? inv : copysign(big, d);
}

SDF_INLINE float3 sdf_safe_inverse(float3 d, float3 o) {
  float reach = sdf_max(1.0f, sdf_max(fabs(o.x), sdf_max(fabs(o.y), fabs(o.z))));
  float big = sdf_min(1e30f, 1e38f / reach);
  return make_float3(sdf_safe_inverse_1(d.x, big), sdf_safe_inverse_1(d.y, big),
                     sdf_safe_inverse_1(d.z, big));
}

SDF_KERNEL_END

#endif /* SDF_INTERSECT_H */
