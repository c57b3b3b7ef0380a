/* SPDX-License-Identifier: GPL-3.0-or-later */
/* The OpenCL versions of two smoothing methods (paper 4.4). Everything they compute lives in
 * sdf_smooth_projected.h and sdf_smooth_texture.h, which the CPU compiles as C++: these entry
 * points only pick their point or texel. Host side: native/opencl/opencl_smoothing.cpp. */
#include "smooth/sdf_smooth_projected.h"
#include "smooth/sdf_smooth_texture.h"

/* Projected points, one iteration: one work item per point of [first, first + count).
 * points: the projected point (xyz) and its value (w), one aligned 16-byte load a point. */
__kernel void sdf_smooth_projected(uint first, uint count, __global const SdfPointNode* nodes,
                                   __global const float4* points, float radius_scale, float lo,
                                   float hi, __global float* next) {
  uint gid = get_global_id(0);
  if (gid >= count) return;
  uint i = first + gid;
  float4 p = points[i];
  next[i] = sdf_smooth_projected_point(nodes, p.xyz, p.w, radius_scale, lo, hi);
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

#ifdef SDF_HAVE_DOUBLE
/* Texture space, drawing (where the device has double precision: texel coverage is computed
 * in double, as on the host). Before it: every texel empty and owned by no face. */
__kernel void sdf_texture_clear(uint texels, __global uint* owner, __global int* island,
                                __global float* value) {
  uint t = get_global_id(0);
  if (t >= texels) return;
  owner[t] = 0;
  island[t] = -1;
  value[t] = 0.0f;
}

/* The first drawing pass, one work item per face of [first, first + count) of m: each face's
 * rank to the texels it offers (sdf_face_offers_next), the largest kept. */
__kernel void sdf_texture_rank(uint first, uint count, uint m, int width, int height,
                               __global const float* uvs, __global uint* owner) {
  uint gid = get_global_id(0);
  if (gid >= count) return;
  SdfFaceOffers o;
  sdf_face_offers_start(first + gid, m, uvs, width, height, &o);
  while (sdf_face_offers_next(&o)) atomic_max(owner + o.texel, o.rank);
}

/* The second pass: each face writes its value and island where its rank won. triangles:
 * null for face values. */
__kernel void sdf_texture_draw(uint first, uint count, uint m, int width, int height,
                               __global const float* uvs, __global const float* values,
                               __global const uint* triangles, float lo, float hi,
                               __global const int* face_island, __global const uint* owner,
                               __global int* island, __global float* value) {
  uint gid = get_global_id(0);
  if (gid >= count) return;
  uint f = first + gid;
  sdf_texture_draw_face(f, m, uvs, width, height, values, triangles, lo, hi, face_island[f],
                        owner, island, value);
}

/* Read back, face values: out[f] from the blurred texels face f covers (values: the input,
 * kept where there is nothing to read). */
__kernel void sdf_texture_read_faces(uint first, uint count, int width, int height,
                                     __global const float* uvs, __global const int* face_island,
                                     __global const int* island, __global const float* blurred,
                                     float lo, float hi, __global const float* values,
                                     __global float* out) {
  uint gid = get_global_id(0);
  if (gid >= count) return;
  uint f = first + gid;
  out[f] = sdf_texture_read_face(f, uvs, width, height, face_island[f], island, blurred, lo, hi,
                                 values[f]);
}

/* Read back, vertex values, first step: every corner of faces [first, first + count) sampled
 * (sdf_texture_sample_corner; NaN: not sampled), 3 per face. */
__kernel void sdf_texture_sample_corners(uint first, uint count, int width, int height,
                                         __global const float* uvs,
                                         __global const int* face_island,
                                         __global const int* island,
                                         __global const float* blurred,
                                         __global float* samples) {
  uint gid = get_global_id(0);
  if (gid >= count) return;
  size_t f = first + gid;
  for (int c = 0; c < 3; ++c)
    samples[3 * f + c] = sdf_texture_sample_corner(uvs[6 * f + 2 * c], uvs[6 * f + 2 * c + 1],
                                                   width, height, face_island[f], island,
                                                   blurred);
}

/* Then each vertex of [first, first + count): the mean over its merged vertex's corners
 * (group_first, corners: CornerGroups; merged: per vertex its group, null for the vertex's
 * own), or its input value where none was sampled. */
__kernel void sdf_texture_read_vertices(uint first, uint count, __global const uint* merged,
                                        __global const uint* group_first,
                                        __global const uint* corners,
                                        __global const float* samples, float lo, float hi,
                                        __global const float* values, __global float* out) {
  uint gid = get_global_id(0);
  if (gid >= count) return;
  uint v = first + gid;
  uint k = merged ? merged[v] : v;
  out[v] = sdf_texture_vertex_mean(group_first[k], group_first[k + 1], corners, samples, lo, hi,
                                   values[v]);
}
#endif
