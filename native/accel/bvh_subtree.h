// SPDX-License-Identifier: GPL-3.0-or-later
// The serial half of the BVH builder: one subtree, built depth first on the calling thread.
#pragma once

#include <vector>

#include "accel/bvh_sah.h"
#include "common/sdf_layout.h"

namespace sdf::bvh_build {

// Builds the subtree over refs[root.begin, root.end), reordering that part of refs into leaf
// order, and returns its number of nodes. nodes[0] receives the subtree's root; its
// descendants follow, children adjacent, each pair's `first` counted from nodes[0]. Leaves'
// `first` index refs itself. nodes must have room for 2 * root.count() - 1 (a binary tree of
// n leaves, none empty). Nodes of at most morton_below triangles are split at Morton-code
// bits (bvh_morton.h) instead of by SAH.
std::size_t build_subtree(PrimRef* refs, const Range& root, int bins, int max_leaf_size,
                          std::size_t morton_below, kern::SdfBvhNode* nodes);

// Writes a node's box (the link fields are set separately).
void set_node_bounds(kern::SdfBvhNode& node, const Box& b);

}  // namespace sdf::bvh_build
