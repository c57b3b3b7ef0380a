// SPDX-License-Identifier: GPL-3.0-or-later
// Quality figures of a built BVH, for tests and the build benchmark: they let a faster builder
// show that it did not buy its speed with a worse tree.
#pragma once

#include "accel/bvh.h"

namespace sdf {

// Surface area heuristic cost of the tree (MacDonald and Booth 1990) with the builder's own
// constants, traversal 1 and intersection 1 per triangle: the sum over inner nodes of
// area(node) / area(root), plus the sum over leaves of area(leaf) / area(root) * triangles.
// 0 for an empty tree. Lower is better: a proxy for cast time that needs no rays.
double bvh_sah_cost(const Bvh& bvh);

}  // namespace sdf
