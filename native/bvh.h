// SPDX-License-Identifier: GPL-3.0-or-later
// Stage 2: a bounding volume hierarchy over the triangles, built with binned SAH (Wald 2007)
// in parallel, then packed into the flat arrays that the CPU engine and the kernels traverse.
#pragma once

#include <memory>
#include <new>
#include <utility>
#include <vector>

#include "../kernels/sdf_layout.h"
#include "mesh.h"

namespace sdf {

struct BvhConfig {
  // Triangles per leaf at most, unless they cannot be separated. Small leaves suit SDF rays,
  // which stop at the first hit (2 to 4 measured best for Moller-Trumbore leaves).
  int max_leaf_size = 4;
  // SAH bins per axis: 16 is within a percent or two of a full sweep (Wald 2007).
  int bins = 16;
  unsigned threads = 0;  // 0: every core
};

// std::allocator, except that resize() leaves new elements uninitialised: the builder then
// writes every element on all threads, where a zero fill first would be a serial pass over
// 80 bytes per triangle (18 ms for the nodes alone of a 1.2M-face mesh).
template <typename T>
struct NoFillAllocator : std::allocator<T> {
  template <typename U>
  struct rebind {
    using other = NoFillAllocator<U>;
  };
  NoFillAllocator() = default;
  template <typename U>
  NoFillAllocator(const NoFillAllocator<U>&) noexcept {}
  template <typename U>
  void construct(U* p) noexcept {
    ::new (static_cast<void*>(p)) U;
  }
  template <typename U, typename... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
};

template <typename T>
using NoFillVector = std::vector<T, NoFillAllocator<T>>;

struct Bvh {
  NoFillVector<kern::SdfBvhNode> nodes;      // nodes[0] is the root
  NoFillVector<kern::SdfTriangle> triangles;  // in leaf order; zero-area triangles left out
  bool empty() const { return triangles.empty(); }
};

Bvh build_bvh(const Mesh& mesh, const BvhConfig& config = BvhConfig());

// Depth of the deepest leaf (root = 0). The traversal stack must hold at least this many.
int bvh_depth(const Bvh& bvh);

}  // namespace sdf
