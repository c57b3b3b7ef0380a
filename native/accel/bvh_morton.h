// SPDX-License-Identifier: GPL-3.0-or-later
// Subtrees split at Morton-code bits (Karras 2012's radix tree, built top-down) instead of by
// SAH: one sort and one pass for bounds where SAH bins and partitions every level. Cheaper to
// build, somewhat slower to traverse; the GPU path, where the build is the larger host stage,
// uses it for the bottom of the tree (BvhConfig::morton_below).
#pragma once

#include <cstdint>
#include <vector>

#include "accel/bvh_sah.h"
#include "common/sdf_layout.h"

namespace sdf::bvh_build {

class MortonSubtrees {
 public:
  explicit MortonSubtrees(int max_leaf_size) : max_leaf_size_(max_leaf_size) {}

  // Builds the children of `node` over refs[range) (reordering that part of refs), its own box
  // already written; new nodes are taken from *used onward, children adjacent, `first`
  // counted from nodes[0]. A node of at most max_leaf_size triangles, or at depth kMaxDepth,
  // is a leaf; equal codes are cut in the middle of their run.
  void build(PrimRef* refs, const Range& range, std::size_t node, kern::SdfBvhNode* nodes,
             std::size_t* used);

 private:
  // Returns the box of refs[begin, end) after making node their subtree's root.
  Box split(PrimRef* refs, std::size_t begin, std::size_t end, int depth, std::size_t node,
            kern::SdfBvhNode* nodes, std::size_t* used);
  void sort_by_code(PrimRef* refs, const Range& range);

  int max_leaf_size_;
  // Scratch reused across subtrees: codes of the range, in the order of refs, and the sort's
  // second buffers.
  std::vector<std::uint32_t> codes_, codes_out_;
  std::vector<PrimRef> refs_out_;
  std::size_t first_ = 0;  // range.begin of the subtree being built (codes_ are relative)
};

}  // namespace sdf::bvh_build
