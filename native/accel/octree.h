// SPDX-License-Identifier: GPL-3.0-or-later
// The paper's octree (section 4.1-4.2, Figures 4 and 5), built top-down on the CPU: a triangle
// goes into every cell it overlaps (Akenine-Moller's triangle-box test), cells split until
// they hold few triangles or reach the maximum depth. Layout: kernels/traverse/sdf_octree.h.
#pragma once

#include <cstdint>
#include <vector>

#include "mesh/mesh.h"
#include "traverse/sdf_octree.h"

namespace sdf {

struct OctreeConfig {
  int max_depth = 10;  // paper: 10 (Table 2 measures 2..14); at most SDF_OCTREE_MAX_DEPTH
  int leaf_size = 8;   // a cell with at most this many triangles is not split further
};

struct Octree {
  std::vector<std::uint32_t> nodes;          // child descriptors; nodes[0] is the root
  std::vector<std::uint32_t> leaves;         // per leaf: count, then triangle indices
  std::vector<kern::SdfTriangle> triangles;  // every triangle in input order (id = index)
  kern::SdfOctreeRoot root{};
  int depth = 0;  // deepest level reached (root = 0)
};

// Throws std::invalid_argument for a bad config, std::length_error when the tree would need
// more than 2^24 nodes or leaf words (the 24-bit pointers of the paper's encoding).
Octree build_octree(const Mesh& mesh, const OctreeConfig& config = OctreeConfig());

// Akenine-Moller (2001): does the triangle overlap the box (centre, half size)? Separating
// axis test on the box axes, the triangle normal and the nine edge cross products.
bool triangle_overlaps_box(glm::vec3 center, glm::vec3 half, glm::vec3 v0, glm::vec3 v1,
                           glm::vec3 v2);

}  // namespace sdf
