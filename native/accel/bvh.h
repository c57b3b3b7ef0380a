// SPDX-License-Identifier: GPL-3.0-or-later
// Stage 2: a bounding volume hierarchy over the triangles, built with binned SAH (Wald 2007)
// in parallel, then packed into the flat arrays that the CPU engine and the kernels traverse.
#pragma once

#include <vector>

#include "common/sdf_layout.h"
#include "mesh/mesh.h"
#include "util/uninitialized_vector.h"

namespace sdf {

struct BvhConfig {
  // Triangles per leaf at most, unless they cannot be separated. Small leaves suit SDF rays,
  // which stop at the first hit (2 to 4 measured best for Moller-Trumbore leaves).
  int max_leaf_size = 4;
  // SAH bins per axis: 16 is within a percent or two of a full sweep (Wald 2007).
  int bins = 16;
  // Nodes of at most this many triangles are split at Morton-code bits instead of by SAH
  // (bvh_morton.h): 0 builds SAH everywhere, the best tree; larger values build faster.
  std::size_t morton_below = 0;
  unsigned threads = 0;  // 0: every core
};

struct Bvh {
  UninitializedVector<kern::SdfBvhNode> nodes;       // nodes[0] is the root
  UninitializedVector<kern::SdfTriangle> triangles;  // in leaf order; zero-area triangles left out
  bool empty() const { return triangles.empty(); }
};

Bvh build_bvh(const Mesh& mesh, const BvhConfig& config = BvhConfig());

// Rewrites every triangle record from `mesh`, keeping the tree and each record's face: for a
// tree built from a copy of `mesh` taken before some faces were reversed (a reversal swaps two
// corners, which leaves a face's box (its zero corners made +0) and its zero-area test as they
// were, so build_bvh would have built the same tree). Then equal to build_bvh(mesh) bit for
// bit.
void rewrite_triangles(Bvh& bvh, const Mesh& mesh, unsigned threads = 0);

// Which trees the casters of a run read: the binary BVH and its collapses to 4 children
// (bvh4.h) and to 8 (bvh8.h).
struct BvhWidths {
  bool binary = false, four = false, eight = false;
};

// Depth of the deepest leaf (root = 0). The traversal stack must hold at least this many.
int bvh_depth(const Bvh& bvh);

}  // namespace sdf
