/* SPDX-License-Identifier: GPL-3.0-or-later */
/* The paper's octree (section 4.2, Figures 4 and 5) and its nearest-hit traversal.
 * Nodes: one 32-bit child descriptor each, the child pointer in the high 24 bits and the valid
 * mask in the low 8 (bit i set: octant i has a child; octant i is high in x when i & 1, in y
 * when i & 2, in z when i & 4). A node with a non-zero mask is inner: its valid children are
 * stored next to each other from the child pointer on, in octant order. A node with mask 0 is
 * a leaf: its pointer indexes the leaf array, which holds the triangle count followed by the
 * triangle indices. Empty octants have no node. */
#ifndef SDF_OCTREE_H
#define SDF_OCTREE_H

#include "ray/sdf_intersect.h"

SDF_KERNEL_BEGIN

#define SDF_OCTREE_POINTER_BITS 24
#define SDF_OCTREE_MAX_POINTER ((1u << SDF_OCTREE_POINTER_BITS) - 1u)
/* A ray in general position crosses at most 4 octants of a cube, but one lying in the cells'
 * shared faces touches every cell on both sides (the entry test is inclusive, so it misses
 * none): all 8 children when it runs along a line where four cells meet. A visit pops one
 * entry and pushes at most 8: 7 more per level, 16 levels the deepest tree the builder
 * accepts. */
#define SDF_OCTREE_MAX_DEPTH 16
#define SDF_OCTREE_STACK_SIZE (7 * SDF_OCTREE_MAX_DEPTH + 1)

SDF_INLINE sdf_uint32 sdf_octree_pointer(sdf_uint32 descriptor) { return descriptor >> 8; }
SDF_INLINE sdf_uint32 sdf_octree_mask(sdf_uint32 descriptor) { return descriptor & 0xffu; }

/* The root cube: its low corner and side length. */
typedef struct SdfOctreeRoot {
  float lo_x, lo_y, lo_z;
  float size;
} SdfOctreeRoot;

SDF_STATIC_ASSERT(sizeof(SdfOctreeRoot) == 16, "SdfOctreeRoot is 16 bytes in every build");

/* Entry distance of the ray into an axis-aligned cube, or INFINITY when it misses the cube or
 * enters it at or beyond tmax. */
SDF_INLINE float sdf_cube_entry(float3 lo, float size, float3 o, float3 inv_d, float tmax) {
  float3 a = (lo - o) * inv_d;
  float3 b = (lo + make_float3(size, size, size) - o) * inv_d;
  float t_near =
      sdf_max(sdf_max(sdf_min(a.x, b.x), sdf_min(a.y, b.y)), sdf_max(sdf_min(a.z, b.z), 0.0f));
  float t_far =
      sdf_min(sdf_min(sdf_max(a.x, b.x), sdf_max(a.y, b.y)), sdf_min(sdf_max(a.z, b.z), tmax));
  return t_near <= t_far ? t_near : INFINITY;
}

/* Nearest hit along o + t d with tmin < t, skipping triangle skip_id; t = INFINITY when none.
 * Children are visited nearest first; subtrees whose cube starts beyond the best hit so far
 * are dropped from the stack unvisited. A triangle may sit in several leaves: testing it twice
 * cannot change the nearest hit. */
SDF_INLINE SdfHit sdf_octree_closest_hit(SDF_GLOBAL const sdf_uint32* nodes,
                                         SDF_GLOBAL const sdf_uint32* leaves,
                                         SDF_GLOBAL const SdfTriangle* tris, SdfOctreeRoot root,
                                         float3 o, float3 d, float tmin, sdf_int32 skip_id) {
  SdfHit hit = sdf_no_hit();
  float3 inv_d = sdf_safe_inverse(d, o);
  sdf_uint32 stack_node[SDF_OCTREE_STACK_SIZE];
  float stack_lo[SDF_OCTREE_STACK_SIZE * 3];
  float stack_size[SDF_OCTREE_STACK_SIZE];
  float stack_entry[SDF_OCTREE_STACK_SIZE];
  int sp = 0;
  float3 root_lo = make_float3(root.lo_x, root.lo_y, root.lo_z);
  float t_root = sdf_cube_entry(root_lo, root.size, o, inv_d, hit.t);
  if (t_root == INFINITY) return hit;
  stack_node[0] = 0u;
  stack_lo[0] = root.lo_x;
  stack_lo[1] = root.lo_y;
  stack_lo[2] = root.lo_z;
  stack_size[0] = root.size;
  stack_entry[0] = t_root;
  sp = 1;
  while (sp > 0) {
    --sp;
    if (stack_entry[sp] > hit.t) continue; /* equal: may hold a tie (sdf_intersect.h) */
    sdf_uint32 descriptor = nodes[stack_node[sp]];
    sdf_uint32 pointer = sdf_octree_pointer(descriptor);
    sdf_uint32 mask = sdf_octree_mask(descriptor);
    if (mask == 0u) {
      sdf_uint32 count = leaves[pointer];
      for (sdf_uint32 k = 0u; k < count; ++k) {
        sdf_uint32 t = leaves[pointer + 1u + k];
        if ((sdf_int32)t != skip_id) sdf_intersect_triangle(o, d, tmin, &tris[t], &hit);
      }
      continue;
    }
    float3 lo = make_float3(stack_lo[3 * sp], stack_lo[3 * sp + 1], stack_lo[3 * sp + 2]);
    float half_size = 0.5f * stack_size[sp];
    /* Children hit by the ray, sorted by entry distance, farthest first. */
    sdf_uint32 child_node[8];
    float child_entry[8];
    float3 child_lo[8];
    int hits = 0;
    sdf_uint32 next = pointer;
    for (int octant = 0; octant < 8; ++octant) {
      if (!(mask & (1u << octant))) continue;
      float3 c_lo =
          lo + make_float3((octant & 1) ? half_size : 0.0f, (octant & 2) ? half_size : 0.0f,
                           (octant & 4) ? half_size : 0.0f);
      float t = sdf_cube_entry(c_lo, half_size, o, inv_d, hit.t);
      if (t != INFINITY) {
        int j = hits++;
        while (j > 0 && child_entry[j - 1] < t) {
          child_entry[j] = child_entry[j - 1];
          child_node[j] = child_node[j - 1];
          child_lo[j] = child_lo[j - 1];
          --j;
        }
        child_entry[j] = t;
        child_node[j] = next;
        child_lo[j] = c_lo;
      }
      ++next;
    }
    for (int i = 0; i < hits; ++i) {
      stack_node[sp] = child_node[i];
      stack_lo[3 * sp] = child_lo[i].x;
      stack_lo[3 * sp + 1] = child_lo[i].y;
      stack_lo[3 * sp + 2] = child_lo[i].z;
      stack_size[sp] = half_size;
      stack_entry[sp] = child_entry[i];
      ++sp;
    }
  }
  return hit;
}

SDF_KERNEL_END

#endif /* SDF_OCTREE_H */
