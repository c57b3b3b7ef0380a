// SPDX-License-Identifier: GPL-3.0-or-later
// The projected-points gather (kernels/smooth/sdf_smooth_projected.h) on eight points at once, for
// the CPU on AVX2 machines. The eight walk the octree together, in the scalar walk's order
// (depth first, a node's children last to first), each lane taking a node only where its own
// walk would: so each lane adds the same terms in the same order and gets the scalar result
// bit for bit. Eight neighbours in Morton order take nearly the same path, so a visit does
// eight points' work for about the price of one. Chosen at run time (projected_avx2_supported:
// AVX2 by cpu_features(), unless a test acts out a CPU without it); elsewhere the scalar
// kernel runs.
#pragma once

#include <cstddef>
#include <cstdint>

#include "post/smoothing_projected.h"

namespace sdf {

// Whether smooth_packet_avx2 may be called here.
bool projected_avx2_supported();

// out[i] = kern::sdf_smooth_projected_point(nodes, points[i].xyz, points[i].w, radius_scale,
// lo, hi) for the `lanes` (1 to 8) point indices i = index[0], ..., index[lanes - 1].
void smooth_packet_avx2(const PointOctreeNode* nodes, const glm::vec4* points,
                        const std::uint32_t* index, int lanes, float radius_scale, float lo,
                        float hi, float* out);

}  // namespace sdf
