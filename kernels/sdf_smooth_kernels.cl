/* SPDX-License-Identifier: GPL-3.0-or-later */
/* The OpenCL versions of two smoothing methods (paper 4.4). Everything they compute lives in
 * sdf_smooth_projected.h and sdf_smooth_texture.h, which the CPU compiles as C++: these entry
 * points only pick their point or texel. Host side: native/opencl/opencl_smoothing.cpp. */
#include "sdf_smooth_projected.h"
#include "sdf_smooth_texture.h"

/* Projected points, one iteration: one work item per point of [first, first + count).
 * points: the projected point (xyz) and its value (w), one aligned 16-byte load a point. */
__kernel void sdf_smooth_projected(__global const SdfPointNode* nodes,
                                   __global const float4* points, float lo, float hi,
                                   uint first, uint count, __global float* next) {
  uint gid = get_global_id(0);
  if (gid >= count) return;
  uint i = first + gid;
  float4 p = points[i];
  next[i] = sdf_smooth_projected_point(nodes, p.xyz, p.w, lo, hi);
}

/* Texture space, one ring of dilation: one work item per texel. */
__kernel void sdf_texture_dilate(int width, int height, __global const int* island,
                                 __global const float* value, __global int* island_out,
                                 __global float* value_out) {
  int x = (int)get_global_id(0), y = (int)get_global_id(1);
  if (x >= width || y >= height) return;
  sdf_dilate_texel(x, y, width, height, island, value, island_out, value_out);
}

/* Texture space, the row pass: value in (each texel weighing 1, as on the CPU), the weighted
 * sums out. */
__kernel void sdf_texture_blur_rows(int width, int height, __global const int* island,
                                    __global const float* value, __global const float* taps,
                                    int radius, float inv_range, __global float* row_value,
                                    __global float* row_weight) {
  int x = (int)get_global_id(0), y = (int)get_global_id(1);
  if (x >= width || y >= height) return;
  size_t o = (size_t)y * width;
  float sv, sw;
  sdf_blur_texel(x, width, 1, island + o, value + o, 0, taps, radius, inv_range, &sv, &sw);
  row_value[o + x] = sv;
  row_weight[o + x] = sw;
}

/* Texture space, the column pass over the row pass's sums, then the weighted mean clamped to
 * [lo, hi] (0 where no island is). */
__kernel void sdf_texture_blur_columns(int width, int height, __global const int* island,
                                       __global const float* row_value,
                                       __global const float* row_weight,
                                       __global const float* taps, int radius, float inv_range,
                                       float lo, float hi, __global float* blurred) {
  int x = (int)get_global_id(0), y = (int)get_global_id(1);
  if (x >= width || y >= height) return;
  float sv, sw;
  sdf_blur_texel(y, height, (size_t)width, island + x, row_value + x, row_weight + x, taps, radius,
                 inv_range, &sv, &sw);
  size_t t = (size_t)y * width + x;
  blurred[t] = island[t] >= 0 ? sdf_blur_normalize(sv, sw, lo, hi) : sv;
}
