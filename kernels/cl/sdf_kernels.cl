/* SPDX-License-Identifier: GPL-3.0-or-later */
/* The OpenCL engine's kernels. Everything they compute lives in the shared headers, which the
 * CPU engine compiles as C++: these entry points only fetch a point, cast its rays and store
 * the result.
 *
 * Casting and reducing are fused (the paper uses one work item per ray and a second kernel
 * per point): no ray length ever reaches global memory (the paper stores rays x points
 * floats) and there is one launch instead of two. Two layouts: one work item per point,
 * casting all its rays into private arrays (CPU devices), or one work item per ray, a work
 * group holding a few points whose rays meet in local memory (GPUs; opencl_engine.cpp says
 * which runs where and why). SDF_MAX_RAYS is set by the host to the run's ray count.
 * Deterministic ray sets (Fibonacci, CGAL) come from the host as a table (direction, angle),
 * computed once with the host's sin and cos, so every device casts the very same rays as the
 * CPU engine. Results are written in launch order (raw[first + i]), so each launch reads back
 * one contiguous range. */
#include "traverse/sdf_bvh_traverse.h"
#include "traverse/sdf_bvh4_traverse.h"
#include "traverse/sdf_bvh8_traverse.h"
#include "ray/sdf_face_point.h"
#include "traverse/sdf_octree.h"
#include "ray/sdf_reduce.h"
#include "smooth/sdf_smooth_projected.h"

#ifndef SDF_MAX_RAYS
#define SDF_MAX_RAYS 32
#endif

/* Ray r of point p in world space, and its angle to the axis: from the host's table for the
 * deterministic samplings, from the device's own sin and cos for random sampling. */
static inline float3 sdf_cast_direction(SdfCastParams params,
                                        __global const float4* restrict local_rays, int r,
                                        uint p, float3 axis, float3 b1, float3 b2,
                                        float* angle) {
  float3 dir_local;
  if (params.sampling == SDF_SAMPLING_RANDOM) {
    dir_local = sdf_ray_local(params.sampling, r, params.rays, params.one_minus_cos_half,
                              params.sin_half, params.seed, p);
    *angle = sdf_ray_angle(dir_local);
  } else {
    float4 table = local_rays[r];
    dir_local = table.xyz;
    *angle = table.w;
  }
  return sdf_to_world(dir_local, b1, b2, axis);
}

/* Where a point's rays start: the origin, the cone's axis (zero: the point casts no rays), the
 * tangent the rays' azimuth starts from, and the face the rays skip. */
typedef struct SdfRayStart {
  float3 origin, axis, tangent;
  int own;
} SdfRayStart;

/* Point p's start from the sampled points' arrays (points made on the host). */
static inline SdfRayStart sdf_start_from_arrays(uint p, __global const float* restrict origins,
                                                __global const float* restrict axes,
                                                __global const float* restrict tangents,
                                                __global const int* restrict own_face) {
  SdfRayStart start;
  start.origin = vload3(p, origins);
  start.axis = vload3(p, axes);
  start.tangent = vload3(p, tangents);
  start.own = own_face[p];
  return start;
}

/* Face p's point made from the mesh, by the function the host's sampling uses (so the same
 * bits): with the tree made on the device (points 'faces'), the cast reads the mesh instead
 * of the points' arrays, 40 bytes a face that then never exist on the device. */
static inline SdfRayStart sdf_start_of_face(uint p, __global const float* restrict vertices,
                                            __global const uint* restrict faces) {
  SdfRayStart start;
  uint3 t = vload3(p, faces);
  sdf_face_point(vload3(t.x, vertices), vload3(t.y, vertices), vload3(t.z, vertices),
                 &start.origin, &start.axis, &start.tangent);
  start.own = (int)p;
  return start;
}

#define SDF_START_FROM_ARRAYS(p) sdf_start_from_arrays(p, origins, axes, tangents, own_face)
#define SDF_START_OF_FACE(p) sdf_start_of_face(p, vertices, faces)

/* One work item per point: fetch the point and its ray frame (a point without an axis gets
 * -1 and no rays), ... SDF_KEEP each ray's hit in ray order ..., then reduce and store. */
#define SDF_POINT_BEGIN(START)                                                        \
  uint gid = get_global_id(0);                                                        \
  if (gid >= params.count) return;                                                    \
  uint p = order[params.first + gid];                                                 \
  SdfRayStart start = START(p);                                                       \
  float3 axis = start.axis;                                                           \
  uint out = params.first + gid;                                                      \
  if (axis.x == 0.0f && axis.y == 0.0f && axis.z == 0.0f) {                           \
    raw[out] = -1.0f;                                                                 \
    valid_rays[out] = 0;                                                              \
    return;                                                                           \
  }                                                                                   \
  float3 origin = start.origin;                                                       \
  int own = start.own;                                                                \
  float3 b1, b2;                                                                      \
  sdf_frame(params.sampling, axis, start.tangent, &b1, &b2);                          \
  float lengths[SDF_MAX_RAYS];                                                        \
  float angles[SDF_MAX_RAYS];                                                         \
  int kept = 0;

#define SDF_KEEP(HIT, ANGLE)                                                          \
  if (sdf_exit_hit(HIT)) {                                                            \
    lengths[kept] = (HIT).t;                                                          \
    angles[kept] = (ANGLE);                                                           \
    ++kept;                                                                           \
  }

#define SDF_POINT_END                                                                 \
  raw[out] = sdf_reduce(params.sampling, lengths, angles, kept, params.angle_floor);  \
  valid_rays[out] = kept;

/* The per-point kernel of a structure whose traversal casts one ray at a time. */
#define SDF_CAST_BODY(START, CLOSEST_HIT)                                             \
  SDF_POINT_BEGIN(START)                                                              \
  for (int r = 0; r < params.rays; ++r) {                                             \
    float angle;                                                                      \
    float3 d = sdf_cast_direction(params, local_rays, r, p, axis, b1, b2, &angle);    \
    SdfHit hit = CLOSEST_HIT;                                                         \
    SDF_KEEP(hit, angle)                                                              \
  }                                                                                   \
  SDF_POINT_END

/* One work item per ray: a work group holds P points x rays work items, item l casting ray
 * l % rays of point l / rays, and writes the ray's length to local memory; then the first P
 * items reduce a point's rays each, in ray order, exactly as the per-point kernel does.
 * Threads are `rays` times shorter and hold no length arrays while they trace. On an H100
 * (832k and 1.2M faces) this was 13-15% faster than one item per point; the opposite mapping
 * (a warp holding one ray index of neighbouring points) and Aila and Laine's while-while
 * loop measured the same within 3%. */
#define SDF_CAST_PER_RAY_BODY(START, CLOSEST_HIT)                                     \
  uint lid = get_local_id(0);                                                         \
  uint group_points = get_local_size(0) / params.rays;                                \
  uint slot = lid / params.rays;                                                      \
  int r = (int)(lid % params.rays);                                                   \
  uint gid = get_group_id(0) * group_points + slot;                                   \
  float t_kept = -1.0f;                                                               \
  float angle = 0.0f;                                                                 \
  uint p = 0;                                                                         \
  SdfRayStart start;                                                                  \
  start.axis = make_float3(0.0f, 0.0f, 0.0f);                                         \
  if (gid < params.count && r < params.rays) {                                        \
    p = order[params.first + gid];                                                    \
    start = START(p);                                                                 \
  }                                                                                   \
  float3 axis = start.axis;                                                           \
  if (axis.x != 0.0f || axis.y != 0.0f || axis.z != 0.0f) {                           \
    float3 origin = start.origin;                                                     \
    int own = start.own;                                                              \
    float3 b1, b2;                                                                    \
    sdf_frame(params.sampling, axis, start.tangent, &b1, &b2);                        \
    float3 d = sdf_cast_direction(params, local_rays, r, p, axis, b1, b2, &angle);    \
    SdfHit hit = CLOSEST_HIT;                                                         \
    if (sdf_exit_hit(hit)) t_kept = hit.t;                                            \
  }                                                                                   \
  ray_t[lid] = t_kept;                                                                \
  ray_angle[lid] = angle;                                                             \
  barrier(CLK_LOCAL_MEM_FENCE);                                                       \
  /* Each kept ray writes itself to its place among its point's kept rays in the order a  \
   * stable sort gives (ascending length, ties in ray order), in the second half of the   \
   * local arrays: the reducing item then finds them sorted, and the insertion sort in    \
   * sdf_reduce only checks (1 compare a ray, not up to rays). After the barrier, where  \
   * that sort ran on one item a point, the kernel spent 10% of its warp instructions     \
   * and 25% of its stall samples; ranking first cut the cast by 7% (H100, CUDA build,    \
   * bench/cuda_cast, 1.21M faces: 42.3 -> 39.2 ms). */                                   \
  uint group_size = get_local_size(0);                                                \
  if (t_kept >= 0.0f) {                                                               \
    uint base = slot * params.rays;                                                   \
    int rank = 0;                                                                     \
    for (int k = 0; k < params.rays; ++k) {                                           \
      float t = ray_t[base + k];                                                      \
      rank += t >= 0.0f && (t < t_kept || (t == t_kept && k < r));                    \
    }                                                                                 \
    ray_t[group_size + base + rank] = t_kept;                                         \
    ray_angle[group_size + base + rank] = angle;                                      \
  }                                                                                   \
  barrier(CLK_LOCAL_MEM_FENCE);                                                       \
  /* The first group_points items reduce, item i the rays of point i of the group. */   \
  slot = lid;                                                                         \
  gid = get_group_id(0) * group_points + slot;                                        \
  if (lid >= group_points || gid >= params.count) return;                             \
  /* Kept lengths are > tmin >= 0, so -1 marks a ray not kept. */                     \
  float lengths[SDF_MAX_RAYS];                                                        \
  float angles[SDF_MAX_RAYS];                                                         \
  int kept = 0;                                                                       \
  for (int k = 0; k < params.rays; ++k) kept += ray_t[slot * params.rays + k] >= 0.0f; \
  for (int k = 0; k < kept; ++k) {                                                    \
    uint at = group_size + slot * params.rays + k;                                    \
    lengths[k] = ray_t[at];                                                           \
    angles[k] = ray_angle[at];                                                        \
  }                                                                                   \
  uint out = params.first + gid;                                                      \
  raw[out] = sdf_reduce(params.sampling, lengths, angles, kept, params.angle_floor);  \
  valid_rays[out] = kept;

/* The inputs and outputs every cast kernel takes after its acceleration structure and its
 * points (SDF_POINT_ARGS or SDF_FACE_POINT_ARGS). restrict: nothing aliases, and NVIDIA's
 * compiler then reads through the read-only cache. */
#define SDF_RUN_ARGS                                                                       \
  __global const uint* restrict order, __global const float4* restrict local_rays,         \
      SdfCastParams params, __global float* restrict raw, __global int* restrict valid_rays

/* The points as the host sampled them (SDF_START_FROM_ARRAYS). */
#define SDF_POINT_ARGS                                                                     \
  __global const float* restrict origins, __global const float* restrict axes,             \
      __global const float* restrict tangents, __global const int* restrict own_face,      \
      SDF_RUN_ARGS

/* The faces' points, made from the mesh as they are cast (SDF_START_OF_FACE). */
#define SDF_FACE_POINT_ARGS                                                                \
  __global const float* restrict vertices, __global const uint* restrict faces, SDF_RUN_ARGS

/* The binary BVH kernels take the nodes and triangles as float4 arrays (the SdfBvhNode and
 * SdfTriangle bytes): see sdf_bvh_closest_hit_units. */
__kernel void sdf_cast_bvh(__global const float4* restrict nodes,
                           __global const float4* restrict tris, SDF_POINT_ARGS) {
  SDF_CAST_BODY(SDF_START_FROM_ARRAYS,
                sdf_bvh_closest_hit_units(nodes, tris, 0, origin, d, params.tmin, own))
}

__kernel void sdf_cast_bvh4(__global const SdfBvh4Node* restrict nodes,
                            __global const SdfTriangle* restrict tris, SDF_POINT_ARGS) {
  SDF_CAST_BODY(SDF_START_FROM_ARRAYS,
                sdf_bvh4_closest_hit(nodes, tris, origin, d, params.tmin, own))
}

/* One work item per point on the 8-wide BVH (CPU devices): SDF_CAST_BODY with the point's
 * rays cast two at a time, taking turns visit by visit (sdf_bvh8_traverse.h). Lengths are
 * kept in ray order, as SDF_CAST_BODY keeps them. */
__kernel void sdf_cast_bvh8(__global const SdfBvh8Node* restrict nodes,
                            __global const SdfTrianglePacket4* restrict packets, SDF_POINT_ARGS) {
  SDF_POINT_BEGIN(SDF_START_FROM_ARRAYS)
  for (int r = 0; r < params.rays; r += 2) {
    SdfHit hit[2];
    float angle[2];
    float3 d0 = sdf_cast_direction(params, local_rays, r, p, axis, b1, b2, &angle[0]);
    int pair = r + 1 < params.rays;
    if (pair) {
      float3 d1 = sdf_cast_direction(params, local_rays, r + 1, p, axis, b1, b2, &angle[1]);
      sdf_bvh8_closest_hits2(nodes, packets, origin, d0, d1, params.tmin, own, &hit[0],
                             &hit[1]);
    } else {
      hit[0] = sdf_bvh8_closest_hit(nodes, packets, origin, d0, params.tmin, own);
    }
    for (int k = 0; k <= pair; ++k) {
      SDF_KEEP(hit[k], angle[k])
    }
  }
  SDF_POINT_END
}

/* ray_t and ray_angle hold 2 x the group's size: the rays as cast, then sorted per point. */
__kernel void sdf_cast_bvh_per_ray(__global const float4* restrict nodes,
                                   __global const float4* restrict tris, SDF_POINT_ARGS,
                                   __local float* ray_t, __local float* ray_angle) {
  SDF_CAST_PER_RAY_BODY(SDF_START_FROM_ARRAYS,
                        sdf_bvh_closest_hit_units(nodes, tris, 0, origin, d, params.tmin, own))
}

/* The binary tree's two kernels on the faces' points, made from the mesh as they are cast (with
 * the trees made on the device). */
__kernel void sdf_cast_bvh_faces(__global const float4* restrict nodes,
                                 __global const float4* restrict tris, SDF_FACE_POINT_ARGS) {
  SDF_CAST_BODY(SDF_START_OF_FACE, sdf_bvh_closest_hit_units(nodes, tris, SDF_LBVH_ROOT, origin,
                                                             d, params.tmin, own))
}

__kernel void sdf_cast_bvh_per_ray_faces(__global const float4* restrict nodes,
                                         __global const float4* restrict tris,
                                         SDF_FACE_POINT_ARGS, __local float* ray_t,
                                         __local float* ray_angle) {
  SDF_CAST_PER_RAY_BODY(SDF_START_OF_FACE,
                        sdf_bvh_closest_hit_units(nodes, tris, SDF_LBVH_ROOT, origin, d,
                                                  params.tmin, own))
}

__kernel void sdf_cast_octree(__global const uint* restrict nodes,
                              __global const uint* restrict leaves,
                              __global const SdfTriangle* restrict tris, SdfOctreeRoot root,
                              SDF_POINT_ARGS) {
  SDF_CAST_BODY(SDF_START_FROM_ARRAYS,
                sdf_octree_closest_hit(nodes, leaves, tris, root, origin, d, params.tmin, own))
}

/* Writes the size and member offsets of every struct shared with the host, so a test can
 * compare them with the host's own (tinybvh keeps layouts in sync by comments; we check). */
#define SDF_OFFSET(type, member) ((uint)(size_t)&(((type*)0)->member))
__kernel void sdf_layout_probe(__global uint* out) {
  out[0] = sizeof(SdfBvhNode);
  out[1] = SDF_OFFSET(SdfBvhNode, first);
  out[2] = SDF_OFFSET(SdfBvhNode, hi_x);
  out[3] = SDF_OFFSET(SdfBvhNode, count);
  out[4] = sizeof(SdfTriangle);
  out[5] = SDF_OFFSET(SdfTriangle, id);
  out[6] = SDF_OFFSET(SdfTriangle, e1_x);
  out[7] = SDF_OFFSET(SdfTriangle, e2_x);
  out[8] = sizeof(SdfOctreeRoot);
  out[9] = SDF_OFFSET(SdfOctreeRoot, size);
  out[10] = sizeof(SdfCastParams);
  out[11] = SDF_OFFSET(SdfCastParams, tmin);
  out[12] = SDF_OFFSET(SdfCastParams, count);
  out[13] = sizeof(SdfPointNode);
  out[14] = SDF_OFFSET(SdfPointNode, half_side);
  out[15] = SDF_OFFSET(SdfPointNode, count);
  out[16] = SDF_OFFSET(SdfPointNode, first_child);
  out[17] = SDF_OFFSET(SdfPointNode, child_count);
  out[18] = sizeof(SdfBvh8Node);
  out[19] = SDF_OFFSET(SdfBvh8Node, hi_x);
  out[20] = SDF_OFFSET(SdfBvh8Node, child);
  out[21] = SDF_OFFSET(SdfBvh8Node, count);
  out[22] = sizeof(SdfTrianglePacket4);
  out[23] = SDF_OFFSET(SdfTrianglePacket4, id);
}
