/* SPDX-License-Identifier: GPL-3.0-or-later */
/* Nearest-hit traversal of the 4-wide BVH (SdfBvh4Node) for the OpenCL engine: one node visit
 * tests four boxes, so a ray visits about half the nodes of the binary tree and reads them as
 * two 64-byte lines instead of one 32-byte node per box. Leaves are intersected as soon as
 * their box is hit (nearest first), inner children go on a short stack (farthest first).
 * Same answers as sdf_bvh_traverse.h: ties between equally near hits go to the lower triangle
 * id, whatever the visiting order. */
#ifndef SDF_BVH4_TRAVERSE_H
#define SDF_BVH4_TRAVERSE_H

#include "ray/sdf_intersect.h"

SDF_KERNEL_BEGIN

/* A visit pushes at most three more entries than it pops, so a tree of depth D needs 3 D + 1
 * entries; the host uses this traversal only for trees at most SDF_BVH4_MAX_DEPTH deep and
 * falls back to the binary one otherwise. */
#define SDF_BVH4_MAX_DEPTH 31
#define SDF_BVH4_STACK_SIZE (3 * SDF_BVH4_MAX_DEPTH + 1)

/* One child of a visited node: its entry distance (INFINITY when missed), index and count. */
typedef struct SdfSlot {
  float t;
  sdf_int32 child;
  sdf_int32 count;
} SdfSlot;

/* Per axis the plane a ray meets first is lo when it travels up the axis and hi otherwise,
 * chosen once per ray; empty slots (lo = +inf, hi = -inf) then give near > far. The same
 * arithmetic as the CPU engine's SSE test (native/cast/bvh4_traverse.h): lo * inv - o * inv. */
SDF_INLINE SdfSlot sdf_bvh4_slot(SDF_GLOBAL const SdfBvh4Node* n, int i, int neg_x, int neg_y,
                                 int neg_z, float3 inv, float3 o_inv, float tmax) {
  float near_x = (neg_x ? n->hi_x[i] : n->lo_x[i]) * inv.x - o_inv.x;
  float near_y = (neg_y ? n->hi_y[i] : n->lo_y[i]) * inv.y - o_inv.y;
  float near_z = (neg_z ? n->hi_z[i] : n->lo_z[i]) * inv.z - o_inv.z;
  float far_x = (neg_x ? n->lo_x[i] : n->hi_x[i]) * inv.x - o_inv.x;
  float far_y = (neg_y ? n->lo_y[i] : n->hi_y[i]) * inv.y - o_inv.y;
  float far_z = (neg_z ? n->lo_z[i] : n->hi_z[i]) * inv.z - o_inv.z;
  float t_near = sdf_max(sdf_max(near_x, near_y), sdf_max(near_z, 0.0f));
  float t_far = sdf_min(sdf_min(far_x, far_y), sdf_min(far_z, tmax));
  SdfSlot s;
  s.t = t_near <= t_far ? t_near : INFINITY;
  s.child = n->child[i];
  s.count = n->count[i];
  return s;
}

/* A box worth opening: hit, and not beyond the best hit (equal may still hold a tie won by a
 * smaller id). */
SDF_INLINE int sdf_bvh4_open(float t, float best) { return t < INFINITY && t <= best; }

SDF_INLINE void sdf_bvh4_order(SdfSlot* a, SdfSlot* b) {
  if (b->t < a->t) {
    SdfSlot tmp = *a;
    *a = *b;
    *b = tmp;
  }
}

SDF_INLINE void sdf_bvh4_leaf(SDF_GLOBAL const SdfTriangle* tris, SdfSlot s, float3 o, float3 d,
                              float tmin, sdf_int32 skip_id, SdfHit* hit) {
  if (s.count == 0 || !sdf_bvh4_open(s.t, hit->t)) return;
  sdf_int32 first = ~s.child;
  for (sdf_int32 k = first; k < first + s.count; ++k) {
    if (tris[k].id != skip_id) sdf_intersect_triangle(o, d, tmin, &tris[k], hit);
  }
}

#define SDF_BVH4_PUSH(s)                                                  \
  if ((s).child >= 0 && (s).count == 0 && sdf_bvh4_open((s).t, hit.t)) { \
    stack_node[sp] = (s).child;                                           \
    stack_t[sp++] = (s).t;                                                \
  }

/* Finds the nearest triangle hit along o + t d with tmin < t, skipping triangle skip_id (-1
 * for none). Returns the hit with t = INFINITY when nothing is hit. */
SDF_INLINE SdfHit sdf_bvh4_closest_hit(SDF_GLOBAL const SdfBvh4Node* nodes,
                                       SDF_GLOBAL const SdfTriangle* tris, float3 o, float3 d,
                                       float tmin, sdf_int32 skip_id) {
  SdfHit hit = sdf_no_hit();
  float3 inv = sdf_safe_inverse(d, o);
  float3 o_inv = make_float3(o.x * inv.x, o.y * inv.y, o.z * inv.z);
  int neg_x = inv.x < 0.0f, neg_y = inv.y < 0.0f, neg_z = inv.z < 0.0f;
  sdf_int32 stack_node[SDF_BVH4_STACK_SIZE];
  float stack_t[SDF_BVH4_STACK_SIZE];
  int sp = 0;
  sdf_int32 index = 0;
  for (;;) {
    SDF_GLOBAL const SdfBvh4Node* n = &nodes[index];
    SdfSlot s0 = sdf_bvh4_slot(n, 0, neg_x, neg_y, neg_z, inv, o_inv, hit.t);
    SdfSlot s1 = sdf_bvh4_slot(n, 1, neg_x, neg_y, neg_z, inv, o_inv, hit.t);
    SdfSlot s2 = sdf_bvh4_slot(n, 2, neg_x, neg_y, neg_z, inv, o_inv, hit.t);
    SdfSlot s3 = sdf_bvh4_slot(n, 3, neg_x, neg_y, neg_z, inv, o_inv, hit.t);
    /* A sorting network on four: s0 <= s1 <= s2 <= s3 by entry distance. */
    sdf_bvh4_order(&s0, &s1);
    sdf_bvh4_order(&s2, &s3);
    sdf_bvh4_order(&s0, &s2);
    sdf_bvh4_order(&s1, &s3);
    sdf_bvh4_order(&s1, &s2);
    /* Leaves nearest first: each hit shortens the ray for the boxes after it. */
    sdf_bvh4_leaf(tris, s0, o, d, tmin, skip_id, &hit);
    sdf_bvh4_leaf(tris, s1, o, d, tmin, skip_id, &hit);
    sdf_bvh4_leaf(tris, s2, o, d, tmin, skip_id, &hit);
    sdf_bvh4_leaf(tris, s3, o, d, tmin, skip_id, &hit);
    /* Inner children farthest first, so the nearest is popped next. */
    SDF_BVH4_PUSH(s3)
    SDF_BVH4_PUSH(s2)
    SDF_BVH4_PUSH(s1)
    SDF_BVH4_PUSH(s0)
    for (;;) {
      if (sp == 0) return hit;
      --sp;
      if (stack_t[sp] <= hit.t) break;
    }
    index = stack_node[sp];
  }
}

#undef SDF_BVH4_PUSH

SDF_KERNEL_END

#endif /* SDF_BVH4_TRAVERSE_H */
