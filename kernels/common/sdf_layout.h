/* SPDX-License-Identifier: GPL-3.0-or-later */
/* Packed data read by the ray caster, the same bytes on the host and in the kernels.
 * Only scalar members: OpenCL's float3 is 16 bytes and GLM's vec3 is 12, so shared structs
 * never use vector types. Every size is static_assert-ed on the host. */
#ifndef SDF_LAYOUT_H
#define SDF_LAYOUT_H

#include "common/sdf_compat.h"

SDF_KERNEL_BEGIN

/* A BVH node, 32 bytes. Interior (count == 0): children at first and first + 1.
 * Leaf (count > 0): triangles [first, first + count) of the packed triangle array. */
typedef struct SdfBvhNode {
  float lo_x, lo_y, lo_z;
  sdf_int32 first;
  float hi_x, hi_y, hi_z;
  sdf_int32 count;
} SdfBvhNode;

/* A 4-wide BVH node, 128 bytes: the four child boxes as structure of arrays (one float4 load
 * per plane), then per child an index. child[i] >= 0: an inner node; child[i] < 0: a leaf of
 * count[i] triangles starting at ~child[i]. Unused slots hold an empty box (lo = +inf,
 * hi = -inf) that no ray enters. The same bytes as the CPU engine's Bvh4Node (native/accel/bvh4.h). */
typedef struct SdfBvh4Node {
  float lo_x[4], lo_y[4], lo_z[4];
  float hi_x[4], hi_y[4], hi_z[4];
  sdf_int32 child[4];
  sdf_int32 count[4];
} SdfBvh4Node;

/* An 8-wide BVH node, 256 bytes, for OpenCL on CPUs (sdf_bvh8_traverse.h): the 4-wide node's
 * layout with eight slots (one float8 load per plane). child[i] < 0: a leaf of count[i]
 * triangle packets starting at ~child[i]. The same bytes as the CPU engine's Bvh8Node
 * (native/accel/bvh8.h). */
typedef struct SdfBvh8Node {
  float lo_x[8], lo_y[8], lo_z[8];
  float hi_x[8], hi_y[8], hi_z[8];
  sdf_int32 child[8];
  sdf_int32 count[8];
} SdfBvh8Node;

/* Four triangles of an 8-wide leaf, SdfTriangle's fields as structure of arrays, 160 bytes
 * (one float4 load per field). Unused lanes have e1 = e2 = 0, never hit. The same bytes as the
 * CPU engine's TrianglePacket4 (native/accel/bvh8.h). */
typedef struct SdfTrianglePacket4 {
  float v0_x[4], v0_y[4], v0_z[4];
  float e1_x[4], e1_y[4], e1_z[4];
  float e2_x[4], e2_y[4], e2_z[4];
  sdf_int32 id[4];
} SdfTrianglePacket4;

/* A triangle prepared for Moller-Trumbore, 48 bytes: v0, e1 = v1 - v0, e2 = v2 - v0, and the
 * index of the triangle in the user's array (id), so hits report user indices. */
typedef struct SdfTriangle {
  float v0_x, v0_y, v0_z;
  sdf_int32 id;
  float e1_x, e1_y, e1_z;
  float pad0;
  float e2_x, e2_y, e2_z;
  float pad1;
} SdfTriangle;

/* Per-launch parameters of the cast kernels, passed by value. */
typedef struct SdfCastParams {
  sdf_int32 rays;
  sdf_int32 sampling;
  float one_minus_cos_half;
  float sin_half;
  float angle_floor;
  sdf_uint32 seed;
  float tmin;
  sdf_uint32 first; /* this launch covers order[first .. first + count) */
  sdf_uint32 count;
} SdfCastParams;

/* The slot of the root of a tree made on the device (slot 0 stays unused): every pair of
 * children then starts at an even slot, so its 64 bytes never straddle a 128-byte cache line
 * (H100, 1.21M faces, three runs: cast 39.6 -> 38.7 ms; 832k 27.3 -> 26.75; 64 rays 89.4 ->
 * 87.6). Trees made on the host keep the root in slot 0. */
#define SDF_LBVH_ROOT 1

/* How ray directions are chosen (see sdf_rays.h). */
#define SDF_SAMPLING_FIBONACCI 0
#define SDF_SAMPLING_RANDOM 1
#define SDF_SAMPLING_CGAL 2

SDF_STATIC_ASSERT(sizeof(SdfBvhNode) == 32, "SdfBvhNode is 32 bytes in every build");
SDF_STATIC_ASSERT(sizeof(SdfBvh4Node) == 128, "SdfBvh4Node is 128 bytes in every build");
SDF_STATIC_ASSERT(sizeof(SdfBvh8Node) == 256, "SdfBvh8Node is 256 bytes in every build");
SDF_STATIC_ASSERT(sizeof(SdfTrianglePacket4) == 160, "SdfTrianglePacket4 is 160 bytes");
SDF_STATIC_ASSERT(sizeof(SdfTriangle) == 48, "SdfTriangle is 48 bytes in every build");
SDF_STATIC_ASSERT(sizeof(SdfCastParams) == 36, "SdfCastParams is 36 bytes in every build");

SDF_KERNEL_END

#endif /* SDF_LAYOUT_H */
