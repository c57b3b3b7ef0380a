/* SPDX-License-Identifier: GPL-3.0-or-later */
/* Per-point reduction of the kept ray lengths to one SDF value (paper 4.3; CGAL's rule). */
#ifndef SDF_REDUCE_H
#define SDF_REDUCE_H

#include "ray/sdf_rays.h"

SDF_KERNEL_BEGIN

/* Sorts values ascending, carrying companions along. Insertion sort: n is a ray count (tens),
 * and it needs no extra memory in a kernel. */
SDF_INLINE void sdf_sort_pairs(float* values, float* companions, int n) {
  for (int i = 1; i < n; ++i) {
    float v = values[i], c = companions[i];
    int j = i - 1;
    while (j >= 0 && values[j] > v) {
      values[j + 1] = values[j];
      companions[j + 1] = companions[j];
      --j;
    }
    values[j + 1] = v;
    companions[j + 1] = c;
  }
}

/* Median of sorted values; the mean of the two middle ones for an even count (as CGAL). */
SDF_INLINE float sdf_median_sorted(const float* sorted, int n) {
  return (n % 2) ? sorted[n / 2] : 0.5f * (sorted[n / 2 - 1] + sorted[n / 2]);
}

/* Paper and Shapira et al.: keep lengths within one (population) standard deviation of the
 * median, then average them with weight 1 / angle to the cone axis, the angle floored at
 * angle_floor (sdf_angle_floor). Sorts lengths (and angles with them) in place. */
SDF_INLINE float sdf_reduce_paper(float* lengths, float* angles, int n, float angle_floor) {
  sdf_sort_pairs(lengths, angles, n);
  float median = sdf_median_sorted(lengths, n);
  float mean = 0.0f;
  for (int i = 0; i < n; ++i) mean += lengths[i];
  mean /= (float)n;
  float variance = 0.0f;
  for (int i = 0; i < n; ++i) variance += (lengths[i] - mean) * (lengths[i] - mean);
  /* The bound is inclusive and given a relative hair of slack: with two lengths both lie
   * exactly one deviation from the median, and rounding (which differs between devices) must
   * not decide which one survives. */
  float bound = sqrt(variance / (float)n) * (1.0f + 1e-5f);
  float sum_w = 0.0f, sum_wl = 0.0f;
  for (int i = 0; i < n; ++i) {
    if (fabs(lengths[i] - median) <= bound) {
      /* The paper's weight 1 / angle, taken relative to 1 / angle_floor (the same weighted
       * mean): in (0, 1], so w * length never overflows where 1 / angle (up to 1e30 for
       * the narrowest cones) times a long length did. */
      float w = angle_floor / fmax(angles[i], angle_floor);
      sum_w += w;
      sum_wl += w * lengths[i];
    }
  }
  return sum_w > 0.0f ? sum_wl / sum_w : median;
}

/* CGAL's remove_outliers_and_calculate_sdf_value (SDF_calculation.h): keep lengths within
 * 1.5 median absolute deviations of the median, plain mean. scratch holds n floats. */
SDF_INLINE float sdf_reduce_cgal(float* lengths, float* scratch, int n) {
  if (n == 1) return lengths[0];
  sdf_sort_pairs(lengths, scratch, n);
  float median = sdf_median_sorted(lengths, n);
  for (int i = 0; i < n; ++i) scratch[i] = fabs(lengths[i] - median);
  /* Sort the deviations alone: companions are the deviations themselves. */
  for (int i = 1; i < n; ++i) {
    float v = scratch[i];
    int j = i - 1;
    while (j >= 0 && scratch[j] > v) {
      scratch[j + 1] = scratch[j];
      --j;
    }
    scratch[j + 1] = v;
  }
  float mad = sdf_median_sorted(scratch, n);
  float sum = 0.0f;
  int kept = 0;
  for (int i = 0; i < n; ++i) {
    if (fabs(lengths[i] - median) <= 1.5f * mad) {
      sum += lengths[i];
      ++kept;
    }
  }
  return sum != 0.0f ? sum / (float)kept : median;
}

/* One point's value from its n kept lengths, or -1 when no ray was kept. angles and scratch
 * are clobbered. */
SDF_INLINE float sdf_reduce(int sampling, float* lengths, float* angles, int n, float angle_floor) {
  if (n == 0) return -1.0f;
  if (sampling == SDF_SAMPLING_CGAL) return sdf_reduce_cgal(lengths, angles, n);
  return sdf_reduce_paper(lengths, angles, n, angle_floor);
}

SDF_KERNEL_END

#endif /* SDF_REDUCE_H */
