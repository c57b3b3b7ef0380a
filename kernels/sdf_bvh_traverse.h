/* SPDX-License-Identifier: GPL-3.0-or-later */
/* Nearest-hit traversal of the packed BVH: near child first, far child on a short stack,
 * subtrees skipped once the best hit is nearer than their box. */
#ifndef SDF_BVH_TRAVERSE_H
#define SDF_BVH_TRAVERSE_H

#include "sdf_intersect.h"

SDF_KERNEL_BEGIN

/* Deep enough for any tree the host builds: the builder stops splitting at this depth. */
#define SDF_BVH_STACK_SIZE 64

/* Finds the nearest triangle hit along o + t d with tmin < t, skipping triangle skip_id (the
 * point's own face; -1 for none). Returns the hit with t = INFINITY when nothing is hit. */
SDF_INLINE SdfHit sdf_bvh_closest_hit(SDF_GLOBAL const SdfBvhNode* nodes,
                                      SDF_GLOBAL const SdfTriangle* tris, float3 o, float3 d,
                                      float tmin, sdf_int32 skip_id) {
  SdfHit hit = sdf_no_hit();
  float3 inv_d = sdf_safe_inverse(d);
  /* Far children wait here with their entry distance, so a pop that can no longer hold a
   * nearer hit is dropped without touching the node again. */
  sdf_int32 stack_node[SDF_BVH_STACK_SIZE];
  float stack_entry[SDF_BVH_STACK_SIZE];
  int sp = 0;
  sdf_int32 index = 0;
  if (sdf_box_entry(&nodes[0], o, inv_d, hit.t) == INFINITY) return hit;
  for (;;) {
    SDF_GLOBAL const SdfBvhNode* node = &nodes[index];
    if (node->count > 0) {
      for (sdf_int32 k = node->first; k < node->first + node->count; ++k) {
        if (tris[k].id != skip_id) sdf_intersect_triangle(o, d, tmin, &tris[k], &hit);
      }
    } else {
      sdf_int32 left = node->first;
      float t_left = sdf_box_entry(&nodes[left], o, inv_d, hit.t);
      float t_right = sdf_box_entry(&nodes[left + 1], o, inv_d, hit.t);
      if (t_left != INFINITY || t_right != INFINITY) {
        if (t_left == INFINITY) {
          index = left + 1;
        } else if (t_right == INFINITY) {
          index = left;
        } else if (t_left <= t_right) {
          stack_node[sp] = left + 1;
          stack_entry[sp++] = t_right;
          index = left;
        } else {
          stack_node[sp] = left;
          stack_entry[sp++] = t_left;
          index = left + 1;
        }
        continue;
      }
    }
    /* Pop the next subtree that can still hold a nearer hit (or an equally near one: ties
     * are decided by triangle id, see sdf_intersect_triangle). */
    for (;;) {
      if (sp == 0) return hit;
      --sp;
      if (stack_entry[sp] <= hit.t) break;
    }
    index = stack_node[sp];
  }
}

SDF_KERNEL_END

#endif /* SDF_BVH_TRAVERSE_H */
