// SPDX-License-Identifier: GPL-3.0-or-later
// The host's share of a BVH built on the device (kernels/sdf_lbvh_kernels.cl, Karras 2012):
// every face in Morton order of its box's centre, the codes the tree splits at, and the
// margin every box grows by (bvh_margin.h). One pass over the faces for the bounds, one for
// the codes, and a radix sort: a few milliseconds on the host instead of a BVH build of tens.
#pragma once

#include <cstdint>

#include "mesh.h"
#include "stopwatch.h"
#include "uninitialized_vector.h"

namespace sdf {

struct TreeKeys {
  // Every face: those with area in Morton order (ties in face order), then the zero-area
  // ones in face order. The order the device casts the faces' points in, and the order of
  // the tree's triangle records for the first `with_area`.
  UninitializedVector<std::uint32_t> order;
  // The 30-bit Morton code of each of order's first `with_area` faces.
  UninitializedVector<std::uint32_t> codes;
  std::size_t with_area = 0;
  // What grow_boxes_to_cover_hits would grow the boxes of a tree of these triangles by.
  float margin = 0.0f;
};

// From the mesh as oriented or as wound: reversing a face (swapping its last two corners)
// changes neither its box, its area test nor its edges' components, so neither the keys.
// `threads` as everywhere (0: every core); the result does not depend on it. steps: where
// given, the seconds of 'keys: boxes', 'keys: codes', 'keys: sort' are appended.
TreeKeys make_tree_keys(const Mesh& mesh, unsigned threads = 0, StageTimings* steps = nullptr);

}  // namespace sdf
