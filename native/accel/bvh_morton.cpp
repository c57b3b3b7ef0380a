// SPDX-License-Identifier: GPL-3.0-or-later
#include "accel/bvh_morton.h"

#include <algorithm>

#include "accel/bvh_subtree.h"
#include "util/morton.h"

namespace sdf::bvh_build {

void MortonSubtrees::sort_by_code(PrimRef* refs, const Range& range) {
  const std::size_t n = range.count();
  codes_.resize(n);
  codes_out_.resize(n);
  refs_out_.resize(n);
  // Codes of the centroids (as lo + hi, like the binning) in the node's centroid box, 10 bits
  // an axis.
  float lo[3], scale[3];
  for (int a = 0; a < 3; ++a) {
    const float extent = range.centroids.hi[a] - range.centroids.lo[a];
    lo[a] = range.centroids.lo[a];
    scale[a] = extent > 0.0f ? 1023.0f / extent : 0.0f;
  }
  for (std::size_t i = 0; i < n; ++i) {
    const PrimRef& r = refs[range.begin + i];
    std::uint32_t code = 0;
    for (int a = 0; a < 3; ++a) {
      const float q = std::min(1023.0f, std::max(0.0f, (r.lo[a] + r.hi[a] - lo[a]) * scale[a]));
      code |= spread_bits_10(static_cast<std::uint32_t>(q)) << a;
    }
    codes_[i] = code;
  }
  // LSD radix sort, 10 bits a pass, stable: equal codes keep the order SAH's partitions left.
  PrimRef* src = refs + range.begin;
  for (int shift = 0; shift < 30; shift += 10) {
    std::uint32_t offset[1025] = {};
    for (std::size_t i = 0; i < n; ++i) ++offset[((codes_[i] >> shift) & 0x3ffu) + 1];
    for (int b = 0; b < 1024; ++b) offset[b + 1] += offset[b];
    for (std::size_t i = 0; i < n; ++i) {
      const std::uint32_t to = offset[(codes_[i] >> shift) & 0x3ffu]++;
      codes_out_[to] = codes_[i];
      refs_out_[to] = src[i];
    }
    codes_.swap(codes_out_);
    std::copy(refs_out_.begin(), refs_out_.begin() + n, src);
  }
}

void MortonSubtrees::build(PrimRef* refs, const Range& range, std::size_t node,
                           kern::SdfBvhNode* nodes, std::size_t* used) {
  sort_by_code(refs, range);
  first_ = range.begin;
  split(refs, range.begin, range.end, range.depth, node, nodes, used);
}

Box MortonSubtrees::split(PrimRef* refs, std::size_t begin, std::size_t end, int depth,
                          std::size_t node, kern::SdfBvhNode* nodes, std::size_t* used) {
  const std::size_t count = end - begin;
  if (count <= static_cast<std::size_t>(max_leaf_size_) || depth >= kMaxDepth) {
    nodes[node].first = static_cast<std::int32_t>(begin);
    nodes[node].count = static_cast<std::int32_t>(count);
    Box4 box;
    for (std::size_t i = begin; i < end; ++i) box.grow(lo4(refs[i]), hi4(refs[i]));
    return box.box();
  }
  const std::uint32_t a = codes_[begin - first_], b = codes_[end - 1 - first_];
  std::size_t mid = begin + count / 2;
  if (a != b) {
    // The first code with the highest differing bit set: the codes share every bit above it.
    const std::uint32_t bit = 1u << (31 - __builtin_clz(a ^ b));
    const std::uint32_t* first = codes_.data() + (begin - first_);
    mid = begin + static_cast<std::size_t>(
                      std::partition_point(first, first + count,
                                           [bit](std::uint32_t c) { return (c & bit) == 0; }) -
                      first);
  }
  const std::size_t child = *used;
  *used += 2;
  nodes[node].first = static_cast<std::int32_t>(child);
  nodes[node].count = 0;
  Box left = split(refs, begin, mid, depth + 1, child, nodes, used);
  const Box right = split(refs, mid, end, depth + 1, child + 1, nodes, used);
  set_node_bounds(nodes[child], left);
  set_node_bounds(nodes[child + 1], right);
  left.grow(right);
  return left;
}

}  // namespace sdf::bvh_build
