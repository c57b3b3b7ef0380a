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

// Exactly one of the three is set. bvh8 only where bvh8_supported() (AVX2), else bvh4.
struct CpuScene {
  const Bvh8* bvh8 = nullptr;
  const Bvh4* bvh4 = nullptr;
  const Octree* octree = nullptr;
};

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
