// SPDX-License-Identifier: GPL-3.0-or-later
#include "accel/bvh_subtree.h"

#include <utility>

#include "accel/bvh_morton.h"

namespace sdf::bvh_build {

void set_node_bounds(kern::SdfBvhNode& node, const Box& b) {
  node.lo_x = b.lo.x;
  node.lo_y = b.lo.y;
  node.lo_z = b.lo.z;
  node.hi_x = b.hi.x;
  node.hi_y = b.hi.y;
  node.hi_z = b.hi.z;
}

namespace {

class SubtreeBuilder {
 public:
  SubtreeBuilder(PrimRef* refs, int bins, int max_leaf_size, std::size_t morton_below,
                 kern::SdfBvhNode* nodes)
      : refs_(refs),
        bins_(bins),
        max_leaf_size_(max_leaf_size),
        morton_below_(morton_below),
        morton_(max_leaf_size),
        nodes_(nodes) {}

  std::size_t node_count() const { return used_; }

  void build(std::size_t node, const Range& range) {
    if (range.count() <= morton_below_) {
      morton_.build(refs_, range, node, nodes_, &used_);
      return;
    }
    const Split split = decide(range);
    if (split.kind == Split::Leaf) {
      nodes_[node].first = static_cast<std::int32_t>(range.begin);
      nodes_[node].count = static_cast<std::int32_t>(range.count());
      return;
    }
    Range left, right;
    partition(range, split, left, right);
    const std::size_t first = used_;
    used_ += 2;
    nodes_[node].first = static_cast<std::int32_t>(first);
    nodes_[node].count = 0;
    set_node_bounds(nodes_[first], left.bounds);
    set_node_bounds(nodes_[first + 1], right.bounds);
    build(first, left);
    build(first + 1, right);
  }

 private:
  Split decide(const Range& range) const {
    if (range.count() <= 1 || range.depth >= kMaxDepth) return Split();
    const BinMapping map(range.centroids, bins_);
    return choose_split_serial(refs_ + range.begin, range, map, max_leaf_size_);
  }

  // Splits range in place into left and right and gathers their bounds on the way.
  void partition(const Range& range, const Split& split, Range& left, Range& right) {
    if (split.kind == Split::Median) {
      const std::size_t mid = range.begin + range.count() / 2;
      left = Range{0, range.begin, mid, range.depth + 1, Box(), Box()};
      right = Range{0, mid, range.end, range.depth + 1, Box(), Box()};
      gather_bounds(left);
      gather_bounds(right);
      return;
    }
    Box4 bounds[2], centroids[2];
    auto grow = [&](int side, const PrimRef& r) {
      const Float4 lo = lo4(r), hi = hi4(r), c = lo + hi;
      bounds[side].grow(lo, hi);
      centroids[side].grow(c, c);
    };
    std::size_t i = range.begin, j = range.end;
    for (;;) {
      while (i < j && split.goes_left(refs_[i])) grow(0, refs_[i++]);
      while (i < j && !split.goes_left(refs_[j - 1])) grow(1, refs_[--j]);
      if (i >= j) break;
      std::swap(refs_[i], refs_[j - 1]);
      grow(0, refs_[i++]);
      grow(1, refs_[--j]);
    }
    left = Range{0, range.begin, i, range.depth + 1, bounds[0].box(), centroids[0].box()};
    right = Range{0, i, range.end, range.depth + 1, bounds[1].box(), centroids[1].box()};
  }

  void gather_bounds(Range& r) const {
    Box4 bounds, centroids;
    for (std::size_t i = r.begin; i < r.end; ++i) {
      const Float4 lo = lo4(refs_[i]), hi = hi4(refs_[i]);
      bounds.grow(lo, hi);
      const Float4 c = lo + hi;
      centroids.grow(c, c);
    }
    r.bounds = bounds.box();
    r.centroids = centroids.box();
  }

  PrimRef* refs_;
  int bins_;
  int max_leaf_size_;
  std::size_t morton_below_;
  MortonSubtrees morton_;
  kern::SdfBvhNode* nodes_;
  std::size_t used_ = 1;  // the root
};

}  // namespace

std::size_t build_subtree(PrimRef* refs, const Range& root, int bins, int max_leaf_size,
                          std::size_t morton_below, kern::SdfBvhNode* nodes) {
  set_node_bounds(nodes[0], root.bounds);
  SubtreeBuilder builder(refs, bins, max_leaf_size, morton_below, nodes);
  builder.build(0, root);
  return builder.node_count();
}

}  // namespace sdf::bvh_build
