/* SPDX-License-Identifier: GPL-3.0-or-later */
/* Nearest-hit traversal of the packed BVH: leaf children tested at once, then the nearer inner
 * child first, the farther on a short stack, subtrees skipped once the best hit is nearer
 * than their box. */
#ifndef SDF_BVH_TRAVERSE_H
#define SDF_BVH_TRAVERSE_H

#include "ray/sdf_intersect.h"

SDF_KERNEL_BEGIN

/* Deep enough for any tree: the host's builder stops splitting 4 levels short of it
 * (bvh_sah.h), the device's LBVH is at most 31 + log2(faces) <= 60 levels high, and the
 * stack holds fewer entries than the tree has levels. */
#define SDF_BVH_STACK_SIZE 64

/* The hits of leaf triangles [first, first + count) into *hit. */
SDF_INLINE void sdf_bvh_leaf_hits(SDF_GLOBAL const sdf_float4* tris, sdf_int32 first,
                                  sdf_int32 count, float3 o, float3 d, float tmin,
                                  sdf_int32 skip_id, SdfHit* hit) {
  for (sdf_int32 k = first; k < first + count; ++k) {
    sdf_float4 a = sdf_load4(tris, 3 * k);
    if (sdf_as_int(a.w) == skip_id) continue;
    sdf_float4 b = sdf_load4(tris, 3 * k + 1), c = sdf_load4(tris, 3 * k + 2);
    sdf_intersect_values(o, d, tmin, make_float3(a.x, a.y, a.z), make_float3(b.x, b.y, b.z),
                         make_float3(c.x, c.y, c.z), sdf_as_int(a.w), hit);
  }
}

/* Finds the nearest triangle hit along o + t d with tmin < t, skipping triangle skip_id (the
 * point's own face; -1 for none). Returns the hit with t = INFINITY when nothing is hit.
 * nodes and tris are the SdfBvhNode and SdfTriangle arrays seen as 16-byte units, the root in
 * slot `root` (0 for the host's trees, SDF_LBVH_ROOT for the device's).
 *
 * Memory is read in 16-byte loads: a node as two (its box's lo with `first`, hi with `count`),
 * a triangle as three (v0 with id, e1, e2). On an H100 the per-ray kernel was bound by the L1
 * cache's request rate (Nsight Compute on a CUDA build of this header, bench/cuda_cast: L1 89%
 * busy, 6.6 tag requests per warp-wide load, the rays of a warp reading different nodes), and
 * a 16-byte load costs the same requests as a 4-byte one. Both children of a node are read
 * together, and each child's first and count come with its box, so no node is read twice.
 *
 * A leaf child is tested where its parent is read, not descended into: the loop only ever
 * stands on inner nodes, and the stack holds inner nodes alone, as (first child, bits of the
 * entry distance) in 8 bytes. On an H100 (trees of one-triangle leaves made on the device,
 * 30 rays) this cut the cast from 49.0 to 40.2 ms at 1.21M faces and from 34.1 to 27.8 at 832k
 * (64 rays: 110.5 to 97.0), against descending into leaves with 16-byte stack entries. */
SDF_INLINE SdfHit sdf_bvh_closest_hit_units(SDF_GLOBAL const sdf_float4* nodes,
                                            SDF_GLOBAL const sdf_float4* tris, sdf_int32 root,
                                            float3 o, float3 d, float tmin, sdf_int32 skip_id) {
  SdfHit hit = sdf_no_hit();
  float3 inv_d = sdf_safe_inverse(d, o);
  /* Slab distances as one fused multiply-add each: on an H100 (1.21M faces, two runs) the
   * cast took 39.6 ms against 40.2 with (lo - o) * inv_d. */
  float3 o_inv = make_float3(o.x * inv_d.x, o.y * inv_d.y, o.z * inv_d.z);
  sdf_int2 stack[SDF_BVH_STACK_SIZE];
  int sp = 0;
  sdf_float4 lo = sdf_load4(nodes, 2 * root), hi = sdf_load4(nodes, 2 * root + 1);
  if (sdf_box_entry_fused(make_float3(lo.x, lo.y, lo.z), make_float3(hi.x, hi.y, hi.z), o_inv,
                          inv_d, hit.t) == INFINITY)
    return hit;
  sdf_int32 first = sdf_as_int(lo.w);
  if (sdf_as_int(hi.w) > 0) {
    sdf_bvh_leaf_hits(tris, first, sdf_as_int(hi.w), o, d, tmin, skip_id, &hit);
    return hit;
  }
  for (;;) {
    sdf_float4 l_lo = sdf_load4(nodes, 2 * first), l_hi = sdf_load4(nodes, 2 * first + 1);
    sdf_float4 r_lo = sdf_load4(nodes, 2 * first + 2), r_hi = sdf_load4(nodes, 2 * first + 3);
    float t_left = sdf_box_entry_fused(make_float3(l_lo.x, l_lo.y, l_lo.z),
                                       make_float3(l_hi.x, l_hi.y, l_hi.z), o_inv, inv_d, hit.t);
    float t_right = sdf_box_entry_fused(make_float3(r_lo.x, r_lo.y, r_lo.z),
                                        make_float3(r_hi.x, r_hi.y, r_hi.z), o_inv, inv_d, hit.t);
    if (sdf_as_int(l_hi.w) > 0) {
      if (t_left != INFINITY)
        sdf_bvh_leaf_hits(tris, sdf_as_int(l_lo.w), sdf_as_int(l_hi.w), o, d, tmin, skip_id, &hit);
      t_left = INFINITY;
    }
    if (sdf_as_int(r_hi.w) > 0) {
      if (t_right != INFINITY && t_right <= hit.t)
        sdf_bvh_leaf_hits(tris, sdf_as_int(r_lo.w), sdf_as_int(r_hi.w), o, d, tmin, skip_id, &hit);
      t_right = INFINITY;
    }
    /* A leaf's hit may have put an inner child beyond reach (ties stay: see the pop). */
    if (t_left > hit.t) t_left = INFINITY;
    if (t_right > hit.t) t_right = INFINITY;
    if (t_left != INFINITY || t_right != INFINITY) {
      if (t_left == INFINITY) {
        first = sdf_as_int(r_lo.w);
      } else if (t_right == INFINITY) {
        first = sdf_as_int(l_lo.w);
      } else if (t_left <= t_right) {
        stack[sp++] = sdf_make_int2(sdf_as_int(r_lo.w), sdf_as_int(t_right));
        first = sdf_as_int(l_lo.w);
      } else {
        stack[sp++] = sdf_make_int2(sdf_as_int(l_lo.w), sdf_as_int(t_left));
        first = sdf_as_int(r_lo.w);
      }
      continue;
    }
    /* Pop the next subtree that can still hold a nearer hit (or an equally near one: ties
     * are decided by triangle id, see sdf_intersect_values). */
    for (;;) {
      if (sp == 0) return hit;
      --sp;
      if (sdf_as_float(stack[sp].y) <= hit.t) break;
    }
    first = stack[sp].x;
  }
}

/* The same on the typed arrays (the C++ tests). The kernels pass float4 arrays straight from
 * their arguments instead: through a cast pointer NVIDIA's compiler loads 4 bytes at a time. */
SDF_INLINE SdfHit sdf_bvh_closest_hit(SDF_GLOBAL const SdfBvhNode* nodes,
                                      SDF_GLOBAL const SdfTriangle* tris, float3 o, float3 d,
                                      float tmin, sdf_int32 skip_id) {
  return sdf_bvh_closest_hit_units((SDF_GLOBAL const sdf_float4*)nodes,
                                   (SDF_GLOBAL const sdf_float4*)tris, 0, o, d, tmin, skip_id);
}

SDF_KERNEL_END

#endif /* SDF_BVH_TRAVERSE_H */
