// SPDX-License-Identifier: GPL-3.0-or-later
// An 8-wide BVH for the CPU engine on AVX2 machines, collapsed from the binary BVH like the
// 4-wide one (bvh4.h), with the leaf triangles repacked four at a time as structure-of-arrays
// so that one SSE test covers four of them (a leaf holds up to kBvh8MergeUpTo triangles, two
// packets, more only where the builder's depth limit left a larger leaf). A ray visits about half
// the nodes it visits in the 4-wide tree; each visit tests eight boxes with one AVX2 instruction
// per slab. Traversal (bvh8_traverse.h) is compiled for AVX2 alone and chosen at run time: the
// package must still run on x86-64 CPUs without AVX2, which keep the 4-wide SSE tree.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "accel/bvh.h"
#include "util/cpu_features.h"

// The 8-wide traversal exists on x86-64 builds only (elsewhere the CPU engine casts the
// binary tree; the OpenCL kernels read the 8-wide tree on any host).
#define SDF_HAVE_BVH8 SDF_X86_SIMD

namespace sdf {

// Eight child boxes as structure-of-arrays, 256 bytes. child[i] >= 0: an inner node index;
// child[i] < 0: a leaf of count[i] packets starting at ~child[i] in the packet array.
// Unused slots have an empty box (lo = +inf, hi = -inf) that no ray enters. Boxes are the
// binary BVH's: grown by grow_boxes_to_cover_hits (bvh_margin.h), they cover the rounding of
// the fused box test.
struct alignas(32) Bvh8Node {
  float lo_x[8], lo_y[8], lo_z[8];
  float hi_x[8], hi_y[8], hi_z[8];
  std::int32_t child[8];
  std::int32_t count[8];
};
static_assert(sizeof(Bvh8Node) == 256, "Bvh8Node is four cache lines");

// Four triangles of a leaf, the fields of kern::SdfTriangle as structure-of-arrays. Unused
// lanes have e1 = e2 = 0: det is exactly 0 and the lane never hits.
struct alignas(16) TrianglePacket4 {
  float v0_x[4], v0_y[4], v0_z[4];
  float e1_x[4], e1_y[4], e1_z[4];
  float e2_x[4], e2_y[4], e2_z[4];
  std::int32_t id[4];
};
static_assert(sizeof(TrianglePacket4) == 160, "TrianglePacket4 is 40 words");
// The OpenCL engine uploads both arrays as the kernels' SdfBvh8Node and SdfTrianglePacket4
// (kernels/traverse/sdf_bvh8_traverse.h): the same bytes.
static_assert(sizeof(Bvh8Node) == sizeof(kern::SdfBvh8Node) &&
                  offsetof(Bvh8Node, lo_y) == offsetof(kern::SdfBvh8Node, lo_y) &&
                  offsetof(Bvh8Node, hi_x) == offsetof(kern::SdfBvh8Node, hi_x) &&
                  offsetof(Bvh8Node, child) == offsetof(kern::SdfBvh8Node, child) &&
                  offsetof(Bvh8Node, count) == offsetof(kern::SdfBvh8Node, count),
              "Bvh8Node and SdfBvh8Node share one layout");
static_assert(sizeof(TrianglePacket4) == sizeof(kern::SdfTrianglePacket4) &&
                  offsetof(TrianglePacket4, e1_x) == offsetof(kern::SdfTrianglePacket4, e1_x) &&
                  offsetof(TrianglePacket4, e2_x) == offsetof(kern::SdfTrianglePacket4, e2_x) &&
                  offsetof(TrianglePacket4, id) == offsetof(kern::SdfTrianglePacket4, id),
              "TrianglePacket4 and SdfTrianglePacket4 share one layout");

struct Bvh8 {
  std::vector<Bvh8Node> nodes;  // nodes[0] is the root (a lone leaf root becomes one slot)
  std::vector<TrianglePacket4> packets;
  bool empty() const { return nodes.empty(); }
};

// Whether this build and CPU run the 8-wide traversal (x86-64 with AVX2 and FMA, and an OS
// that saves the YMM registers: cpu_features()).
bool bvh8_supported();

// Copies `bvh`'s boxes and triangles (it need not outlive the result). Pass a tree grown by
// grow_boxes_to_cover_hits: the 8-wide box test relies on it. A subtree of merge_up_to
// triangles or fewer becomes one leaf: the binary builder's leaves of 1 to 4 mostly fill part
// of a packet, and one or two SIMD tests cost less than visiting the boxes between them.
// 8 measured best of 0, 4, 8 and 12 (bench/cast_timing: 8-wide over 4-wide rays/s 1.80, 1.98,
// 2.08 on bunny00; 1.85 (4), 2.21 (8), 2.16 (12) on armadillo-x4).
constexpr int kBvh8MergeUpTo = 8;
Bvh8 collapse_to_bvh8(const Bvh& bvh, int merge_up_to = kBvh8MergeUpTo);

}  // namespace sdf
