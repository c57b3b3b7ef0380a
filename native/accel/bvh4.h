// SPDX-License-Identifier: GPL-3.0-or-later
// A 4-wide BVH for the CPU engine, collapsed from the binary BVH: one SSE instruction tests a
// ray against four boxes, so a ray visits about half the nodes and mispredicts far fewer
// branches than in the binary tree (the cost that dominates scalar BVH2 traversal here).
// The binary BVH stays the layout the OpenCL kernels read.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "accel/bvh.h"

namespace sdf {

// Four child boxes as structure-of-arrays, 128 bytes. child[i] >= 0: an inner node index;
// child[i] < 0: a leaf of count[i] triangles starting at ~child[i] in the triangle array.
// Unused slots have an empty box (lo = +inf, hi = -inf) that no ray enters.
struct alignas(16) Bvh4Node {
  float lo_x[4], lo_y[4], lo_z[4];
  float hi_x[4], hi_y[4], hi_z[4];
  std::int32_t child[4];
  std::int32_t count[4];
};
static_assert(sizeof(Bvh4Node) == 128, "Bvh4Node is two cache lines");
// The OpenCL engine uploads these nodes as the kernels' SdfBvh4Node: the same bytes.
static_assert(sizeof(Bvh4Node) == sizeof(kern::SdfBvh4Node) &&
                  offsetof(Bvh4Node, hi_x) == offsetof(kern::SdfBvh4Node, hi_x) &&
                  offsetof(Bvh4Node, child) == offsetof(kern::SdfBvh4Node, child) &&
                  offsetof(Bvh4Node, count) == offsetof(kern::SdfBvh4Node, count),
              "Bvh4Node and SdfBvh4Node share one layout");

struct Bvh4 {
  std::vector<Bvh4Node> nodes;  // nodes[0] is the root (a lone leaf root becomes one slot)
  const UninitializedVector<kern::SdfTriangle>* triangles = nullptr;  // the binary BVH's, shared
  int depth = 0;  // of the deepest wide node (root = 0), recorded while collapsing
  bool empty() const { return nodes.empty(); }
};

// Collapses `bvh` (which must outlive the result: triangles are shared, not copied).
Bvh4 collapse_to_bvh4(const Bvh& bvh);

}  // namespace sdf
