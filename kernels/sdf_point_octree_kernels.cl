/* SPDX-License-Identifier: GPL-3.0-or-later */
/* Projected-points smoothing with its octree built on the device, level by level (host side:
 * native/opencl/opencl_projected.cpp). Each level, every point still in a branching node adds
 * itself to one of that node's eight child bins; the host reads the bins back, makes the
 * children (smoothing_projected.h's rules, the same as the host builder's) and says which of
 * them branch. No sort: sums are fixed point (sdf_fixed_value), so atomics add them in any
 * order to the same bits, and minima are exact.
 *
 * A work item takes `span` points, a group's items interleaved over the group's stretch (so a
 * warp's loads are contiguous); points in the mesh's order are near each other, so an item's
 * points mostly fall in one bin and it adds them up before one set of atomics per run. */
#include "sdf_smooth_projected.h"

/* A bin: 4 uints (host: ProjectedBin). The 64-bit sum is added as two 32-bit halves, the carry
 * of the low half added to the high one (exact: additions commute), so devices without 64-bit
 * atomics run it too. Values are >= 0, so their float bits order as the values do (minimum). */
#define SDF_BIN_COUNT 0
#define SDF_BIN_SUM_LOW 1
#define SDF_BIN_SUM_HIGH 2
#define SDF_BIN_MIN 3

void sdf_bin_add(__global uint* bins, int bin, uint count, ulong sum, uint min_bits) {
  if (count == 0) return;
  __global uint* b = bins + 4 * bin;
  atomic_add(b + SDF_BIN_COUNT, count);
  uint low = (uint)sum;
  uint old = atomic_add(b + SDF_BIN_SUM_LOW, low);
  uint high = (uint)(sum >> 32) + (old + low < old ? 1u : 0u);
  if (high != 0) atomic_add(b + SDF_BIN_SUM_HIGH, high);
  atomic_min(b + SDF_BIN_MIN, min_bits);
}

/* Float bits as a uint that orders as the floats do (negative ones too): the points' box. */
uint sdf_ordered_bits(float x) {
  uint b = as_uint(x);
  return (b & 0x80000000u) ? ~b : (b | 0x80000000u);
}

/* The k-th point of this work item's span, or count (none). */
uint sdf_span_point(uint k, uint span) {
  return (uint)get_group_id(0) * (uint)get_local_size(0) * span + (uint)get_local_id(0) +
         k * (uint)get_local_size(0);
}

/* Each point moved inward by half its value (points: xyz and the value in w, the gather's
 * input). Points with an axis (members) go into bin 0, the root, and into its sums and the box
 * of all members (box: 3 minima, 3 maxima as sdf_ordered_bits); the others get bin -1. */
__kernel void sdf_projected_points(uint count, uint span, __global const float* origins,
                                   __global const float* axes, __global const float* values,
                                   int shift, __global float4* points, __global int* bin_of,
                                   __global uint* box, __global uint* root) {
  uint members = 0, min_bits = 0xffffffffu;
  ulong sum = 0;
  float3 lo = (float3)(INFINITY), hi = (float3)(-INFINITY);
  for (uint k = 0; k < span; ++k) {
    uint i = sdf_span_point(k, span);
    if (i >= count) break;
    float3 origin = vload3(i, origins), axis = vload3(i, axes);
    float value = values[i];
    float3 p = sdf_project_point(origin, axis, value);
    points[i] = (float4)(p, value);
    int member = axis.x != 0.0f || axis.y != 0.0f || axis.z != 0.0f;
    bin_of[i] = member ? 0 : -1;
    if (!member) continue;
    ++members;
    sum += sdf_fixed_value(value, shift);
    min_bits = min(min_bits, as_uint(value));
    lo = fmin(lo, p);
    hi = fmax(hi, p);
  }
  if (members == 0) return;
  sdf_bin_add(root, 0, members, sum, min_bits);
  atomic_min(box + 0, sdf_ordered_bits(lo.x));
  atomic_min(box + 1, sdf_ordered_bits(lo.y));
  atomic_min(box + 2, sdf_ordered_bits(lo.z));
  atomic_max(box + 3, sdf_ordered_bits(hi.x));
  atomic_max(box + 4, sdf_ordered_bits(hi.y));
  atomic_max(box + 5, sdf_ordered_bits(hi.z));
}

/* One level: a point in bin b of the level above (bin_of) whose node branches (slot_of_bin[b]
 * = the node's slot >= 0) goes into bin slot * 8 + octant of this level; the others leave
 * the build (bin -1). */
__kernel void sdf_projected_bin(uint count, uint span, __global const float4* points,
                                int level, int depth, float corner_x, float corner_y,
                                float corner_z, float scale, uint cells, int shift,
                                __global const int* slot_of_bin, __global int* bin_of,
                                __global uint* bins) {
  int run = -1;
  uint run_count = 0, run_min = 0xffffffffu;
  ulong run_sum = 0;
  for (uint k = 0; k < span; ++k) {
    uint i = sdf_span_point(k, span);
    if (i >= count) break;
    int b = bin_of[i];
    if (b < 0) continue;
    int slot = slot_of_bin[b];
    if (slot < 0) {
      bin_of[i] = -1;
      continue;
    }
    float4 p = points[i];
    uint octant = sdf_point_octant(sdf_point_cell(p.x, corner_x, scale, cells),
                                   sdf_point_cell(p.y, corner_y, scale, cells),
                                   sdf_point_cell(p.z, corner_z, scale, cells), level, depth);
    int bin = slot * 8 + (int)octant;
    bin_of[i] = bin;
    if (bin != run) {
      if (run >= 0) sdf_bin_add(bins, run, run_count, run_sum, run_min);
      run = bin;
      run_count = 0;
      run_sum = 0;
      run_min = 0xffffffffu;
    }
    ++run_count;
    run_sum += sdf_fixed_value(p.w, shift);
    run_min = min(run_min, as_uint(p.w));
  }
  if (run >= 0) sdf_bin_add(bins, run, run_count, run_sum, run_min);
}
