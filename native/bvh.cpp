// SPDX-License-Identifier: GPL-3.0-or-later
#include "bvh.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <thread>

#include "../kernels/sdf_bvh_traverse.h"
#include "parallel.h"

namespace sdf {

namespace {

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

// Leaves deeper than this would overflow the traversal stack; the builder stops there.
constexpr int kMaxDepth = SDF_BVH_STACK_SIZE - 4;
// Subtrees at least this large are built on a thread of their own.
constexpr std::size_t kParallelSubtree = 20000;

class Builder {
 public:
  Builder(const std::vector<Box>& boxes, const std::vector<glm::vec3>& centroids,
          std::vector<std::uint32_t>& prims, std::vector<kern::SdfBvhNode>& nodes,
          const BvhConfig& config)
      : boxes_(boxes), centroids_(centroids), prims_(prims), nodes_(nodes), config_(config) {}

  void build(std::uint32_t node, std::size_t begin, std::size_t end, int depth) {
    Box bounds, centroid_bounds;
    for (std::size_t i = begin; i < end; ++i) {
      bounds.grow(boxes_[prims_[i]]);
      centroid_bounds.grow(centroids_[prims_[i]]);
    }
    set_bounds(node, bounds);
    const std::size_t count = end - begin;
    std::size_t mid = begin;
    if (count > 1 && depth < kMaxDepth) mid = split(begin, end, bounds, centroid_bounds);
    if (mid == begin) {
      make_leaf(node, begin, count);
      return;
    }
    const std::uint32_t left = next_node_.fetch_add(2);
    nodes_[node].first = static_cast<std::int32_t>(left);
    nodes_[node].count = 0;
    if (mid - begin >= kParallelSubtree && end - mid >= kParallelSubtree &&
        spawned_.fetch_add(1) < resolve_threads(config_.threads) * 2) {
      std::thread helper([&, left, begin, mid, depth] { build(left, begin, mid, depth + 1); });
      build(left + 1, mid, end, depth + 1);
      helper.join();
    } else {
      build(left, begin, mid, depth + 1);
      build(left + 1, mid, end, depth + 1);
    }
  }

  std::uint32_t node_count() const { return next_node_.load(); }

 private:
  // Partitions prims_[begin, end) and returns the split position, or begin for "make a leaf".
  std::size_t split(std::size_t begin, std::size_t end, const Box& bounds,
                    const Box& centroid_bounds) {
    const std::size_t count = end - begin;
    const int bins = config_.bins;
    float best_cost = std::numeric_limits<float>::infinity();
    int best_axis = -1, best_bin = 0;
    for (int axis = 0; axis < 3; ++axis) {
      const float lo = centroid_bounds.lo[axis], extent = centroid_bounds.hi[axis] - lo;
      if (!(extent > 0.0f)) continue;
      const float scale = bins / extent;
      std::vector<Box> bin_box(bins);
      std::vector<std::size_t> bin_count(bins, 0);
      for (std::size_t i = begin; i < end; ++i) {
        const int b = bin_of(centroids_[prims_[i]][axis], lo, scale);
        bin_box[b].grow(boxes_[prims_[i]]);
        ++bin_count[b];
      }
      // Sweep from the right to get the right-hand areas, then from the left.
      std::vector<float> right_area(bins);
      std::vector<std::size_t> right_count(bins);
      Box acc;
      std::size_t n = 0;
      for (int b = bins - 1; b > 0; --b) {
        acc.grow(bin_box[b]);
        n += bin_count[b];
        right_area[b] = acc.half_area();
        right_count[b] = n;
      }
      acc = Box();
      n = 0;
      for (int b = 0; b < bins - 1; ++b) {
        acc.grow(bin_box[b]);
        n += bin_count[b];
        if (n == 0 || right_count[b + 1] == 0) continue;
        const float cost = acc.half_area() * n + right_area[b + 1] * right_count[b + 1];
        if (cost < best_cost) {
          best_cost = cost;
          best_axis = axis;
          best_bin = b;
        }
      }
    }
    const float leaf_cost = bounds.half_area() * count;
    // SAH with traversal and intersection costs of 1: split when it is cheaper, and always
    // once the leaf would be larger than allowed.
    if (best_axis < 0) {
      return count > static_cast<std::size_t>(config_.max_leaf_size) ? median_split(begin, end)
                                                                      : begin;
    }
    if (count <= static_cast<std::size_t>(config_.max_leaf_size) &&
        leaf_cost <= best_cost + bounds.half_area())
      return begin;
    const float lo = centroid_bounds.lo[best_axis];
    const float scale = bins / (centroid_bounds.hi[best_axis] - lo);
    auto middle = std::partition(prims_.begin() + begin, prims_.begin() + end,
                                 [&](std::uint32_t p) {
                                   return bin_of(centroids_[p][best_axis], lo, scale) <= best_bin;
                                 });
    return static_cast<std::size_t>(middle - prims_.begin());
  }

  // Every centroid is equal: split the list in two halves, the only way to bound leaf size.
  std::size_t median_split(std::size_t begin, std::size_t end) { return begin + (end - begin) / 2; }

  int bin_of(float c, float lo, float scale) const {
    const int b = static_cast<int>((c - lo) * scale);
    return std::min(std::max(b, 0), config_.bins - 1);
  }

  void set_bounds(std::uint32_t node, const Box& b) {
    kern::SdfBvhNode& n = nodes_[node];
    n.lo_x = b.lo.x;
    n.lo_y = b.lo.y;
    n.lo_z = b.lo.z;
    n.hi_x = b.hi.x;
    n.hi_y = b.hi.y;
    n.hi_z = b.hi.z;
  }

  void make_leaf(std::uint32_t node, std::size_t begin, std::size_t count) {
    nodes_[node].first = static_cast<std::int32_t>(begin);
    nodes_[node].count = static_cast<std::int32_t>(count);
  }

  const std::vector<Box>& boxes_;
  const std::vector<glm::vec3>& centroids_;
  std::vector<std::uint32_t>& prims_;
  std::vector<kern::SdfBvhNode>& nodes_;
  const BvhConfig& config_;
  std::atomic<std::uint32_t> next_node_{1};
  std::atomic<unsigned> spawned_{0};
};

}  // namespace

Bvh build_bvh(const Mesh& mesh, const BvhConfig& config) {
  if (config.max_leaf_size < 1 || config.bins < 2)
    throw std::invalid_argument("BvhConfig: max_leaf_size >= 1 and bins >= 2 are required");
  // Zero-area triangles can never be hit (Moller-Trumbore's determinant is 0): leave them out.
  std::vector<std::uint32_t> prims;
  prims.reserve(mesh.triangles.size());
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    const glm::vec3 n = face_area_normal(mesh, f);
    if (n.x != 0.0f || n.y != 0.0f || n.z != 0.0f) prims.push_back(static_cast<std::uint32_t>(f));
  }
  Bvh bvh;
  if (prims.empty()) return bvh;

  std::vector<Box> boxes(mesh.triangles.size());
  std::vector<glm::vec3> centroids(mesh.triangles.size());
  parallel_for(prims.size(), 16384, config.threads, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      const std::uint32_t f = prims[i];
      const glm::uvec3 t = mesh.triangles[f];
      Box box;
      box.grow(mesh.vertices[t.x]);
      box.grow(mesh.vertices[t.y]);
      box.grow(mesh.vertices[t.z]);
      boxes[f] = box;
      centroids[f] = 0.5f * (box.lo + box.hi);
    }
  });

  bvh.nodes.resize(2 * prims.size());
  Builder builder(boxes, centroids, prims, bvh.nodes, config);
  builder.build(0, 0, prims.size(), 0);
  bvh.nodes.resize(builder.node_count());

  bvh.triangles.resize(prims.size());
  for (std::size_t i = 0; i < prims.size(); ++i) {
    const glm::uvec3 t = mesh.triangles[prims[i]];
    const glm::vec3 v0 = mesh.vertices[t.x];
    const glm::vec3 e1 = mesh.vertices[t.y] - v0, e2 = mesh.vertices[t.z] - v0;
    bvh.triangles[i] = kern::SdfTriangle{v0.x, v0.y, v0.z, static_cast<std::int32_t>(prims[i]),
                                         e1.x, e1.y, e1.z, 0.0f, e2.x, e2.y, e2.z, 0.0f};
  }
  return bvh;
}

int bvh_depth(const Bvh& bvh) {
  if (bvh.nodes.empty()) return 0;
  int deepest = 0;
  std::vector<std::pair<std::int32_t, int>> stack{{0, 0}};
  while (!stack.empty()) {
    const auto [index, depth] = stack.back();
    stack.pop_back();
    deepest = std::max(deepest, depth);
    const kern::SdfBvhNode& n = bvh.nodes[index];
    if (n.count == 0) {
      stack.push_back({n.first, depth + 1});
      stack.push_back({n.first + 1, depth + 1});
    }
  }
  return deepest;
}

}  // namespace sdf
