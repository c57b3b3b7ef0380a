/* SPDX-License-Identifier: GPL-3.0-or-later */
/* Nearest-hit traversal of the 8-wide BVH (SdfBvh8Node, SdfTrianglePacket4) for OpenCL on
 * CPUs (PoCL): the CPU engine's tree and algorithm (native/cast/bvh8_traverse_avx2.cpp) written
 * with OpenCL vector types, which PoCL's LLVM compiles to the host's SIMD registers. One visit
 * tests eight boxes as float8 slabs; a leaf tests four triangles per float4 packet.
 * OpenCL C only (vector types, vload8): the CPU engine has its own intrinsics version.
 * Same answers, bit for bit, as sdf_intersect_triangle over every triangle: each packet lane
 * does the scalar test's operations in its order (FP_CONTRACT is off, sdf_compat.h), and
 * passing lanes update the hit in lane order with the scalar test's tie rule. */
#ifndef SDF_BVH8_TRAVERSE_H
#define SDF_BVH8_TRAVERSE_H

#include "ray/sdf_intersect.h"
#include "traverse/sdf_bvh_traverse.h"

/* A visit pushes at most seven more entries than it pops; a wide node lies at least one binary
 * level below its parent, so the 8-wide tree is no deeper than the binary one
 * (SDF_BVH_STACK_SIZE - 4 levels at most, bvh_sah.h) and this stack never overflows. */
#define SDF_BVH8_STACK_SIZE (7 * (SDF_BVH_STACK_SIZE - 4) + 1)

/* Offsets, in floats, of the planes of SdfBvh8Node (sdf_layout.h). */
#define SDF_BVH8_LO_X 0
#define SDF_BVH8_LO_Y 8
#define SDF_BVH8_LO_Z 16
#define SDF_BVH8_HI_X 24
#define SDF_BVH8_HI_Y 32
#define SDF_BVH8_HI_Z 40

/* One passing lane of a packet: the scalar test's final update, ties to the lower id. */
#define SDF_PACKET_LANE(lane)                                             \
  if (pass.lane) {                                                        \
    float t_lane = t.lane;                                                \
    sdf_int32 id_lane = id.lane;                                          \
    if (!(t_lane > hit->t || (t_lane == hit->t && id_lane >= hit->id))) { \
      hit->t = t_lane;                                                    \
      hit->det = det.lane;                                                \
      hit->id = id_lane;                                                  \
    }                                                                     \
  }

/* sdf_intersect_triangle on the four triangles of a packet (unused lanes have e1 = e2 = 0,
 * so det == 0 rejects them), skipping skip_id. */
__attribute__((always_inline)) SDF_INLINE void sdf_intersect_packet4(
    __global const SdfTrianglePacket4* p, float3 o, float3 d, float tmin, sdf_int32 skip_id,
    SdfHit* hit) {
  float4 e1x = vload4(0, p->e1_x), e1y = vload4(0, p->e1_y), e1z = vload4(0, p->e1_z);
  float4 e2x = vload4(0, p->e2_x), e2y = vload4(0, p->e2_y), e2z = vload4(0, p->e2_z);
  /* p = cross(d, e2); det = dot(e1, p) */
  float4 px = d.y * e2z - d.z * e2y;
  float4 py = d.z * e2x - d.x * e2z;
  float4 pz = d.x * e2y - d.y * e2x;
  float4 det = e1x * px + e1y * py + e1z * pz;
  float4 inv_det = 1.0f / det;
  /* s = o - v0; u = dot(s, p) * inv_det */
  float4 sx = o.x - vload4(0, p->v0_x);
  float4 sy = o.y - vload4(0, p->v0_y);
  float4 sz = o.z - vload4(0, p->v0_z);
  float4 u = (sx * px + sy * py + sz * pz) * inv_det;
  /* q = cross(s, e1); v = dot(d, q) * inv_det; t = dot(e2, q) * inv_det */
  float4 qx = sy * e1z - sz * e1y;
  float4 qy = sz * e1x - sx * e1z;
  float4 qz = sx * e1y - sy * e1x;
  float4 v = (d.x * qx + d.y * qy + d.z * qz) * inv_det;
  float4 t = (e2x * qx + e2y * qy + e2z * qz) * inv_det;
  int4 id = vload4(0, p->id);
  /* Rejections exactly as the scalar code writes them (ordered comparisons: false on NaN,
   * except "not greater than tmin", true on NaN, so a NaN t is turned away as there). */
  const float lo = -SDF_BARYCENTRIC_SLACK, hi = 1.0f + SDF_BARYCENTRIC_SLACK;
  int4 reject = (det == 0.0f) | (u < lo) | (u > hi) | (v < lo) | (u + v > hi) | ~(t > tmin) |
                (t > hit->t) | (id == skip_id);
  int4 pass = ~reject;
  if (!any(pass)) return;
  SDF_PACKET_LANE(s0)
  SDF_PACKET_LANE(s1)
  SDF_PACKET_LANE(s2)
  SDF_PACKET_LANE(s3)
}

#undef SDF_PACKET_LANE

/* One slab distance for the eight boxes: plane * inv - o * inv, as the 4-wide kernel. */
SDF_INLINE float8 sdf_bvh8_slab(__global const float* node, int plane, float inv, float o_inv) {
  return vload8(0, node + plane) * inv - o_inv;
}

/* One ray's traversal as a state machine: sdf_bvh8_step does one visit (a node or a leaf),
 * so that two rays of a point can take turns and one's cache misses overlap the other's work,
 * as the CPU engine does: 1.09-1.14x the rays/s of one ray at a time (PoCL, 52k-832k faces,
 * same run). The nearest box hit is visited next and the others pushed farthest first.
 * The state is two small structs and three stack arrays kept apart from them: one struct
 * holding the stacks too measured 4-18% slower than a plain loop, and so did the interleaving
 * built on it. always_inline: the step is called from two places per pair. */
typedef struct SdfBvh8Ray {
  float3 o, d, inv, o_inv;
  /* Per axis the plane a ray meets first is lo when it travels up the axis and hi otherwise
   * (empty slots, lo = +inf and hi = -inf, then give near > far). */
  int near_x, far_x, near_y, far_y, near_z, far_z;
} SdfBvh8Ray;

typedef struct SdfBvh8Cursor {
  SdfHit hit;
  sdf_int32 child, count; /* what the next visit visits */
  int sp;
} SdfBvh8Cursor;

SDF_INLINE SdfBvh8Ray sdf_bvh8_ray(float3 o, float3 d) {
  SdfBvh8Ray r;
  r.o = o;
  r.d = d;
  r.inv = sdf_safe_inverse(d, o);
  r.o_inv = make_float3(o.x * r.inv.x, o.y * r.inv.y, o.z * r.inv.z);
  r.near_x = r.inv.x < 0.0f ? SDF_BVH8_HI_X : SDF_BVH8_LO_X;
  r.far_x = r.inv.x < 0.0f ? SDF_BVH8_LO_X : SDF_BVH8_HI_X;
  r.near_y = r.inv.y < 0.0f ? SDF_BVH8_HI_Y : SDF_BVH8_LO_Y;
  r.far_y = r.inv.y < 0.0f ? SDF_BVH8_LO_Y : SDF_BVH8_HI_Y;
  r.near_z = r.inv.z < 0.0f ? SDF_BVH8_HI_Z : SDF_BVH8_LO_Z;
  r.far_z = r.inv.z < 0.0f ? SDF_BVH8_LO_Z : SDF_BVH8_HI_Z;
  return r;
}

SDF_INLINE SdfBvh8Cursor sdf_bvh8_cursor(void) {
  SdfBvh8Cursor c;
  c.hit.t = INFINITY;
  c.hit.det = 0.0f;
  c.hit.id = -1;
  c.child = 0;
  c.count = 0;
  c.sp = 0;
  return c;
}

/* One visit; 0 once the ray is done (c->hit is then final). */
__attribute__((always_inline)) SDF_INLINE int sdf_bvh8_step(
    __global const SdfBvh8Node* nodes, __global const SdfTrianglePacket4* packets, SdfBvh8Ray r,
    float tmin, sdf_int32 skip_id, SdfBvh8Cursor* c, sdf_int32* stack_child, sdf_int32* stack_count,
    float* stack_t) {
  if (c->child < 0) {
    __global const SdfTrianglePacket4* packet = &packets[~c->child];
    for (sdf_int32 k = 0; k < c->count; ++k)
      sdf_intersect_packet4(&packet[k], r.o, r.d, tmin, skip_id, &c->hit);
  } else {
    __global const SdfBvh8Node* node = &nodes[c->child];
    __global const float* planes = (__global const float*)node;
    float8 t_near = fmax(fmax(sdf_bvh8_slab(planes, r.near_x, r.inv.x, r.o_inv.x),
                              sdf_bvh8_slab(planes, r.near_y, r.inv.y, r.o_inv.y)),
                         fmax(sdf_bvh8_slab(planes, r.near_z, r.inv.z, r.o_inv.z), (float8)(0.0f)));
    float8 t_far =
        fmin(fmin(sdf_bvh8_slab(planes, r.far_x, r.inv.x, r.o_inv.x),
                  sdf_bvh8_slab(planes, r.far_y, r.inv.y, r.o_inv.y)),
             fmin(sdf_bvh8_slab(planes, r.far_z, r.inv.z, r.o_inv.z), (float8)(c->hit.t)));
    int8 hits = (t_near <= t_far) & (int8)(1, 2, 4, 8, 16, 32, 64, 128);
    uint mask =
        (uint)(hits.s0 | hits.s1 | hits.s2 | hits.s3 | hits.s4 | hits.s5 | hits.s6 | hits.s7);
    if (mask != 0) {
      float entry[8];
      vstore8(t_near, 0, entry);
      /* Sorted by entry distance, farthest first (insertion sort: mostly 1 to 3 boxes). */
      sdf_int32 sorted_child[8], sorted_count[8];
      float sorted_t[8];
      int h = 0;
      while (mask) {
        int i = 31 - clz(mask & (~mask + 1u));
        mask &= mask - 1u;
        float t_i = entry[i];
        int j = h++;
        while (j > 0 && sorted_t[j - 1] < t_i) {
          sorted_t[j] = sorted_t[j - 1];
          sorted_child[j] = sorted_child[j - 1];
          sorted_count[j] = sorted_count[j - 1];
          --j;
        }
        sorted_t[j] = t_i;
        sorted_child[j] = node->child[i];
        sorted_count[j] = node->count[i];
      }
      for (int k = 0; k < h - 1; ++k) {
        stack_child[c->sp] = sorted_child[k];
        stack_count[c->sp] = sorted_count[k];
        stack_t[c->sp++] = sorted_t[k];
      }
      c->child = sorted_child[h - 1];
      c->count = sorted_count[h - 1];
      return 1;
    }
  }
  /* Next: the nearest pushed box that may still hold a nearer hit (equal may hold a tie won
   * by a smaller id). */
  for (;;) {
    if (c->sp == 0) return 0;
    --c->sp;
    if (stack_t[c->sp] <= c->hit.t) break;
  }
  c->child = stack_child[c->sp];
  c->count = stack_count[c->sp];
  return 1;
}

/* The nearest hits of two rays from one origin, taking turns visit by visit. */
SDF_INLINE void sdf_bvh8_closest_hits2(__global const SdfBvh8Node* nodes,
                                       __global const SdfTrianglePacket4* packets, float3 o,
                                       float3 d0, float3 d1, float tmin, sdf_int32 skip_id,
                                       SdfHit* hit0, SdfHit* hit1) {
  SdfBvh8Ray a = sdf_bvh8_ray(o, d0), b = sdf_bvh8_ray(o, d1);
  SdfBvh8Cursor ca = sdf_bvh8_cursor(), cb = sdf_bvh8_cursor();
  sdf_int32 a_child[SDF_BVH8_STACK_SIZE], a_count[SDF_BVH8_STACK_SIZE];
  sdf_int32 b_child[SDF_BVH8_STACK_SIZE], b_count[SDF_BVH8_STACK_SIZE];
  float a_t[SDF_BVH8_STACK_SIZE], b_t[SDF_BVH8_STACK_SIZE];
  int a_on = 1, b_on = 1;
  while (a_on | b_on) {
    if (a_on) a_on = sdf_bvh8_step(nodes, packets, a, tmin, skip_id, &ca, a_child, a_count, a_t);
    if (b_on) b_on = sdf_bvh8_step(nodes, packets, b, tmin, skip_id, &cb, b_child, b_count, b_t);
  }
  *hit0 = ca.hit;
  *hit1 = cb.hit;
}

/* Finds the nearest triangle hit along o + t d with tmin < t, skipping triangle skip_id (-1
 * for none). Returns the hit with t = INFINITY when nothing is hit. */
SDF_INLINE SdfHit sdf_bvh8_closest_hit(__global const SdfBvh8Node* nodes,
                                       __global const SdfTrianglePacket4* packets, float3 o,
                                       float3 d, float tmin, sdf_int32 skip_id) {
  SdfBvh8Ray r = sdf_bvh8_ray(o, d);
  SdfBvh8Cursor c = sdf_bvh8_cursor();
  sdf_int32 stack_child[SDF_BVH8_STACK_SIZE], stack_count[SDF_BVH8_STACK_SIZE];
  float stack_t[SDF_BVH8_STACK_SIZE];
  while (sdf_bvh8_step(nodes, packets, r, tmin, skip_id, &c, stack_child, stack_count, stack_t)) {
  }
  return c.hit;
}

#endif /* SDF_BVH8_TRAVERSE_H */
