/* SPDX-License-Identifier: GPL-3.0-or-later */
/* Projected-points smoothing with its octree built on the device, level by level (host side:
 * native/opencl/opencl_projected.cpp). Each level, every point still in a branching node adds
 * itself to one of that node's eight child bins; the host reads the bins back, makes the
 * children (smoothing_projected.h's rules, the same as the host builder's) and says which of
 * them branch. No sort: sums are fixed point (sdf_fixed_value), so atomics add them in any
 * order to the same bits, and minima are exact.
 *
 * Atomics on a few addresses from every work item serialise (on an H100 the root's eight bins
 * took 3.3 ms a level that way, 0.07 ms as below), so sums meet in steps: a work item takes
 * `span` points (a group's items interleaved over the group's stretch, so a warp's loads are
 * contiguous) and, as points in the mesh's order are near each other, adds runs of them in one
 * bin in registers; the group's items then meet in local memory; one set of global atomics per
 * group and bin is left. */
#include "smooth/sdf_smooth_projected.h"

/* A bin: 4 uints (host: ProjectedBin). The 64-bit sum is added as two 32-bit halves, the carry
 * of the low half added to the high one (exact: additions commute), so devices without 64-bit
 * atomics run it too. Values are >= 0, so their float bits order as the values do (minimum),
 * once -0 is taken as +0 (its bits are the largest: a node of -0 and 0.5 had minimum 0.5). */
#define SDF_BIN_COUNT 0
#define SDF_BIN_SUM_LOW 1
#define SDF_BIN_SUM_HIGH 2
#define SDF_BIN_MIN 3

uint sdf_value_bits(float value) { return as_uint(value) & 0x7fffffffu; }

/* OpenCL 1.2 functions take one address space per pointer: the same body for both. */
#define SDF_BIN_ADD(b, count, sum, min_bits)                                        \
  do {                                                                              \
    atomic_add((b) + SDF_BIN_COUNT, (count));                                       \
    uint low_ = (uint)(sum);                                                        \
    uint old_ = atomic_add((b) + SDF_BIN_SUM_LOW, low_);                            \
    uint high_ = (uint)((sum) >> 32) + (old_ + low_ < old_ ? 1u : 0u);              \
    if (high_ != 0) atomic_add((b) + SDF_BIN_SUM_HIGH, high_);                      \
    atomic_min((b) + SDF_BIN_MIN, (min_bits));                                      \
  } while (0)

void sdf_bin_add(__global uint* bins, int bin, uint count, ulong sum, uint min_bits) {
  if (count != 0) SDF_BIN_ADD(bins + 4 * bin, count, sum, min_bits);
}

/* A group's table of bins in local memory (`size` slots: keys, -1 for free, and 4 sums each),
 * found by open addressing on the bin; a run that finds it full goes out directly. */
void sdf_table_add(__local int* keys, __local uint* sums, uint size, __global uint* bins, int bin,
                   uint count, ulong sum, uint min_bits) {
  if (count == 0) return;
  uint slot = ((uint)bin * 2654435761u) % size;
  for (uint probe = 0; probe < size; ++probe) {
    int key = atomic_cmpxchg(keys + slot, -1, bin);
    if (key == -1 || key == bin) {
      SDF_BIN_ADD(sums + 4 * slot, count, sum, min_bits);
      return;
    }
    slot = (slot + 1) % size;
  }
  sdf_bin_add(bins, bin, count, sum, min_bits);
}

void sdf_table_clear(__local int* keys, __local uint* sums, uint size) {
  for (uint j = get_local_id(0); j < size; j += get_local_size(0)) {
    keys[j] = -1;
    sums[4 * j + SDF_BIN_COUNT] = 0;
    sums[4 * j + SDF_BIN_SUM_LOW] = 0;
    sums[4 * j + SDF_BIN_SUM_HIGH] = 0;
    sums[4 * j + SDF_BIN_MIN] = 0xffffffffu;
  }
  barrier(CLK_LOCAL_MEM_FENCE);
}

/* After every item of the group has added: each used slot to the global bins. */
void sdf_table_flush(__local int* keys, __local uint* sums, uint size, __global uint* bins) {
  barrier(CLK_LOCAL_MEM_FENCE);
  for (uint j = get_local_id(0); j < size; j += get_local_size(0))
    if (keys[j] >= 0)
      sdf_bin_add(bins, keys[j], sums[4 * j + SDF_BIN_COUNT],
                  (ulong)sums[4 * j + SDF_BIN_SUM_HIGH] << 32 | sums[4 * j + SDF_BIN_SUM_LOW],
                  sums[4 * j + SDF_BIN_MIN]);
}

/* Float bits as a uint that orders as the floats do (negative ones too): the points' box. */
uint sdf_ordered_bits(float x) {
  uint b = as_uint(x);
  return (b & 0x80000000u) ? ~b : (b | 0x80000000u);
}

/* The k-th point of this work item's span (count or more: none). */
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
  __local uint group_box[6];
  __local uint group_root[4];
  if (get_local_id(0) == 0) {
    for (int a = 0; a < 3; ++a) {
      group_box[a] = 0xffffffffu;
      group_box[3 + a] = 0u;
    }
    group_root[SDF_BIN_COUNT] = group_root[SDF_BIN_SUM_LOW] = group_root[SDF_BIN_SUM_HIGH] = 0u;
    group_root[SDF_BIN_MIN] = 0xffffffffu;
  }
  barrier(CLK_LOCAL_MEM_FENCE);
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
    min_bits = min(min_bits, sdf_value_bits(value));
    lo = fmin(lo, p);
    hi = fmax(hi, p);
  }
  if (members != 0) {
    SDF_BIN_ADD(group_root, members, sum, min_bits);
    atomic_min(group_box + 0, sdf_ordered_bits(lo.x));
    atomic_min(group_box + 1, sdf_ordered_bits(lo.y));
    atomic_min(group_box + 2, sdf_ordered_bits(lo.z));
    atomic_max(group_box + 3, sdf_ordered_bits(hi.x));
    atomic_max(group_box + 4, sdf_ordered_bits(hi.y));
    atomic_max(group_box + 5, sdf_ordered_bits(hi.z));
  }
  barrier(CLK_LOCAL_MEM_FENCE);
  if (get_local_id(0) != 0 || group_root[SDF_BIN_COUNT] == 0) return;
  sdf_bin_add(root, 0, group_root[SDF_BIN_COUNT],
              (ulong)group_root[SDF_BIN_SUM_HIGH] << 32 | group_root[SDF_BIN_SUM_LOW],
              group_root[SDF_BIN_MIN]);
  for (int a = 0; a < 3; ++a) {
    atomic_min(box + a, group_box[a]);
    atomic_max(box + 3 + a, group_box[3 + a]);
  }
}

/* One level: a point in bin b of the level above (bin_of) whose node branches (slot_of_bin[b]
 * = the node's slot >= 0) goes into bin slot * 8 + octant of this level; the others leave
 * the build (bin -1). keys and sums: the group's table of `table` slots (sdf_table_add). */
__kernel void sdf_projected_bin(uint count, uint span, __global const float4* points,
                                int level, int depth, float corner_x, float corner_y,
                                float corner_z, float scale, uint cells, int shift,
                                __global const int* slot_of_bin, __global int* bin_of,
                                __global uint* bins, __local int* keys, __local uint* sums,
                                uint table) {
  sdf_table_clear(keys, sums, table);
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
      if (run >= 0) sdf_table_add(keys, sums, table, bins, run, run_count, run_sum, run_min);
      run = bin;
      run_count = 0;
      run_sum = 0;
      run_min = 0xffffffffu;
    }
    ++run_count;
    run_sum += sdf_fixed_value(p.w, shift);
    run_min = min(run_min, sdf_value_bits(p.w));
  }
  if (run >= 0) sdf_table_add(keys, sums, table, bins, run, run_count, run_sum, run_min);
  sdf_table_flush(keys, sums, table, bins);
}
