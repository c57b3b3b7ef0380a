/* SPDX-License-Identifier: GPL-3.0-or-later */
/* Smoothing on projected points (paper 4.4), the per-point parts: where a point goes, which
 * cell of the octree it falls in, what it adds to a node's sum, and the weighted mean of the
 * nodes that a sphere gathers. The host (native/post/smoothing_projected.cpp) and the OpenCL
 * kernels (sdf_point_octree_kernels.cl builds the octree, sdf_smooth_kernels.cl gathers) both
 * build it from these, so they make the same tree; the CPU calls them as C++, the kernels as
 * OpenCL C. */
#ifndef SDF_SMOOTH_PROJECTED_H
#define SDF_SMOOTH_PROJECTED_H

#include "common/sdf_compat.h"

SDF_KERNEL_BEGIN

/* One octree node, 32 bytes (the same bytes on the host and on a device). Children of a
 * branching node are stored next to each other (empty octants have none) from first_child
 * on. (`half` is an OpenCL type name, hence half_side.) */
typedef struct SdfPointNode {
  float center[3];
  float half_side;       /* half the side of the node's cube */
  float mean;            /* mean value of the points inside */
  sdf_uint32 count;      /* points inside (> 0) */
  sdf_int32 first_child; /* -1 for a leaf */
  sdf_uint32 child_count;
} SdfPointNode;

SDF_STATIC_ASSERT(sizeof(SdfPointNode) == 32, "SdfPointNode is 32 bytes in every build");

/* Deepest octree: 3 bits per level in a 64-bit Morton key. Children pushed per visit are at
 * most 8, one visit pops 1: 7 more per level. */
#define SDF_POINT_MAX_DEPTH 20
#define SDF_POINT_STACK (7 * SDF_POINT_MAX_DEPTH + 2)

/* A point moved inward along its axis by half its value (the SDF): near the medial axis. */
SDF_INLINE float3 sdf_project_point(float3 origin, float3 axis, float value) {
  float h = 0.5f * value;
  return make_float3(origin.x + axis.x * h, origin.y + axis.y * h, origin.z + axis.z * h);
}

/* A coordinate's cell along one axis at the deepest level: `cells` per axis over the root
 * cube, which starts at `corner`; scale = cells / the cube's side. A multiplication, not a
 * division: OpenCL rounds division differently unless asked not to. */
SDF_INLINE sdf_uint32 sdf_point_cell(float x, float corner, float scale, sdf_uint32 cells) {
  float c = floor((x - corner) * scale);
  if (!(c > 0.0f)) return 0u;
  return c < (float)cells ? (sdf_uint32)c : cells - 1u;
}

/* Which child (octant: bit 0 x, bit 1 y, bit 2 z) of a node of level `level` in a tree of
 * depth `depth` holds the cell (cx, cy, cz): the cells' bits at depth - level - 1, as in a
 * Morton key whose x bits come first. */
SDF_INLINE sdf_uint32 sdf_point_octant(sdf_uint32 cx, sdf_uint32 cy, sdf_uint32 cz, int level,
                                       int depth) {
  int bit = depth - level - 1;
  return ((cx >> bit) & 1u) | ((cy >> bit) & 1u) << 1 | ((cz >> bit) & 1u) << 2;
}

/* A value >= 0 in fixed point, units of 2^-shift (truncated). Node sums add these as
 * integers, which give the same sum in any order: one thread or a device's thousands, with
 * atomics, make the same means. The host picks shift so that no sum overflows 2^62
 * (smoothing_projected.h, point_fixed_shift); ldexp is exact. */
SDF_INLINE sdf_uint64 sdf_fixed_value(float value, int shift) {
  return (sdf_uint64)ldexp(value, shift);
}

/* Approximate fraction of a cube of side `side` whose centre is `distance` from the centre of
 * a sphere of radius `radius` that lies inside the sphere: the cube is taken as the ball of
 * equal volume (radius 0.6204 side, (3 / (4 pi))^(1/3)) and the fraction is the volume of the
 * two balls' lens over that ball's volume. Exact when one ball holds the other; never above
 * sphere volume / cube volume. */
SDF_INLINE float sdf_cube_fraction_in_sphere(float side, float distance, float radius) {
  float rho = 0.62035049f * side;
  float r = radius, d = distance;
  if (!(r > 0.0f) || d >= r + rho) return 0.0f;
  float ball = rho * rho * rho; /* volumes below without the common 4 pi / 3 */
  if (d <= fabs(r - rho)) return r >= rho ? 1.0f : sdf_min(1.0f, (r * r * r) / ball);
  /* Lens of two balls (radii r, rho, centres d apart): pi (r + rho - d)^2 (d^2 + 2 d (r + rho)
   * - 3 (r - rho)^2) / (12 d); over (4 pi / 3) rho^3 that is the expression below. */
  float s = r + rho - d;
  float lens = s * s * (d * d + 2.0f * d * (r + rho) - 3.0f * (r - rho) * (r - rho)) / (16.0f * d);
  return sdf_min(1.0f, sdf_max(0.0f, lens / ball));
}

/* The weighted mean of the nodes that the sphere (center, radius) gathers: a node wholly
 * inside counts whole (weight = its count), a leaf the sphere cuts weighs count x
 * sdf_cube_fraction_in_sphere. Returns 0 (and leaves *mean alone) when it gathers nothing. */
SDF_INLINE int sdf_gather_sphere(SDF_GLOBAL const SdfPointNode* nodes, float3 center, float radius,
                                 float* mean) {
  sdf_uint32 stack[SDF_POINT_STACK];
  int top = 0;
  stack[top++] = 0;
  sdf_wide sum = 0.0f, weight = 0.0f;
  const float sqrt3 = 1.7320508f;
  while (top > 0) {
    SDF_GLOBAL const SdfPointNode* node = nodes + stack[--top];
    float3 c = make_float3(node->center[0], node->center[1], node->center[2]);
    float3 offset = center - c;
    /* Distance from the sphere's centre to the cube: outside when it exceeds the radius. */
    float3 out = make_float3(sdf_max(fabs(offset.x) - node->half_side, 0.0f),
                             sdf_max(fabs(offset.y) - node->half_side, 0.0f),
                             sdf_max(fabs(offset.z) - node->half_side, 0.0f));
    if (sdf_dot(out, out) > radius * radius) continue;
    float d = sqrt(sdf_dot(offset, offset));
    float fraction;
    if (d + sqrt3 * node->half_side <= radius) {
      fraction = 1.0f; /* wholly inside: the node's count and mean stand for its points */
    } else if (node->first_child >= 0) {
      for (sdf_uint32 i = 0; i < node->child_count; ++i)
        stack[top++] = (sdf_uint32)node->first_child + i;
      continue;
    } else {
      fraction = sdf_cube_fraction_in_sphere(2.0f * node->half_side, d, radius);
      if (!(fraction > 0.0f)) continue;
    }
    sdf_wide w = (sdf_wide)node->count * fraction;
    sum += w * node->mean;
    weight += w;
  }
  if (!(weight > 0.0f)) return 0;
  *mean = (float)(sum / weight);
  return 1;
}

/* One point of one iteration: the mean its sphere (radius: radius_scale times its value)
 * gathers, clamped to [lo, hi] (the input's range), or the point's own value when the sphere
 * gathers nothing. */
SDF_INLINE float sdf_smooth_projected_point(SDF_GLOBAL const SdfPointNode* nodes, float3 projected,
                                            float value, float radius_scale, float lo, float hi) {
  float mean;
  if (!sdf_gather_sphere(nodes, projected, radius_scale * value, &mean)) return value;
  return sdf_min(hi, sdf_max(lo, mean));
}

SDF_KERNEL_END

#endif /* SDF_SMOOTH_PROJECTED_H */
