// SPDX-License-Identifier: GPL-3.0-or-later
// Nearest-hit traversal of the 8-wide BVH with AVX2 (bvh8_traverse_avx2.cpp): call it only
// when bvh8_supported(). Same answers, bit for bit, as
// kern::sdf_intersect_triangle over every triangle (the C++ tests check it ray by ray).
#pragma once

#include "accel/bvh8.h"
#include "ray/sdf_intersect.h"

#if SDF_HAVE_BVH8
namespace sdf {

kern::SdfHit bvh8_closest_hit_avx2(const Bvh8& bvh, glm::vec3 o, glm::vec3 d, float tmin,
                                   std::int32_t skip_id);

// The same for `count` rays from one origin: hits[i] for d[i]. Rays are traversed two at a
// time, taking turns visit by visit, so that one ray's cache misses overlap the other's work.
void bvh8_closest_hits_avx2(const Bvh8& bvh, glm::vec3 o, const glm::vec3* d, int count, float tmin,
                            std::int32_t skip_id, kern::SdfHit* hits);

}  // namespace sdf
#endif
