/* SPDX-License-Identifier: GPL-3.0-or-later */
/* A BVH built on the device: the host sends the mesh alone instead of a tree and points of its
 * own making (the cast makes the faces' points from the mesh: sdf_start_of_face in
 * sdf_kernels.cl). The faces' Morton codes and their sorted order are made here too
 * (sdf_lbvh_extent, sdf_lbvh_codes, then sdf_sort_kernels.cl; the tests check them against a
 * numpy reference).
 *
 * The tree is Karras's (2012): internal node i of the faces with area (n of them, sorted)
 * finds the range of keys it covers and where that range splits from the keys alone, all
 * nodes at once. Its layout is the host tree's (SdfBvhNode, children side by side) shifted by
 * one slot: the two children of internal node i sit in slots 2i + 2 and 2i + 3, the root in
 * slot SDF_LBVH_ROOT = 1 (sdf_layout.h says why). A node whose range holds at most
 * SDF_LBVH_LEAF_SIZE triangles is written as a leaf of them (its subtree's slots then stay
 * unused). Boxes are made bottom up, one launch per level of height: a node's box is made in
 * the launch after both children's, so every box read was written by an earlier
 * launch. (A first version climbed in one launch, the second child to arrive at a node making
 * its box from its sibling's: on an H100 a box could be read before its sibling's write had
 * landed, and 1 in 1.2M faces' values differed.) Every box grows by the host's margin
 * (bvh_margin.h), so this tree returns the hits of every other tree, bit for bit. */
#include "common/sdf_layout.h"
#include "common/sdf_morton.h"

/* Leaves of one triangle (no node collapsed): on an H100 (1.21M faces, two runs) the cast took
 * 48.9 ms with leaves of at most 1, 50.6-50.7 with 2, 53.4 with 3, 56.8 with 4, 63.0 with 6,
 * 69.3 with 8 (64 rays: 109.3, 113.5-113.6, 119.2, 126.4, 140.1, 154.1): Morton ranges make
 * looser leaves than SAH splits do. A build option may set it (benchmarks:
 * the test override opencl_extra_options="-DSDF_LBVH_LEAF_SIZE=4"). */
#ifndef SDF_LBVH_LEAF_SIZE
#define SDF_LBVH_LEAF_SIZE 1
#endif

/* Face f's box as the host's tree makes it (corners' min and max, made +0 at zero) and
 * whether it has area (its cross product is not zero: the host's test, to the bit). */
static inline int sdf_face_box(__global const float* vertices, __global const uint* triangles,
                               uint f, float3* lo, float3* hi, float* edge) {
  uint3 t = vload3(f, triangles);
  float3 a = vload3(t.x, vertices), b = vload3(t.y, vertices), c = vload3(t.z, vertices);
  float3 e1 = b - a, e2 = c - a;
  float3 n = sdf_cross(e1, e2);
  *lo = fmin(a, fmin(b, c)) + 0.0f;
  *hi = fmax(a, fmax(b, c)) + 0.0f;
  float3 m = fmax(fabs(e1), fabs(e2));
  *edge = fmax(m.x, fmax(m.y, m.z));
  return n.x != 0.0f || n.y != 0.0f || n.z != 0.0f;
}

/* The box of the faces with area (ordered ints: lo x, y, z, hi x, y, z), their longest edge
 * component and their count, into extent[0..7] (which starts as INT_MAX x 3, INT_MIN x 3,
 * 0, 0): per work group in local memory, then one atomic per group and entry. */
__kernel void sdf_lbvh_extent(__global const float* restrict vertices,
                              __global const uint* restrict triangles, uint faces,
                              __global int* extent) {
  __local int part[8];
  uint lid = get_local_id(0), f = get_global_id(0);
  if (lid < 8) part[lid] = lid < 3 ? INT_MAX : lid < 6 ? INT_MIN : 0;
  barrier(CLK_LOCAL_MEM_FENCE);
  float3 lo, hi;
  float edge;
  if (f < faces && sdf_face_box(vertices, triangles, f, &lo, &hi, &edge)) {
    atomic_min(&part[0], sdf_ordered_int(lo.x));
    atomic_min(&part[1], sdf_ordered_int(lo.y));
    atomic_min(&part[2], sdf_ordered_int(lo.z));
    atomic_max(&part[3], sdf_ordered_int(hi.x));
    atomic_max(&part[4], sdf_ordered_int(hi.y));
    atomic_max(&part[5], sdf_ordered_int(hi.z));
    atomic_max(&part[6], as_int(edge)); /* >= 0: its bits order as it does */
    atomic_inc(&part[7]);
  }
  barrier(CLK_LOCAL_MEM_FENCE);
  if (lid < 3) atomic_min(&extent[lid], part[lid]);
  else if (lid < 7) atomic_max(&extent[lid], part[lid]);
  else if (lid == 7) atomic_add(&extent[7], part[7]);
}

/* Face f's sort key: the 30-bit Morton code of its box
 * centre in the box of faces with area, 2^30 (after every code) for a face without area. */
__kernel void sdf_lbvh_codes(__global const float* restrict vertices,
                             __global const uint* restrict triangles, uint faces,
                             __global const int* restrict extent, __global uint* restrict keys,
                             __global uint* restrict values) {
  uint f = get_global_id(0);
  if (f >= faces) return;
  float3 all_lo = make_float3(sdf_ordered_float(extent[0]), sdf_ordered_float(extent[1]),
                              sdf_ordered_float(extent[2]));
  float3 all_hi = make_float3(sdf_ordered_float(extent[3]), sdf_ordered_float(extent[4]),
                              sdf_ordered_float(extent[5]));
  float3 scale = 1023.0f / fmax(all_hi - all_lo, (float3)(1e-30f));
  float3 lo, hi;
  float edge;
  uint key = 1u << 30;
  if (sdf_face_box(vertices, triangles, f, &lo, &hi, &edge)) {
    float3 centre = (lo + hi) * 0.5f;
    uint3 c = convert_uint3(clamp((centre - all_lo) * scale, 0.0f, 1023.0f));
    key = sdf_morton_30(c.x, c.y, c.z);
  }
  keys[f] = key;
  values[f] = f;
}

/* Triangle record k (SdfTriangle as three 16-byte units) of face order[k], k < count, as the
 * host writes them (bvh.cpp: write_triangles). */
__kernel void sdf_lbvh_triangles(__global const float* restrict vertices,
                                 __global const uint* restrict triangles,
                                 __global const uint* restrict order, uint count,
                                 __global float4* restrict tris) {
  uint k = get_global_id(0);
  if (k >= count) return;
  uint f = order[k];
  uint3 t = vload3(f, triangles);
  float3 v0 = vload3(t.x, vertices);
  float3 e1 = vload3(t.y, vertices) - v0, e2 = vload3(t.z, vertices) - v0;
  tris[3 * k] = (float4)(v0, as_float((int)f));
  tris[3 * k + 1] = (float4)(e1, 0.0f);
  tris[3 * k + 2] = (float4)(e2, 0.0f);
}

/* Karras's delta: the length of the common prefix of keys i and j, the key being the code
 * followed by the index (so equal codes still differ); -1 outside [0, n). */
static inline int sdf_lbvh_delta(__global const uint* codes, int n, int i, int j) {
  if (j < 0 || j >= n) return -1;
  uint a = codes[i], b = codes[j];
  if (a != b) return (int)clz(a ^ b);
  return 32 + (int)clz((uint)i ^ (uint)j);
}

/* Internal node i < n - 1: its range of triangles (first, count) and its children (an
 * internal node j as j, leaf k as ~k). slot_of holds where each node's record goes: leaves at
 * [0, n), internal nodes at n + i. Marks the node not yet made (made_in: the launch of
 * sdf_lbvh_level that made it). */
__kernel void sdf_lbvh_inner(__global const uint* restrict codes, int n,
                             __global int* restrict slot_of, __global int4* restrict inner,
                             __global int* restrict made_in) {
  int i = (int)get_global_id(0);
  if (n == 1 && i == 0) slot_of[0] = SDF_LBVH_ROOT;  /* one triangle: the root is its leaf */
  if (i >= n - 1) return;
  int d = sdf_lbvh_delta(codes, n, i, i + 1) > sdf_lbvh_delta(codes, n, i, i - 1) ? 1 : -1;
  int below = sdf_lbvh_delta(codes, n, i, i - d);
  int reach = 2;
  while (sdf_lbvh_delta(codes, n, i, i + reach * d) > below) reach *= 2;
  int l = 0;
  for (int t = reach / 2; t >= 1; t /= 2)
    if (sdf_lbvh_delta(codes, n, i, i + (l + t) * d) > below) l += t;
  int j = i + l * d;
  int shared = sdf_lbvh_delta(codes, n, i, j);
  int s = 0;
  int t = l;
  do {
    t = (t + 1) / 2;
    if (sdf_lbvh_delta(codes, n, i, i + (s + t) * d) > shared) s += t;
  } while (t > 1);
  int split = i + s * d + min(d, 0);
  int first = min(i, j), last = max(i, j);
  int left = first == split ? ~split : split;
  int right = last == split + 1 ? ~(split + 1) : split + 1;
  slot_of[left < 0 ? ~left : n + left] = 2 * i + 1 + SDF_LBVH_ROOT;
  slot_of[right < 0 ? ~right : n + right] = 2 * i + 2 + SDF_LBVH_ROOT;
  inner[i] = (int4)(first, last - first + 1, left, right);
  made_in[i] = INT_MAX;
  if (i == 0) slot_of[n] = SDF_LBVH_ROOT;
}

static inline void sdf_lbvh_store(__global float4* nodes, int slot, float3 lo, int first,
                                  float3 hi, int count) {
  nodes[2 * slot] = (float4)(lo, as_float(first));
  nodes[2 * slot + 1] = (float4)(hi, as_float(count));
}

/* Leaf k < n, triangle order[k]: the corners' min and max made +0 at zero (as the host's
 * boxes), grown by margin. Growing each leaf and taking unions gives the bits of growing the
 * unions, as the host does: rounding is monotonic. */
__kernel void sdf_lbvh_leaves(__global const float* restrict vertices,
                              __global const uint* restrict triangles,
                              __global const uint* restrict order, int n,
                              __global const int* restrict slot_of, float margin,
                              __global float4* restrict nodes) {
  int k = (int)get_global_id(0);
  if (k >= n) return;
  float3 lo, hi;
  float edge;
  sdf_face_box(vertices, triangles, order[k], &lo, &hi, &edge);
  sdf_lbvh_store(nodes, slot_of[k], lo - margin, k, hi + margin, 1);
}

/* Launch `level` (1, 2, ...): every internal node whose children were both made before this
 * launch (leaves count as made in launch 0) makes its record, a leaf of its range when that
 * holds at most SDF_LBVH_LEAF_SIZE triangles. A child made in this very launch reads as not
 * yet made (its made_in is INT_MAX or `level`), so no box is read in the launch that writes
 * it. */
__kernel void sdf_lbvh_level(int n, int level, __global const int* restrict slot_of,
                             __global const int4* restrict inner, __global int* made_in,
                             __global float4* nodes) {
  int i = (int)get_global_id(0);
  if (i >= n - 1 || made_in[i] != INT_MAX) return;
  int4 node = inner[i];
  if (node.z >= 0 && made_in[node.z] >= level) return;
  if (node.w >= 0 && made_in[node.w] >= level) return;
  int left = 2 * i + 1 + SDF_LBVH_ROOT;
  float4 l_lo = nodes[2 * left], l_hi = nodes[2 * left + 1];
  float4 r_lo = nodes[2 * left + 2], r_hi = nodes[2 * left + 3];
  float3 lo = fmin(l_lo.xyz, r_lo.xyz), hi = fmax(l_hi.xyz, r_hi.xyz);
  int slot = slot_of[n + i];
  if (node.y <= SDF_LBVH_LEAF_SIZE)
    sdf_lbvh_store(nodes, slot, lo, node.x, hi, node.y);
  else
    sdf_lbvh_store(nodes, slot, lo, left, hi, 0);
  made_in[i] = level;
}
