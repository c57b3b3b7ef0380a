/* SPDX-License-Identifier: GPL-3.0-or-later */
/* Smoothing in texture space (paper 4.4), the per-face and per-texel parts: the texels a
 * face covers, drawing a face, one texel of one ring of dilation, one texel of one 1-D pass
 * of the island-masked Gaussian, and reading a face back. The CPU
 * (native/post/smoothing_texture.cpp) calls these functions as C++ in loops over faces, rows and
 * columns; the OpenCL kernels of sdf_smooth_kernels.cl call them as OpenCL C, one work item
 * per face or texel. Images are row-major, `width` texels a row. The per-face parts compute
 * in double (texel coverage must be the host's to the bit), so devices without double
 * precision do not have them. */
#ifndef SDF_SMOOTH_TEXTURE_H
#define SDF_SMOOTH_TEXTURE_H

#include "common/sdf_compat.h"

SDF_KERNEL_BEGIN

#ifdef SDF_HAVE_DOUBLE

/* The texels a face covers: those whose centre (x + 0.5, y + 0.5) lies inside its UV
 * triangle in texel units (u * width, v * height). A centre on an edge belongs to one side
 * only: the triangle is turned counter-clockwise, and an edge claims its points when its
 * direction (dx, dy) has dy > 0, or dy == 0 and dx < 0; the neighbour across it sees (-dx,
 * -dy). The edge functions are evaluated the same way from both sides, so the tie is exact,
 * and a texel is never covered by two faces of one island. Used as an iterator:
 * sdf_texel_walk_start, then while (sdf_texel_walk_next(&w)) { w.texel, w.b[0..2] }. */
typedef struct {
  double ax[3], ay[3], dx[3], dy[3]; /* edge i: from (ax, ay) along (dx, dy) */
  double inv;                        /* 1 / twice the area */
  int order[3];                      /* edge i lies opposite corner order[i] */
  int claims[3];
  int xmin, xmax, ymax, x, y; /* candidate texels, and the next one to test */
  int width;
  size_t texel; /* the covered texel sdf_texel_walk_next found ... */
  double b[3];  /* ... and its barycentric coordinates (of corners 0, 1, 2) */
} SdfTexelWalk;

SDF_INLINE double sdf_dmin(double a, double b) { return a < b ? a : b; }
SDF_INLINE double sdf_dmax(double a, double b) { return a > b ? a : b; }

/* uv: the face's 3 corners, (u, v) each. */
SDF_INLINE void sdf_texel_walk_start(SDF_GLOBAL const float* uv, int width, int height,
                                     SdfTexelWalk* w) {
  double x[3], y[3];
  for (int c = 0; c < 3; ++c) {
    x[c] = uv[2 * c] * (double)width;
    y[c] = uv[2 * c + 1] * (double)height;
  }
  /* Texels whose centre may lie inside, clamped in double (a UV far outside [0, 1] would
   * overflow an int). Most faces of a dense mesh cover no centre at all: they stop here,
   * before the edge set-up. */
  double xlo = sdf_dmin(x[0], sdf_dmin(x[1], x[2])), xhi = sdf_dmax(x[0], sdf_dmax(x[1], x[2]));
  double ylo = sdf_dmin(y[0], sdf_dmin(y[1], y[2])), yhi = sdf_dmax(y[0], sdf_dmax(y[1], y[2]));
  w->xmin = (int)sdf_dmax(0.0, sdf_dmin((double)width, ceil(xlo - 0.5)));
  w->xmax = (int)sdf_dmax(-1.0, sdf_dmin(width - 1.0, floor(xhi - 0.5)));
  w->y = (int)sdf_dmax(0.0, sdf_dmin((double)height, ceil(ylo - 0.5)));
  w->ymax = (int)sdf_dmax(-1.0, sdf_dmin(height - 1.0, floor(yhi - 0.5)));
  w->x = w->xmin;
  w->width = width;
  double area = (x[1] - x[0]) * (y[2] - y[0]) - (x[2] - x[0]) * (y[1] - y[0]);
  w->order[0] = 0;
  w->order[1] = 1;
  w->order[2] = 2;
  w->inv = 0.0;
  if (w->xmin > w->xmax || w->y > w->ymax || !(fabs(area) > 0.0)) {
    w->y = w->ymax + 1; /* nothing to visit */
    return;
  }
  if (area < 0.0) { /* clockwise (a mirrored island): walk it the other way round */
    w->order[1] = 2;
    w->order[2] = 1;
    area = -area;
  }
  for (int i = 0; i < 3; ++i) {
    int a = w->order[(i + 1) % 3], b = w->order[(i + 2) % 3];
    w->ax[i] = x[a];
    w->ay[i] = y[a];
    w->dx[i] = x[b] - x[a];
    w->dy[i] = y[b] - y[a];
    w->claims[i] = w->dy[i] > 0.0 || (w->dy[i] == 0.0 && w->dx[i] < 0.0);
  }
  w->inv = 1.0 / area;
}

/* Advances to the next covered texel (row by row, left to right); 0 when there is none. */
SDF_INLINE int sdf_texel_walk_next(SdfTexelWalk* w) {
  while (w->y <= w->ymax) {
    const double cy = w->y + 0.5;
    while (w->x <= w->xmax) {
      const int px = w->x++;
      const double cx = px + 0.5;
      double e[3];
      int inside = 1;
      for (int i = 0; i < 3 && inside; ++i) {
        /* Twice the area of (edge start, edge end, centre): > 0 on the inner side. */
        e[i] = w->dx[i] * (cy - w->ay[i]) - w->dy[i] * (cx - w->ax[i]);
        inside = e[i] > 0.0 || (e[i] == 0.0 && w->claims[i]);
      }
      if (!inside) continue;
      for (int i = 0; i < 3; ++i) w->b[w->order[i]] = e[i] * w->inv;
      w->texel = (size_t)w->y * w->width + px;
      return 1;
    }
    ++w->y;
    w->x = w->xmin;
  }
  return 0;
}

/* The texel under a UV point, or -1 outside the image. */
SDF_INLINE sdf_int64 sdf_texel_at(float u, float v, int width, int height) {
  double x = floor(u * (double)width), y = floor(v * (double)height);
  if (!(x >= 0.0 && x < width && y >= 0.0 && y < height)) return -1;
  return (sdf_int64)y * width + (sdf_int64)x;
}

/* The texel under a face's UV centroid (where a face too small to cover a texel centre
 * draws), or -1. */
SDF_INLINE sdf_int64 sdf_texel_of_centroid(SDF_GLOBAL const float* uv, int width, int height) {
  return sdf_texel_at((uv[0] + uv[2] + uv[4]) / 3.0f, (uv[1] + uv[3] + uv[5]) / 3.0f, width,
                      height);
}

/* What face f draws: face values, values[f] everywhere; vertex values (triangles given), its
 * corners' values interpolated at a covered texel and clamped to theirs, or their mean
 * clamped to [lo, hi] at its centroid. */
typedef struct {
  float a, b, c, vmin, vmax;
  int interpolate;
} SdfFaceDraw;

SDF_INLINE SdfFaceDraw sdf_face_draw(sdf_uint32 f, SDF_GLOBAL const float* values,
                                     SDF_GLOBAL const sdf_uint32* triangles) {
  SdfFaceDraw d;
  d.interpolate = triangles != 0;
  if (d.interpolate) {
    d.a = values[triangles[3 * (size_t)f]];
    d.b = values[triangles[3 * (size_t)f + 1]];
    d.c = values[triangles[3 * (size_t)f + 2]];
  } else {
    d.a = d.b = d.c = values[f];
  }
  d.vmin = sdf_min(d.a, sdf_min(d.b, d.c));
  d.vmax = sdf_max(d.a, sdf_max(d.b, d.c));
  return d;
}

/* At a covered texel of barycentric coordinates b. */
SDF_INLINE float sdf_face_draw_at(const SdfFaceDraw* d, const double* b) {
  if (!d->interpolate) return d->a;
  return sdf_min(d->vmax, sdf_max(d->vmin, (float)(b[0] * d->a + b[1] * d->b + b[2] * d->c)));
}

/* At the centroid of a face that covers no texel centre. */
SDF_INLINE float sdf_face_draw_centroid(const SdfFaceDraw* d, float lo, float hi) {
  if (!d->interpolate) return d->a;
  return sdf_min(hi, sdf_max(lo, (d->a + d->b + d->c) / 3.0f));
}

/* Drawing: where UV triangles overlap, a texel takes the face of the largest rank. A face
 * offers its rank to the texels it covers, rank m + 1 + f (above any centroid: the later
 * face wins), or, covering no texel centre, to the texel under its UV centroid, rank m - f
 * (the earlier wins, and only where no face covers): the image a serial loop in face order
 * gives, whatever order the faces run in. Rank 0: no face. The host draws in one pass (rank
 * and value in one 64-bit atomic maximum); a device in two: ranks by 32-bit atomic maximum,
 * then sdf_texture_draw_face writes where a face's rank won. All three walk a face's offers
 * with this iterator: sdf_face_offers_start, then while (sdf_face_offers_next(&o)) { o.texel,
 * o.rank, o.at_centroid, and at a covered texel o.walk.b }. */
typedef struct {
  SdfTexelWalk walk;
  SDF_GLOBAL const float* uv;
  int height;
  int covered; /* texels offered so far */
  int done;
  size_t texel;    /* the texel offered ... */
  sdf_uint32 rank; /* ... with this rank */
  int at_centroid; /* the centroid texel (else a covered one, barycentrics in walk.b) */
  sdf_uint32 cover_rank, centroid_rank;
} SdfFaceOffers;

SDF_INLINE void sdf_face_offers_start(sdf_uint32 f, sdf_uint32 m, SDF_GLOBAL const float* uvs,
                                      int width, int height, SdfFaceOffers* o) {
  o->uv = uvs + 6 * (size_t)f;
  o->height = height;
  o->covered = 0;
  o->done = 0;
  o->cover_rank = m + 1 + f;
  o->centroid_rank = m - f;
  sdf_texel_walk_start(o->uv, width, height, &o->walk);
}

SDF_INLINE int sdf_face_offers_next(SdfFaceOffers* o) {
  if (o->done) return 0;
  if (sdf_texel_walk_next(&o->walk)) {
    ++o->covered;
    o->texel = o->walk.texel;
    o->rank = o->cover_rank;
    o->at_centroid = 0;
    return 1;
  }
  o->done = 1;
  if (o->covered) return 0;
  sdf_int64 t = sdf_texel_of_centroid(o->uv, o->walk.width, o->height);
  if (t < 0) return 0;
  o->texel = (size_t)t;
  o->rank = o->centroid_rank;
  o->at_centroid = 1;
  return 1;
}

/* The value a face draws at an offer. */
SDF_INLINE float sdf_face_draw_offer(const SdfFaceDraw* d, const SdfFaceOffers* o, float lo,
                                     float hi) {
  return o->at_centroid ? sdf_face_draw_centroid(d, lo, hi) : sdf_face_draw_at(d, o->walk.b);
}

/* A device's second pass for face f of m: its value and island go where owner holds its
 * rank. */
SDF_INLINE void sdf_texture_draw_face(sdf_uint32 f, sdf_uint32 m, SDF_GLOBAL const float* uvs,
                                      int width, int height, SDF_GLOBAL const float* values,
                                      SDF_GLOBAL const sdf_uint32* triangles, float lo, float hi,
                                      sdf_int32 face_island, SDF_GLOBAL const sdf_uint32* owner,
                                      SDF_GLOBAL sdf_int32* island, SDF_GLOBAL float* value) {
  const SdfFaceDraw d = sdf_face_draw(f, values, triangles);
  SdfFaceOffers o;
  sdf_face_offers_start(f, m, uvs, width, height, &o);
  while (sdf_face_offers_next(&o)) {
    if (owner[o.texel] != o.rank) continue;
    island[o.texel] = face_island;
    value[o.texel] = sdf_face_draw_offer(&d, &o, lo, hi);
  }
}

/* Step 5 for face f: the mean of the blurred texels it covers that belong to its island,
 * clamped to [lo, hi]; else the texel under its centroid if of its island; else `keep`. */
SDF_INLINE float sdf_texture_read_face(sdf_uint32 f, SDF_GLOBAL const float* uvs, int width,
                                       int height, sdf_int32 face_island,
                                       SDF_GLOBAL const sdf_int32* island,
                                       SDF_GLOBAL const float* blurred, float lo, float hi,
                                       float keep) {
  SDF_GLOBAL const float* uv = uvs + 6 * (size_t)f;
  double sum = 0.0;
  sdf_uint32 count = 0;
  SdfTexelWalk w;
  sdf_texel_walk_start(uv, width, height, &w);
  while (sdf_texel_walk_next(&w)) {
    if (island[w.texel] != face_island) continue;
    sum += blurred[w.texel];
    ++count;
  }
  if (count > 0) return sdf_min(hi, sdf_max(lo, (float)(sum / count)));
  sdf_int64 t = sdf_texel_of_centroid(uv, width, height);
  return t >= 0 && island[t] == face_island ? blurred[t] : keep;
}

/* Step 5 for vertex values, one corner at (u, v) of a face of island `face_island`: the
 * bilinear read of the blurred texels around it that belong to the island, each weighing its
 * share; where none does, the texel under it if of the island; else NaN (not sampled). */
SDF_INLINE float sdf_texture_sample_corner(float u, float v, int width, int height,
                                           sdf_int32 face_island,
                                           SDF_GLOBAL const sdf_int32* island,
                                           SDF_GLOBAL const float* blurred) {
  double x = u * (double)width - 0.5, y = v * (double)height - 0.5;
  double fx = floor(x), fy = floor(y);
  int x0 = (int)sdf_dmax(-2.0, sdf_dmin(fx, (double)width));
  int y0 = (int)sdf_dmax(-2.0, sdf_dmin(fy, (double)height));
  double ax = x - fx, ay = y - fy;
  double sum = 0.0, weight = 0.0;
  for (int k = 0; k < 4; ++k) {
    int tx = x0 + (k & 1), ty = y0 + (k >> 1);
    if (tx < 0 || ty < 0 || tx >= width || ty >= height) continue;
    size_t t = (size_t)ty * width + tx;
    if (island[t] != face_island) continue;
    double w = ((k & 1) ? ax : 1.0 - ax) * ((k >> 1) ? ay : 1.0 - ay);
    sum += w * blurred[t];
    weight += w;
  }
  if (weight > 0.0) return (float)(sum / weight);
  sdf_int64 t = sdf_texel_at(u, v, width, height);
  return t >= 0 && island[t] == face_island ? blurred[t] : NAN;
}

/* Step 5 for vertex values, one vertex: the mean of its (merged vertex's) sampled corners,
 * corners[begin, end) in face order (samples: NaN where not sampled), summed in double in that
 * order, clamped to [lo, hi]; `keep` where none was sampled. */
SDF_INLINE float sdf_texture_vertex_mean(sdf_uint32 begin, sdf_uint32 end,
                                         SDF_GLOBAL const sdf_uint32* corners,
                                         SDF_GLOBAL const float* samples, float lo, float hi,
                                         float keep) {
  double sum = 0.0;
  sdf_uint32 count = 0;
  for (sdf_uint32 j = begin; j < end; ++j) {
    float s = samples[corners[j]];
    if (s != s) continue; /* NaN: not sampled */
    sum += s;
    ++count;
  }
  return count > 0 ? sdf_min(hi, sdf_max(lo, (float)(sum / count))) : keep;
}

#endif /* SDF_HAVE_DOUBLE */

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
 * first pass, the value and a null weight_sum: 1 everywhere, with no array to fill). Bilateral
 * (inv_range > 0): taps also weigh exp(-1/2 ((v_tap - v_centre) * inv_range)^2), v = value_sum /
 * weight_sum. An empty centre (island < 0) gives 0 and 0. */
SDF_INLINE void sdf_blur_texel(int i, int count, size_t stride, SDF_GLOBAL const sdf_int32* island,
                               SDF_GLOBAL const float* value_sum,
                               SDF_GLOBAL const float* weight_sum, SDF_GLOBAL const float* taps,
                               int radius, float inv_range, float* value_out, float* weight_out) {
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
 * (the centre texel itself always counts, so weight > 0). Values near the float limit can
 * overflow the float sums to inf - inf: such a NaN becomes lo here, on the host as on a
 * device (whose fmax would drop it where the host's compare keeps it), and no blurred texel
 * is NaN (the vertex read-back takes NaN for "no sample"). */
SDF_INLINE float sdf_blur_normalize(float value_sum, float weight_sum, float lo, float hi) {
  float mean = value_sum / weight_sum;
  if (mean != mean) return lo;
  return sdf_min(hi, sdf_max(lo, mean));
}

SDF_KERNEL_END

#endif /* SDF_SMOOTH_TEXTURE_H */
