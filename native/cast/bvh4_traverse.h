// SPDX-License-Identifier: GPL-3.0-or-later
// Nearest-hit traversal of the 4-wide BVH with SSE (x86-64 baseline, no special flags): the
// same answers as kernels/traverse/sdf_bvh_traverse.h, which the C++ tests check ray by ray.
// x86-64 only (SDF_HAVE_BVH4_SSE); elsewhere the CPU engine casts the binary tree.
#pragma once

#include "accel/bvh4.h"
#include "ray/sdf_intersect.h"
#include "util/cpu_features.h"

#define SDF_HAVE_BVH4_SSE SDF_X86_SIMD

#if SDF_HAVE_BVH4_SSE
#include <xmmintrin.h>

namespace sdf {

inline kern::SdfHit bvh4_closest_hit(const Bvh4& bvh, glm::vec3 o, glm::vec3 d, float tmin,
                                     std::int32_t skip_id) {
  kern::SdfHit hit{INFINITY, 0.0f, -1};
  if (bvh.empty()) return hit;
  const kern::SdfTriangle* tris = bvh.triangles->data();
  const glm::vec3 inv = kern::sdf_safe_inverse(d, o);
  // Per axis, the plane a ray meets first is lo when it travels up the axis, hi otherwise;
  // choosing once per ray (not min/max per box) also makes empty slots (lo = +inf, hi = -inf)
  // give near > far.
  const bool neg_x = inv.x < 0.0f, neg_y = inv.y < 0.0f, neg_z = inv.z < 0.0f;
  const __m128 inv_x = _mm_set1_ps(inv.x), inv_y = _mm_set1_ps(inv.y), inv_z = _mm_set1_ps(inv.z);
  const __m128 o_inv_x = _mm_set1_ps(o.x * inv.x), o_inv_y = _mm_set1_ps(o.y * inv.y),
               o_inv_z = _mm_set1_ps(o.z * inv.z);
  const __m128 zero = _mm_setzero_ps();

  struct Entry {
    std::int32_t child, count;
    float t;
  };
  // Each visit pushes at most 3 more than it pops; the tree is at most ~60 levels deep.
  Entry stack[256];
  int sp = 0;
  stack[sp++] = Entry{0, 0, 0.0f};
  while (sp > 0) {
    const Entry e = stack[--sp];
    if (e.t > hit.t) continue;  // equal may still hold a tie won by a smaller id
    if (e.child < 0) {
      const std::int32_t first = ~e.child;
      for (std::int32_t k = first; k < first + e.count; ++k)
        if (tris[k].id != skip_id) kern::sdf_intersect_triangle(o, d, tmin, &tris[k], &hit);
      continue;
    }
    const Bvh4Node& n = bvh.nodes[e.child];
    const __m128 near_x =
        _mm_sub_ps(_mm_mul_ps(_mm_load_ps(neg_x ? n.hi_x : n.lo_x), inv_x), o_inv_x);
    const __m128 near_y =
        _mm_sub_ps(_mm_mul_ps(_mm_load_ps(neg_y ? n.hi_y : n.lo_y), inv_y), o_inv_y);
    const __m128 near_z =
        _mm_sub_ps(_mm_mul_ps(_mm_load_ps(neg_z ? n.hi_z : n.lo_z), inv_z), o_inv_z);
    const __m128 far_x =
        _mm_sub_ps(_mm_mul_ps(_mm_load_ps(neg_x ? n.lo_x : n.hi_x), inv_x), o_inv_x);
    const __m128 far_y =
        _mm_sub_ps(_mm_mul_ps(_mm_load_ps(neg_y ? n.lo_y : n.hi_y), inv_y), o_inv_y);
    const __m128 far_z =
        _mm_sub_ps(_mm_mul_ps(_mm_load_ps(neg_z ? n.lo_z : n.hi_z), inv_z), o_inv_z);
    const __m128 t_near = _mm_max_ps(_mm_max_ps(near_x, near_y), _mm_max_ps(near_z, zero));
    const __m128 t_far =
        _mm_min_ps(_mm_min_ps(far_x, far_y), _mm_min_ps(far_z, _mm_set1_ps(hit.t)));
    int mask = _mm_movemask_ps(_mm_cmple_ps(t_near, t_far));
    if (mask == 0) continue;
    alignas(16) float entry[4];
    _mm_store_ps(entry, t_near);
    // Push the boxes hit, farthest first, so the nearest is popped next.
    Entry hits[4];
    int h = 0;
    while (mask) {
      const int i = __builtin_ctz(mask);
      mask &= mask - 1;
      Entry c{n.child[i], n.count[i], entry[i]};
      int j = h++;
      while (j > 0 && hits[j - 1].t < c.t) {
        hits[j] = hits[j - 1];
        --j;
      }
      hits[j] = c;
    }
    for (int i = 0; i < h; ++i) stack[sp++] = hits[i];
  }
  return hit;
}

}  // namespace sdf

#endif  // SDF_HAVE_BVH4_SSE
