// SPDX-License-Identifier: GPL-3.0-or-later
#include "accel/octree.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace sdf {

// In double: the plane test's products are the cube of a length (edge x edge, then a point),
// past float's range for a mesh ~1e13 wide (make_mesh accepts 1e30). An overflow made every
// child reject a triangle its parent held (compute fuzzer).
bool triangle_overlaps_box(glm::vec3 box_center, glm::vec3 box_half, glm::vec3 p0, glm::vec3 p1,
                           glm::vec3 p2) {
  const glm::dvec3 center(box_center), half(box_half);
  const glm::dvec3 v0 = glm::dvec3(p0) - center, v1 = glm::dvec3(p1) - center,
                   v2 = glm::dvec3(p2) - center;
  // Box axes: the triangle's bounds against the box's.
  for (int a = 0; a < 3; ++a) {
    const double lo = std::min(v0[a], std::min(v1[a], v2[a]));
    const double hi = std::max(v0[a], std::max(v1[a], v2[a]));
    if (lo > half[a] || hi < -half[a]) return false;
  }
  const glm::dvec3 e0 = v1 - v0, e1 = v2 - v1, e2 = v0 - v2;
  // The nine cross products of the box axes with the edges.
  const glm::dvec3 edges[3] = {e0, e1, e2};
  const glm::dvec3 axes[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  for (const glm::dvec3& e : edges) {
    for (const glm::dvec3& u : axes) {
      const glm::dvec3 axis = glm::cross(u, e);
      const double d0 = glm::dot(v0, axis), d1 = glm::dot(v1, axis), d2 = glm::dot(v2, axis);
      const double r =
          half.x * std::fabs(axis.x) + half.y * std::fabs(axis.y) + half.z * std::fabs(axis.z);
      if (std::min(d0, std::min(d1, d2)) > r || std::max(d0, std::max(d1, d2)) < -r) return false;
    }
  }
  // The triangle's plane against the box.
  const glm::dvec3 n = glm::cross(e0, e1);
  const double r = half.x * std::fabs(n.x) + half.y * std::fabs(n.y) + half.z * std::fabs(n.z);
  return std::fabs(glm::dot(n, v0)) <= r;
}

namespace {

class OctreeBuilder {
 public:
  OctreeBuilder(const Mesh& mesh, const OctreeConfig& config, Octree& out)
      : mesh_(mesh), config_(config), out_(out) {}

  void build(std::uint32_t node, glm::vec3 lo, float size, const std::vector<std::uint32_t>& tris,
             int depth) {
    out_.depth = std::max(out_.depth, depth);
    if (depth >= config_.max_depth || tris.size() <= static_cast<std::size_t>(config_.leaf_size)) {
      make_leaf(node, tris);
      return;
    }
    const float half = 0.5f * size;
    // Cells grow by a hair so a triangle lying exactly on a cell face is in both cells.
    const glm::vec3 half_extent(0.5f * half * (1.0f + 1e-5f));
    std::vector<std::uint32_t> children[8];
    glm::vec3 child_lo[8];
    std::uint32_t mask = 0;
    for (int octant = 0; octant < 8; ++octant) {
      child_lo[octant] = lo + glm::vec3(octant & 1 ? half : 0.0f, octant & 2 ? half : 0.0f,
                                        octant & 4 ? half : 0.0f);
      const glm::vec3 center = child_lo[octant] + glm::vec3(0.5f * half);
      for (std::uint32_t t : tris) {
        const glm::uvec3 f = mesh_.triangles[t];
        if (triangle_overlaps_box(center, half_extent, mesh_.vertices[f.x], mesh_.vertices[f.y],
                                  mesh_.vertices[f.z]))
          children[octant].push_back(t);
      }
      if (!children[octant].empty()) mask |= 1u << octant;
    }
    // A node whose triangles all touch it only within its margin (the grown parent cell) has
    // no child; mask 0 would read as a leaf with no leaf words behind its pointer.
    if (mask == 0) {
      make_leaf(node, tris);
      return;
    }
    const std::uint32_t first = static_cast<std::uint32_t>(out_.nodes.size());
    const int count = __builtin_popcount(mask);
    check_pointer(first + count, "nodes");
    out_.nodes.resize(first + count);
    out_.nodes[node] = (first << 8) | mask;
    std::uint32_t child = first;
    for (int octant = 0; octant < 8; ++octant) {
      if (!(mask & (1u << octant))) continue;
      build(child++, child_lo[octant], half, children[octant], depth + 1);
    }
  }

 private:
  void make_leaf(std::uint32_t node, const std::vector<std::uint32_t>& tris) {
    const std::uint32_t pointer = static_cast<std::uint32_t>(out_.leaves.size());
    check_pointer(pointer + 1 + tris.size(), "leaf words");
    out_.leaves.push_back(static_cast<std::uint32_t>(tris.size()));
    out_.leaves.insert(out_.leaves.end(), tris.begin(), tris.end());
    out_.nodes[node] = pointer << 8;
  }

  static void check_pointer(std::size_t needed, const char* what) {
    if (needed > SDF_OCTREE_MAX_POINTER)
      throw std::length_error(std::string("the octree needs more than 2^24 ") + what +
                              ", the limit of the paper's 24-bit child pointers; lower the "
                              "octree's depth (octree_depth), raise its leaf size "
                              "(octree_leaf_size), or use accel='bvh'");
  }

  const Mesh& mesh_;
  const OctreeConfig& config_;
  Octree& out_;
};

}  // namespace

Octree build_octree(const Mesh& mesh, const OctreeConfig& config) {
  if (config.max_depth < 0 || config.max_depth > SDF_OCTREE_MAX_DEPTH)
    throw std::invalid_argument("octree max_depth must be in [0, " +
                                std::to_string(SDF_OCTREE_MAX_DEPTH) + "], got " +
                                std::to_string(config.max_depth));
  if (config.leaf_size < 1)
    throw std::invalid_argument("octree leaf_size must be at least 1, got " +
                                std::to_string(config.leaf_size));
  Octree tree;
  std::vector<std::uint32_t> tris;
  tree.triangles.resize(mesh.triangles.size());
  glm::vec3 lo(INFINITY), hi(-INFINITY);
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    const glm::uvec3 t = mesh.triangles[f];
    const glm::vec3 v0 = mesh.vertices[t.x], e1 = mesh.vertices[t.y] - v0,
                    e2 = mesh.vertices[t.z] - v0;
    tree.triangles[f] = kern::SdfTriangle{v0.x, v0.y, v0.z, static_cast<std::int32_t>(f),
                                          e1.x, e1.y, e1.z, 0.0f,
                                          e2.x, e2.y, e2.z, 0.0f};
    const glm::vec3 n = glm::cross(e1, e2);
    if (n.x == 0.0f && n.y == 0.0f && n.z == 0.0f) continue;  // never hit: left out
    tris.push_back(static_cast<std::uint32_t>(f));
    for (const std::uint32_t v : {t.x, t.y, t.z}) {
      lo = glm::min(lo, mesh.vertices[v]);
      hi = glm::max(hi, mesh.vertices[v]);
    }
  }
  if (tris.empty()) lo = hi = glm::vec3(0.0f);
  // A cube around the bounds, grown slightly so no triangle touches the root's faces.
  const glm::vec3 extent = hi - lo;
  const float size = std::max(extent.x, std::max(extent.y, extent.z)) * (1.0f + 1e-4f) + 1e-30f;
  const glm::vec3 root_lo = 0.5f * (lo + hi) - glm::vec3(0.5f * size);
  tree.root = kern::SdfOctreeRoot{root_lo.x, root_lo.y, root_lo.z, size};
  tree.nodes.resize(1);
  OctreeBuilder(mesh, config, tree).build(0, root_lo, size, tris, 0);
  return tree;
}

}  // namespace sdf
