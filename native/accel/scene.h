// SPDX-License-Identifier: GPL-3.0-or-later
// The acceleration structures one run casts through: built once (pipeline/sdf.cpp) and read
// by either engine (cast/cpu_engine.h, opencl/opencl_engine.h).
#pragma once

#include "accel/bvh.h"
#include "accel/bvh4.h"
#include "accel/bvh8.h"
#include "accel/octree.h"

namespace sdf {

// The octree, or the BVH in the widths the engines cast. The 4-wide tree's leaves point at
// the binary tree's triangles, so `bvh` is kept wherever `bvh4` is (cast or not) and a Scene
// is never moved once built; the 8-wide tree holds triangles of its own.
struct Scene {
  BvhWidths widths;  // which of bvh, bvh4 and bvh8 hold a tree to cast
  bool has_octree = false;
  Bvh bvh;
  Bvh4 bvh4;
  Bvh8 bvh8;
  Octree octree;

  Scene() = default;
  Scene(const Scene&) = delete;
  Scene& operator=(const Scene&) = delete;

  // The structures to cast, null where not built.
  const Bvh* binary() const { return widths.binary ? &bvh : nullptr; }
  const Bvh4* four() const { return widths.four ? &bvh4 : nullptr; }
  const Bvh8* eight() const { return widths.eight ? &bvh8 : nullptr; }
  const Octree* tree() const { return has_octree ? &octree : nullptr; }
};

}  // namespace sdf
