/* SPDX-License-Identifier: GPL-3.0-or-later */
/* Smoothing in texture space (paper 4.4), the per-texel parts: one texel of one ring of
 * dilation, and one texel of one 1-D pass of the island-masked Gaussian. The host
 * (native/smoothing_texture.cpp) rasterises and reads back; the CPU calls these functions as
 * C++ in loops over rows and columns, the OpenCL kernels of sdf_smooth_kernels.cl call them
 * as OpenCL C, one work item per texel. Images are row-major, `width` texels a row. */
#ifndef SDF_SMOOTH_TEXTURE_H
#define SDF_SMOOTH_TEXTURE_H

#include "sdf_compat.h"

SDF_KERNEL_BEGIN

/* One ring of dilation at texel (x, y): an empty texel (island < 0) next to texels with a
 * value takes the smallest island among its 8 neighbours and the mean of its neighbours of
 * that island; any other texel is copied. */
SDF_INLINE void sdf_dilate_texel(int x, int y, int width, int height,
                                 SDF_GLOBAL const sdf_int32* island, SDF_GLOBAL const float* value,
                                 SDF_GLOBAL sdf_int32* island_out, SDF_GLOBAL float* value_out) {
  size_t t = (size_t)y * width + x;
  island_out[t] = island[t];
  value_out[t] = value[t];
  if (island[t] >= 0) return;
  sdf_int32 best = -1;
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx) {
      int nx = x + dx, ny = y + dy;
      if (nx < 0 || ny < 0 || nx >= width || ny >= height) continue;
      sdf_int32 i = island[(size_t)ny * width + nx];
      if (i >= 0 && (best < 0 || i < best)) best = i;
    }
  if (best < 0) return;
  sdf_wide sum = 0.0f;
  int count = 0;
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx) {
      int nx = x + dx, ny = y + dy;
      if (nx < 0 || ny < 0 || nx >= width || ny >= height) continue;
      size_t n = (size_t)ny * width + nx;
      if (island[n] != best) continue;
      sum += value[n];
      ++count;
    }
  island_out[t] = best;
  value_out[t] = (float)(sum / count);
}

/* Texel i of a line of `count` texels `stride` apart (island, value_sum, weight_sum point at
 * the line's first texel): the sums over the taps within `radius` of the centre's island, of
 * taps[|j - i|] x value_sum and x weight_sum. In: value_sum / weight_sum per texel (for the
 * first pass, the value and a null weight_sum: 1 everywhere, with no array to fill). Bilateral (inv_range > 0): taps also weigh
 * exp(-1/2 ((v_tap - v_centre) * inv_range)^2), v = value_sum / weight_sum. An empty centre
 * (island < 0) gives 0 and 0. */
SDF_INLINE void sdf_blur_texel(int i, int count, size_t stride, SDF_GLOBAL const sdf_int32* island,
                               SDF_GLOBAL const float* value_sum, SDF_GLOBAL const float* weight_sum,
                               SDF_GLOBAL const float* taps, int radius, float inv_range,
                               float* value_out, float* weight_out) {
  size_t t = (size_t)i * stride;
  sdf_int32 own = island[t];
  if (own < 0) {
    *value_out = 0.0f;
    *weight_out = 0.0f;
    return;
  }
  int lo = i - radius > 0 ? i - radius : 0;
  int hi = i + radius < count - 1 ? i + radius : count - 1;
  float sv = 0.0f, sw = 0.0f;
  /* x / 1 and x * 1 are x: the first pass gives the same bits as with an array of ones. */
  if (inv_range > 0.0f) {
    float centre = weight_sum ? value_sum[t] / weight_sum[t] : value_sum[t];
    for (int j = lo; j <= hi; ++j) {
      size_t n = (size_t)j * stride;
      if (island[n] != own) continue;
      float wn = weight_sum ? weight_sum[n] : 1.0f;
      float d = (value_sum[n] / wn - centre) * inv_range;
      float w = taps[j > i ? j - i : i - j] * exp(-0.5f * d * d);
      sv += w * value_sum[n];
      sw += w * wn;
    }
  } else {
    for (int j = lo; j <= hi; ++j) {
      size_t n = (size_t)j * stride;
      if (island[n] != own) continue;
      float w = taps[j > i ? j - i : i - j];
      sv += w * value_sum[n];
      sw += weight_sum ? w * weight_sum[n] : w;
    }
  }
  *value_out = sv;
  *weight_out = sw;
}

/* A texel of an island after both passes: the weighted mean, clamped to the input's [lo, hi]
 * (the centre texel itself always counts, so weight > 0). */
SDF_INLINE float sdf_blur_normalize(float value_sum, float weight_sum, float lo, float hi) {
  return sdf_min(hi, sdf_max(lo, value_sum / weight_sum));
}

SDF_KERNEL_END

#endif /* SDF_SMOOTH_TEXTURE_H */
