// SPDX-License-Identifier: GPL-3.0-or-later
// Stages 3-4 on CPU threads: cast every point's rays through the acceleration structure and
// reduce them.
#pragma once

#include <cstdint>
#include <vector>

#include "accel/bvh4.h"
#include "accel/bvh8.h"
#include "accel/octree.h"
#include "util/parallel.h"
#include "prepare/rays.h"
#include "prepare/sampling.h"

namespace sdf {

// Exactly one is set. A BVH of the width cpu_bvh_width() gives.
struct CpuScene {
  const Bvh8* bvh8 = nullptr;
  const Bvh4* bvh4 = nullptr;
  const Bvh* bvh = nullptr;
  const Octree* octree = nullptr;
};

// The BVH the CPU engine casts on this build and CPU: the 8-wide tree where bvh8_supported()
// (AVX2), else the 4-wide one on x86-64 (SSE), else (aarch64, ...) the binary tree through
// the kernels' own traversal (kernels/traverse/sdf_bvh_traverse.h). All give the same hits.
BvhWidths cpu_bvh_width();

// For each point: cast its cone of rays, keep the nearest hit of each ray when it lies beyond
// min_closeness, is not on the point's own face and leaves the solid through the hit face
// (dot(ray, outward normal) > 0; otherwise the ray is dropped, as in the paper and CGAL), then
// reduce the kept lengths. Points are worked through in `order` (spatial_order: cache
// locality). Writes raw[i] (-1 when no ray was kept) and valid_rays[i].
// Progress covers [progress_from, progress_to].
void cast_cpu(const CpuScene& scene, const SamplePoints& points,
              const std::vector<std::uint32_t>& order, const Cone& cone, float min_closeness,
              unsigned threads, float* raw, std::int32_t* valid_rays, const ProgressFn& progress,
              double progress_from, double progress_to);

}  // namespace sdf
