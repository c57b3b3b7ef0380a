// SPDX-License-Identifier: GPL-3.0-or-later
// Pieces shared by the two halves of the BVH builder (bvh.cpp: the top levels, in parallel
// within each node; bvh_subtree.cpp: the subtrees below, one thread each): primitive
// references, SAH bins and the split decision. Both halves take the same decisions from the
// same bins, so where the line between them falls changes the speed, never the tree's shape.
#pragma once

#include <algorithm>
#include <cstdint>
#include <limits>

#include <glm/glm.hpp>

#include "accel/bvh_float4.h"
#include "traverse/sdf_bvh_traverse.h"

namespace sdf::bvh_build {

struct Box {
  glm::vec3 lo{std::numeric_limits<float>::infinity()};
  glm::vec3 hi{-std::numeric_limits<float>::infinity()};
  void grow(const Box& b) {
    lo = glm::min(lo, b.lo);
    hi = glm::max(hi, b.hi);
  }
  void grow(glm::vec3 p) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  float half_area() const {
    const glm::vec3 d = hi - lo;
    return (d.x < 0.0f) ? 0.0f : d.x * d.y + d.y * d.z + d.z * d.x;
  }
};

// One triangle as the builder sees it: its box and its index, 32 contiguous bytes, moved
// around by the partitions (Embree's PrimRef). Reading boxes in place instead of through an
// index array removes a cache miss per triangle per level.
struct PrimRef {
  glm::vec3 lo;
  std::uint32_t id;
  glm::vec3 hi;
  // The triangle's bins on x, y and z, a byte each, written by the last binning of its node
  // (BinMapping::record), so the partition that follows compares bytes instead of mapping
  // the centroid again.
  std::uint32_t bins;
};
static_assert(sizeof(PrimRef) == 32, "PrimRef is meant to fill half a cache line");

// A node's primitives [begin, end) of the reference array, with their bounds.
struct Range {
  std::uint32_t node = 0;  // where the node is stored
  std::size_t begin = 0, end = 0;
  int depth = 0;  // root = 0
  Box bounds;     // of the triangles
  // Of the centroids, taken as lo + hi: twice the box centre, the same factor for every
  // triangle, so binning can use it as is and save a multiply.
  Box centroids;
  std::size_t count() const { return end - begin; }
};

// Leaves deeper than this would overflow the traversal stack; the builder stops there.
constexpr int kMaxDepth = SDF_BVH_STACK_SIZE - 4;
// BvhConfig::bins at most: the bins live in fixed arrays (on the stack for a subtree).
constexpr int kMaxBins = 32;

// A box in SIMD form, for the binning loops.
struct Box4 {
  Float4 lo = Float4::splat(std::numeric_limits<float>::infinity());
  Float4 hi = Float4::splat(-std::numeric_limits<float>::infinity());
  void grow(Float4 l, Float4 h) {
    lo = min(lo, l);
    hi = max(hi, h);
  }
  void grow(const Box4& b) { grow(b.lo, b.hi); }
  Box box() const { return Box{glm::vec3(lo[0], lo[1], lo[2]), glm::vec3(hi[0], hi[1], hi[2])}; }
  // The same operations in the same order as Box::half_area.
  float half_area() const {
    const Float4 d = hi - lo;
    return d.x() < 0.0f ? 0.0f : (d * d.yzx()).sum3();
  }
};

inline Float4 lo4(const PrimRef& r) { return Float4::load(&r.lo.x); }
inline Float4 hi4(const PrimRef& r) { return Float4::load(&r.hi.x); }

// Maps a centroid to its bin on each axis. An axis with no extent maps everything to bin 0
// and is skipped by the sweeps.
struct BinMapping {
  float lo[3], scale[3];
  Float4 lo_all, scale_all, last_bin;
  int bins;
  BinMapping(const Box& centroids, int bin_count) : bins(bin_count) {
    for (int a = 0; a < 3; ++a) {
      const float extent = centroids.hi[a] - centroids.lo[a];
      lo[a] = centroids.lo[a];
      scale[a] = extent > 0.0f ? bins / extent : 0.0f;
    }
    lo_all = Float4::set(lo[0], lo[1], lo[2]);
    scale_all = Float4::set(scale[0], scale[1], scale[2]);
    last_bin = Float4::splat(static_cast<float>(bins - 1));
  }
  // Clamped in float before the conversion, so a centroid on the upper bound lands in the
  // last bin and no value is too large to convert.
  void bins_of(const PrimRef& r, int* out) const {
    const Float4 x = (lo4(r) + hi4(r) - lo_all) * scale_all;
    min(max(x, Float4::splat(0.0f)), last_bin).truncate(out);
  }
  bool splits(int axis) const { return scale[axis] > 0.0f; }
  // bins_of, also kept in r.bins.
  void record(PrimRef& r, int* out) const {
    bins_of(r, out);
    r.bins = static_cast<std::uint32_t>(out[0] | (out[1] << 8) | (out[2] << 16));
  }
};

// Boxes and counts per bin on each axis. Merging two sets of bins is exact (min, max and
// integer sums), so bins gathered in chunks on any number of threads equal the serial ones.
struct Bins {
  Box4 box[3][kMaxBins];
  std::uint32_t count[3][kMaxBins];
  explicit Bins(int bins) {
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < bins; ++b) {
        box[a][b] = Box4();
        count[a][b] = 0;
      }
  }
  // Also records each triangle's bins in it (BinMapping::record).
  void add(PrimRef* refs, std::size_t n, const BinMapping& map) {
    alignas(16) int bin[4];
    for (std::size_t i = 0; i < n; ++i) {
      const Float4 lo = lo4(refs[i]), hi = hi4(refs[i]);
      map.record(refs[i], bin);
      for (int a = 0; a < 3; ++a) {
        box[a][bin[a]].grow(lo, hi);
        ++count[a][bin[a]];
      }
    }
  }
  void merge(const Bins& other, int bins) {
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < bins; ++b) {
        box[a][b].grow(other.box[a][b]);
        count[a][b] += other.count[a][b];
      }
  }
};

// What to do with a node: keep it as a leaf, split it at a SAH bin boundary, or (when every
// centroid is equal) cut its list in two halves, the only way left to bound leaf size.
struct Split {
  enum Kind { Leaf, Sah, Median } kind = Leaf;
  int axis = -1;
  int bin = 0;  // Sah: the left side takes bins [0, bin]
  float cost = std::numeric_limits<float>::infinity();
  // From the bins recorded by the node's binning, so the side always agrees with the bins
  // the cost was computed from.
  bool goes_left(const PrimRef& r) const {
    return static_cast<int>((r.bins >> (8 * axis)) & 0xffu) <= bin;
  }
  // Keeps the first of equal costs: the lower axis, then the lower bin.
  void consider(float left_area, std::uint32_t left_count, float right_area,
                std::uint32_t right_count, int at_axis, int at_bin) {
    const float c = left_area * left_count + right_area * right_count;
    if (c < cost) {
      cost = c;
      axis = at_axis;
      bin = at_bin;
    }
  }
};

// Binned SAH (Wald 2007) with traversal and intersection costs of 1: split when that is
// cheaper than a leaf, and always once the leaf would be larger than allowed.
inline Split finish_split(Split best, const Range& range, int max_leaf_size) {
  const std::size_t count = range.count();
  const bool fits_in_leaf = count <= static_cast<std::size_t>(max_leaf_size);
  if (best.axis < 0) {
    best.kind = fits_in_leaf ? Split::Leaf : Split::Median;
    return best;
  }
  const float leaf_cost = range.bounds.half_area() * count;
  best.kind = (fits_in_leaf && leaf_cost <= best.cost + range.bounds.half_area()) ? Split::Leaf
                                                                                  : Split::Sah;
  return best;
}

// The SAH sweep over every bin boundary of every axis.
inline Split choose_split(const Range& range, const Bins& bins, const BinMapping& map,
                          int max_leaf_size) {
  const int n_bins = map.bins;
  Split best;
  for (int axis = 0; axis < 3; ++axis) {
    if (!map.splits(axis)) continue;
    float right_area[kMaxBins];
    std::uint32_t right_count[kMaxBins];
    Box4 acc;
    std::uint32_t n = 0;
    for (int b = n_bins - 1; b > 0; --b) {
      acc.grow(bins.box[axis][b]);
      n += bins.count[axis][b];
      right_area[b] = acc.half_area();
      right_count[b] = n;
    }
    acc = Box4();
    n = 0;
    for (int b = 0; b < n_bins - 1; ++b) {
      acc.grow(bins.box[axis][b]);
      n += bins.count[axis][b];
      if (n == 0 || right_count[b + 1] == 0) continue;
      best.consider(acc.half_area(), n, right_area[b + 1], right_count[b + 1], axis, b);
    }
  }
  return finish_split(best, range, max_leaf_size);
}

// The same decision as choose_split, for one thread, without the cost of clearing and
// sweeping empty bins: only the occupied bins are set up and swept, in order, found from a
// bit mask. The boundaries skipped are those after an empty bin, which have the same two
// sides (so the same cost) as the boundary after the occupied bin before them, and the sweep
// keeps the first of equal costs; the boxes come from the same min and max. So the choice is
// bit for bit the one of choose_split. Most nodes are small (half of them leaves), and for
// them the clearing and the sweep of every bin cost more than the binning itself.
// Also records each triangle's bins in it.
inline Split choose_split_serial(PrimRef* refs, const Range& range, const BinMapping& map,
                                 int max_leaf_size) {
  static_assert(kMaxBins <= 32, "occupied bins are a 32-bit mask");
  const std::size_t n = range.count();
  std::uint32_t occupied[3] = {0, 0, 0};
  for (std::size_t i = 0; i < n; ++i) {
    alignas(16) int bin[4];
    map.record(refs[i], bin);
    for (int a = 0; a < 3; ++a) occupied[a] |= 1u << bin[a];
  }
  // Only the occupied bins are set up (Float4 has no constructor, Box4 would clear all).
  Float4 bin_lo[3][kMaxBins], bin_hi[3][kMaxBins];
  std::uint32_t count[3][kMaxBins];
  int order[3][kMaxBins];  // the occupied bins, ascending
  int occupied_count[3] = {0, 0, 0};
  const Box4 empty;
  for (int axis = 0; axis < 3; ++axis) {
    for (std::uint32_t rest = occupied[axis]; rest != 0; rest &= rest - 1) {
      const int b = __builtin_ctz(rest);
      order[axis][occupied_count[axis]++] = b;
      bin_lo[axis][b] = empty.lo;
      bin_hi[axis][b] = empty.hi;
      count[axis][b] = 0;
    }
  }
  for (std::size_t i = 0; i < n; ++i) {
    const Float4 lo = lo4(refs[i]), hi = hi4(refs[i]);
    const std::uint32_t bins = refs[i].bins;
    for (int axis = 0; axis < 3; ++axis) {
      const int b = static_cast<int>((bins >> (8 * axis)) & 0xffu);
      bin_lo[axis][b] = min(bin_lo[axis][b], lo);
      bin_hi[axis][b] = max(bin_hi[axis][b], hi);
      ++count[axis][b];
    }
  }
  Split best;
  for (int axis = 0; axis < 3; ++axis) {
    if (!map.splits(axis)) continue;
    const int m = occupied_count[axis];
    float right_area[kMaxBins];
    std::uint32_t right_count[kMaxBins];
    Box4 acc;
    std::uint32_t k_count = 0;
    for (int k = m - 1; k > 0; --k) {
      const int b = order[axis][k];
      acc.grow(bin_lo[axis][b], bin_hi[axis][b]);
      k_count += count[axis][b];
      right_area[k] = acc.half_area();
      right_count[k] = k_count;
    }
    acc = Box4();
    k_count = 0;
    for (int k = 0; k + 1 < m; ++k) {
      const int b = order[axis][k];
      acc.grow(bin_lo[axis][b], bin_hi[axis][b]);
      k_count += count[axis][b];
      best.consider(acc.half_area(), k_count, right_area[k + 1], right_count[k + 1], axis, b);
    }
  }
  return finish_split(best, range, max_leaf_size);
}

}  // namespace sdf::bvh_build
