// SPDX-License-Identifier: GPL-3.0-or-later
// Projected-points smoothing as it was written first: serial, every stage on one thread. Kept
// as the specification the parallel version (native/post/smoothing_projected.cpp) and the OpenCL
// builder must match bit for bit: the same node array, the same smoothed values. Hence cells
// by multiplying with cells / side (as OpenCL computes them), node sums
// in fixed point (the same in any order) and nodes breadth first (as a device makes them).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "post/smoothing_projected.h"
#include "util/morton.h"

namespace sdf::test {

namespace reference_detail {

// Stable LSD radix sort of (key, index) pairs, 8 bits a pass.
inline void radix_sort(std::vector<std::uint64_t>& keys, std::vector<std::uint32_t>& index,
                       int bits) {
  std::vector<std::uint64_t> keys2(keys.size());
  std::vector<std::uint32_t> index2(index.size());
  for (int shift = 0; shift < bits; shift += 8) {
    std::size_t count[257] = {};
    for (std::uint64_t k : keys) ++count[((k >> shift) & 0xff) + 1];
    for (int b = 0; b < 256; ++b) count[b + 1] += count[b];
    for (std::size_t i = 0; i < keys.size(); ++i) {
      const std::size_t to = count[(keys[i] >> shift) & 0xff]++;
      keys2[to] = keys[i];
      index2[to] = index[i];
    }
    keys.swap(keys2);
    index.swap(index2);
  }
}

}  // namespace reference_detail

// Options are assumed valid (the tests pass valid ones). The fixed-point scale comes from the
// largest value and `count` (build_point_octree), or from `scale_top` and `scale_count` where
// given (smooth_projected: the input's largest value and all points, members or not).
inline std::vector<PointOctreeNode> reference_point_octree(const glm::vec3* points,
                                                           const float* values, std::size_t count,
                                                           const ProjectedOptions& options,
                                                           float scale_top = -1.0f,
                                                           std::size_t scale_count = 0) {
  using namespace reference_detail;
  std::vector<PointOctreeNode> nodes;
  if (count == 0) return nodes;
  glm::vec3 lo(std::numeric_limits<float>::infinity()), hi(-std::numeric_limits<float>::infinity());
  for (std::size_t i = 0; i < count; ++i) {
    lo = glm::min(lo, points[i]);
    hi = glm::max(hi, points[i]);
  }
  const glm::vec3 extent = hi - lo;
  float side = std::max(extent.x, std::max(extent.y, extent.z));
  const float magnitude = std::max(glm::length(lo), glm::length(hi));
  side = std::max(side * (1.0f + 1.0f / 1024.0f), std::max(magnitude * 1e-6f, 1e-30f));
  const glm::vec3 center = 0.5f * (lo + hi);

  const int depth = options.max_depth;
  const std::uint32_t cells = std::uint32_t{1} << depth;
  const float scale = static_cast<float>(cells) / side;
  const glm::vec3 corner = center - glm::vec3(0.5f * side);
  // Fixed point: values below 2^(62 - bits of count) units, so sums stay below 2^62.
  float top = scale_top;
  if (top < 0.0f)
    for (std::size_t i = 0; i < count; ++i) top = std::max(top, values[i]);
  if (scale_count == 0) scale_count = count;
  int exponent = 0, count_bits = 0;
  std::frexp(top, &exponent);
  while ((scale_count >> count_bits) != 0) ++count_bits;
  const int fixed_shift = 62 - count_bits - exponent;
  std::vector<std::uint64_t> keys(count);
  std::vector<std::uint32_t> order(count);
  for (std::size_t i = 0; i < count; ++i) {
    std::uint64_t key = 0;
    for (int a = 0; a < 3; ++a) {
      const float c = std::floor((points[i][a] - corner[a]) * scale);
      const std::uint64_t cell =
          c > 0.0f ? std::min<std::uint64_t>(cells - 1, static_cast<std::uint64_t>(c)) : 0;
      key |= spread_bits_21(cell) << a;
    }
    keys[i] = key;
    order[i] = static_cast<std::uint32_t>(i);
  }
  radix_sort(keys, order, 3 * depth);
  std::vector<std::uint64_t> prefix(count + 1, 0);
  for (std::size_t i = 0; i < count; ++i)
    prefix[i + 1] =
        prefix[i] + static_cast<std::uint64_t>(std::ldexp(values[order[i]], fixed_shift));

  const bool by_min = options.branch_on == ProjectedOptions::Branch::Min;
  std::vector<float> sorted_values;
  if (by_min) {
    sorted_values.resize(count);
    for (std::size_t i = 0; i < count; ++i) sorted_values[i] = values[order[i]];
  }

  auto make_node = [&](glm::vec3 c, float half, std::uint32_t begin, std::uint32_t end) {
    PointOctreeNode node;
    node.center[0] = c.x;
    node.center[1] = c.y;
    node.center[2] = c.z;
    node.half_side = half;
    node.count = end - begin;
    node.mean = static_cast<float>(
        std::ldexp(static_cast<double>(prefix[end] - prefix[begin]) / node.count, -fixed_shift));
    node.first_child = -1;
    node.child_count = 0;
    return node;
  };

  const double branch_above = options.min_points * static_cast<double>(count);
  struct Task {
    std::uint32_t node, begin, end;
    int level;
  };
  std::vector<Task> queue;  // breadth first: tasks are taken in the order they were made
  nodes.push_back(make_node(center, 0.5f * side, 0, static_cast<std::uint32_t>(count)));
  queue.push_back({0, 0, static_cast<std::uint32_t>(count), 0});
  for (std::size_t next = 0; next < queue.size(); ++next) {
    const Task t = queue[next];
    const PointOctreeNode node = nodes[t.node];
    if (t.level >= depth || !(static_cast<double>(node.count) > branch_above)) continue;
    float test_value = node.mean;
    if (by_min)
      test_value =
          *std::min_element(sorted_values.begin() + t.begin, sorted_values.begin() + t.end);
    const bool branch = test_value <= options.node_size_ratio * 2.0 * node.half_side;
    if (!branch) continue;
    const int shift = 3 * (depth - t.level - 1);
    const std::uint32_t first = static_cast<std::uint32_t>(nodes.size());
    std::uint32_t begin = t.begin;
    for (std::uint32_t octant = 0; octant < 8 && begin < t.end; ++octant) {
      const std::uint32_t end = static_cast<std::uint32_t>(
          std::partition_point(keys.begin() + begin, keys.begin() + t.end,
                               [&](std::uint64_t k) { return ((k >> shift) & 7u) <= octant; }) -
          keys.begin());
      if (end == begin) continue;
      const float q = 0.5f * node.half_side;
      const glm::vec3 c(node.center[0] + ((octant & 1) ? q : -q),
                        node.center[1] + ((octant & 2) ? q : -q),
                        node.center[2] + ((octant & 4) ? q : -q));
      queue.push_back({static_cast<std::uint32_t>(nodes.size()), begin, end, t.level + 1});
      nodes.push_back(make_node(c, q, begin, end));
      begin = end;
    }
    nodes[t.node].first_child = static_cast<std::int32_t>(first);
    nodes[t.node].child_count = static_cast<std::uint32_t>(nodes.size()) - first;
  }
  return nodes;
}

// smooth_projected() as it was: sample_points(), the members copied out, the serial builder
// above, the shared per-point kernel. Values are assumed valid (>= 0, finite).
inline std::vector<float> reference_smooth_projected(const Mesh& mesh, PointKind kind,
                                                     const float* values,
                                                     const ProjectedOptions& options) {
  const SamplePoints sp = sample_points(mesh, kind, 1);
  const std::size_t n = sp.size();
  float lo = std::numeric_limits<float>::infinity(), hi = -lo;
  for (std::size_t i = 0; i < n; ++i) {
    lo = std::min(lo, values[i]);
    hi = std::max(hi, values[i]);
  }
  std::vector<float> current(values, values + n);
  if (n == 0 || lo == hi) return current;
  std::vector<std::uint32_t> members;
  for (std::uint32_t i = 0; i < n; ++i)
    if (sp.axes[i] != glm::vec3(0.0f)) members.push_back(i);
  if (members.empty()) return current;
  std::vector<glm::vec3> projected(n), tree_points(members.size());
  std::vector<float> tree_values(members.size()), next(n);
  for (int it = 0; it < options.iterations; ++it) {
    for (std::size_t i = 0; i < n; ++i)
      projected[i] = sp.origins[i] + sp.axes[i] * (0.5f * current[i]);
    for (std::size_t j = 0; j < members.size(); ++j) {
      tree_points[j] = projected[members[j]];
      tree_values[j] = current[members[j]];
    }
    const std::vector<PointOctreeNode> nodes =
        reference_point_octree(tree_points.data(), tree_values.data(), members.size(), options, hi,
                               n);  // the input's largest value: later iterations stay below it
    for (std::size_t i = 0; i < n; ++i)
      next[i] = kern::sdf_smooth_projected_point(nodes.data(), projected[i], current[i],
                                                 static_cast<float>(options.radius), lo, hi);
    current.swap(next);
  }
  return current;
}

}  // namespace sdf::test
