// SPDX-License-Identifier: GPL-3.0-or-later
// Stages 3-4 on CPU threads: cast every point's rays through the acceleration structure and
// reduce them.
#pragma once

#include <cstdint>
#include <vector>

#include "accel/scene.h"
#include "prepare/rays.h"
#include "prepare/sampling.h"
#include "util/parallel.h"

namespace sdf {

// The BVH the CPU engine casts on this build and CPU: the 8-wide tree where bvh8_supported()
// (AVX2), else the 4-wide one on x86-64 (SSE), else (aarch64, ...) the binary tree through
// the kernels' own traversal (kernels/traverse/sdf_bvh_traverse.h). All give the same hits.
BvhWidths cpu_bvh_width();

// For each point: cast its cone of rays, keep the nearest hit of each ray when it lies beyond
// min_closeness, is not on the point's own face and leaves the solid through the hit face
// (dot(ray, outward normal) > 0; otherwise the ray is dropped, as in the paper and CGAL), then
// reduce the kept lengths. Points are worked through in `order` (spatial_order: cache
// locality). Writes raw[i] (-1 when no ray was kept) and valid_rays[i]. The scene's 8-wide
// tree is cast where it has one (built only where bvh8_supported(): AVX2), else its 4-wide
// tree, else its octree.
// Progress covers [progress_from, progress_to].
void cast_cpu(const Scene& scene, const SamplePoints& points,
              const std::vector<std::uint32_t>& order, const Cone& cone, float min_closeness,
              unsigned threads, float* raw, std::int32_t* valid_rays, const ProgressFn& progress,
              double progress_from, double progress_to);

}  // namespace sdf
