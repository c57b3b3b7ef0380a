// SPDX-License-Identifier: GPL-3.0-or-later
#include "smoothing_projected.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace sdf {

namespace {

constexpr int kMaxDepth = SDF_POINT_MAX_DEPTH;  // 3 bits per level in a 64-bit Morton key

// Spreads the low 21 bits of x three apart (bit i goes to bit 3i).
std::uint64_t spread3(std::uint64_t x) {
  x &= 0x1fffffull;
  x = (x | x << 32) & 0x1f00000000ffffull;
  x = (x | x << 16) & 0x1f0000ff0000ffull;
  x = (x | x << 8) & 0x100f00f00f00f00full;
  x = (x | x << 4) & 0x10c30c30c30c30c3ull;
  x = (x | x << 2) & 0x1249249249249249ull;
  return x;
}

// LSD radix sort of (key, index) pairs on the low `bits` bits of the keys, 8 bits a pass:
// linear time, and stable, so equal keys keep index order (the build is deterministic).
void radix_sort(std::vector<std::uint64_t>& keys, std::vector<std::uint32_t>& index, int bits) {
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

}  // namespace

std::vector<PointOctreeNode> build_point_octree(const glm::vec3* points, const float* values,
                                                std::size_t count,
                                                const ProjectedOptions& options) {
  if (options.max_depth < 0 || options.max_depth > kMaxDepth)
    throw std::invalid_argument("max_depth must be in [0, " + std::to_string(kMaxDepth) +
                                "], got " + std::to_string(options.max_depth));
  if (!(options.min_points >= 0.0 && options.min_points <= 1.0))
    throw std::invalid_argument("min_points must be a fraction in [0, 1]");
  if (!(options.node_size_ratio >= 0.0) || !std::isfinite(options.node_size_ratio))
    throw std::invalid_argument("node_size_ratio must be a finite number >= 0");
  std::vector<PointOctreeNode> nodes;
  if (count == 0) return nodes;
  if (count > std::numeric_limits<std::uint32_t>::max())
    throw std::invalid_argument("too many points for the octree");

  // The root: the bounding cube of the points, a little larger so every point falls strictly
  // inside, and never of zero size (all points may coincide, as on a sphere).
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

  // Points in Morton order at the deepest level: every node is then a contiguous range.
  const int depth = options.max_depth;
  const double cells = std::ldexp(1.0, depth);
  const glm::vec3 corner = center - glm::vec3(0.5f * side);
  std::vector<std::uint64_t> keys(count);
  std::vector<std::uint32_t> order(count);
  for (std::size_t i = 0; i < count; ++i) {
    std::uint64_t key = 0;
    for (int a = 0; a < 3; ++a) {
      const double c = std::floor((points[i][a] - corner[a]) / side * cells);
      const std::uint64_t cell = static_cast<std::uint64_t>(std::min(cells - 1.0, std::max(0.0, c)));
      key |= spread3(cell) << a;
    }
    keys[i] = key;
    order[i] = static_cast<std::uint32_t>(i);
  }
  radix_sort(keys, order, 3 * depth);
  std::vector<double> prefix(count + 1, 0.0);  // sums of values in Morton order
  for (std::size_t i = 0; i < count; ++i) prefix[i + 1] = prefix[i] + values[order[i]];

  // Branching on the minimum: taken over the node's run when it is tested (points x depth).
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
    node.mean = static_cast<float>((prefix[end] - prefix[begin]) / node.count);
    node.first_child = -1;
    node.child_count = 0;
    return node;
  };

  const double branch_above = options.min_points * static_cast<double>(count);
  struct Task {
    std::uint32_t node, begin, end;
    int level;
  };
  std::vector<Task> stack;
  nodes.push_back(make_node(center, 0.5f * side, 0, static_cast<std::uint32_t>(count)));
  stack.push_back({0, 0, static_cast<std::uint32_t>(count), 0});
  while (!stack.empty()) {
    const Task t = stack.back();
    stack.pop_back();
    const PointOctreeNode node = nodes[t.node];
    if (t.level >= depth || !(static_cast<double>(node.count) > branch_above)) continue;
    float test_value = node.mean;
    if (by_min)
      test_value = *std::min_element(sorted_values.begin() + t.begin, sorted_values.begin() + t.end);
    const bool branch = test_value <= options.node_size_ratio * 2.0 * node.half_side;
    if (!branch) continue;
    const int shift = 3 * (depth - t.level - 1);
    const std::uint32_t first = static_cast<std::uint32_t>(nodes.size());
    std::uint32_t begin = t.begin;
    for (std::uint32_t octant = 0; octant < 8 && begin < t.end; ++octant) {
      // The end of this octant's run in the sorted keys.
      const std::uint32_t end = static_cast<std::uint32_t>(
          std::partition_point(keys.begin() + begin, keys.begin() + t.end,
                               [&](std::uint64_t k) { return ((k >> shift) & 7u) <= octant; }) -
          keys.begin());
      if (end == begin) continue;
      const float q = 0.5f * node.half_side;
      const glm::vec3 c(node.center[0] + ((octant & 1) ? q : -q),
                        node.center[1] + ((octant & 2) ? q : -q),
                        node.center[2] + ((octant & 4) ? q : -q));
      stack.push_back({static_cast<std::uint32_t>(nodes.size()), begin, end, t.level + 1});
      nodes.push_back(make_node(c, q, begin, end));
      begin = end;
    }
    nodes[t.node].first_child = static_cast<std::int32_t>(first);
    nodes[t.node].child_count = static_cast<std::uint32_t>(nodes.size()) - first;
  }
  return nodes;
}

// ---- Per-point work: kernels/sdf_smooth_projected.h (shared with the OpenCL kernels). ----
float cube_fraction_in_sphere(float side, float distance, float radius) {
  return kern::sdf_cube_fraction_in_sphere(side, distance, radius);
}

bool gather_sphere(const PointOctreeNode* nodes, glm::vec3 center, float radius, float* mean) {
  return kern::sdf_gather_sphere(nodes, center, radius, mean) != 0;
}

std::vector<float> smooth_projected(const Mesh& mesh, PointKind kind, const float* values,
                                    const ProjectedOptions& options, const ProgressFn& progress,
                                    double progress_from, double progress_to,
                                    const ProjectedGatherFn& gather) {
  if (options.iterations < 0)
    throw std::invalid_argument("iterations must be >= 0, got " +
                                std::to_string(options.iterations));
  const SamplePoints sp = sample_points(mesh, kind);
  const std::size_t n = sp.size();
  float lo = std::numeric_limits<float>::infinity(), hi = -lo;
  for (std::size_t i = 0; i < n; ++i) {
    if (!std::isfinite(values[i]) || values[i] < 0.0f)
      throw std::invalid_argument("value " + std::to_string(i) +
                                  " is negative or not finite (projected smoothing needs the "
                                  "SDF, a length >= 0)");
    lo = std::min(lo, values[i]);
    hi = std::max(hi, values[i]);
  }
  // Options are checked even when there is nothing to do.
  build_point_octree(nullptr, nullptr, 0, options);
  std::vector<float> current(values, values + n);
  if (n == 0 || lo == hi) return current;

  // Points with no inward axis (zero-area faces, lone vertices) are not projected: they stay
  // out of the tree, but still gather around their own position.
  std::vector<std::uint32_t> members;
  for (std::uint32_t i = 0; i < n; ++i)
    if (sp.axes[i] != glm::vec3(0.0f)) members.push_back(i);
  if (members.empty()) return current;

  if (progress && !progress(progress_from)) throw Cancelled();
  std::vector<glm::vec3> projected(n), tree_points(members.size());
  std::vector<float> tree_values(members.size()), next(n);
  for (int it = 0; it < options.iterations; ++it) {
    for (std::size_t i = 0; i < n; ++i) projected[i] = sp.origins[i] + sp.axes[i] * (0.5f * current[i]);
    for (std::size_t j = 0; j < members.size(); ++j) {
      tree_points[j] = projected[members[j]];
      tree_values[j] = current[members[j]];
    }
    const std::vector<PointOctreeNode> nodes =
        build_point_octree(tree_points.data(), tree_values.data(), members.size(), options);
    const double span = (progress_to - progress_from) / options.iterations;
    if (gather) {
      gather(nodes, projected, current, lo, hi, next);
      current.swap(next);
      if (progress && !progress(progress_from + (it + 1) * span)) throw Cancelled();
      continue;
    }
    parallel_for(
        n, 1024, options.threads,
        [&](std::size_t begin, std::size_t end) {
          for (std::size_t i = begin; i < end; ++i)
            next[i] = kern::sdf_smooth_projected_point(nodes.data(), projected[i], current[i], lo, hi);
        },
        progress, progress_from + it * span, progress_from + (it + 1) * span);
    current.swap(next);
  }
  if (progress && !progress(progress_to)) throw Cancelled();
  return current;
}

}  // namespace sdf
