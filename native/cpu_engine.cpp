// SPDX-License-Identifier: GPL-3.0-or-later
#include "cpu_engine.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "bvh4_traverse.h"
#include "../kernels/sdf_reduce.h"

namespace sdf {

namespace {

// Spreads the low 10 bits of v to every third bit (Morton code helper).
std::uint32_t spread_bits(std::uint32_t v) {
  v = (v | (v << 16)) & 0x030000FFu;
  v = (v | (v << 8)) & 0x0300F00Fu;
  v = (v | (v << 4)) & 0x030C30C3u;
  v = (v | (v << 2)) & 0x09249249u;
  return v;
}

// Points in Morton (Z-curve) order of their origins. Neighbouring points cast similar rays
// through the same nodes, so working through them in space order keeps the tree in cache:
// measured 20-30% faster than file order on the bunny.
std::vector<std::uint32_t> spatial_order(const SamplePoints& points) {
  glm::vec3 lo(INFINITY), hi(-INFINITY);
  for (const glm::vec3& p : points.origins) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  const glm::vec3 scale = 1023.0f / glm::max(hi - lo, glm::vec3(1e-30f));
  std::vector<std::pair<std::uint32_t, std::uint32_t>> keyed(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    const glm::uvec3 c = glm::uvec3((points.origins[i] - lo) * scale);
    keyed[i] = {spread_bits(c.x) | (spread_bits(c.y) << 1) | (spread_bits(c.z) << 2),
                static_cast<std::uint32_t>(i)};
  }
  std::sort(keyed.begin(), keyed.end());
  std::vector<std::uint32_t> order(points.size());
  for (std::size_t i = 0; i < keyed.size(); ++i) order[i] = keyed[i].second;
  return order;
}

}  // namespace

void cast_cpu(const Bvh& bvh, const SamplePoints& points, const Cone& cone, float min_closeness,
              unsigned threads, float* raw, std::int32_t* valid_rays, const ProgressFn& progress,
              double progress_from, double progress_to) {
  // Chunks of a few hundred points: small enough for smooth progress and load balance, large
  // enough that handing them out costs nothing.
  constexpr std::size_t kGrain = 256;
  const Bvh4 wide = collapse_to_bvh4(bvh);
  const std::vector<std::uint32_t> order = spatial_order(points);
  parallel_for(
      points.size(), kGrain, threads,
      [&](std::size_t begin, std::size_t end) {
        std::vector<glm::vec3> directions(cone.rays);
        std::vector<float> angles(cone.rays), lengths(cone.rays), kept_angles(cone.rays);
        for (std::size_t i = begin; i < end; ++i) {
          const std::uint32_t p = order[i];
          const glm::vec3 axis = points.axes[p];
          if (bvh.empty() || (axis.x == 0.0f && axis.y == 0.0f && axis.z == 0.0f)) {
            raw[p] = -1.0f;
            valid_rays[p] = 0;
            continue;
          }
          cone_rays(cone, axis, p, directions.data(), angles.data());
          int kept = 0;
          for (int r = 0; r < cone.rays; ++r) {
            const kern::SdfHit hit = bvh4_closest_hit(wide, points.origins[p], directions[r],
                                                      min_closeness, points.own_face[p]);
            if (hit.det < 0.0f && std::isfinite(hit.t)) {
              lengths[kept] = hit.t;
              kept_angles[kept] = angles[r];
              ++kept;
            }
          }
          raw[p] = kern::sdf_reduce(static_cast<int>(cone.sampling), lengths.data(),
                                    kept_angles.data(), kept, cone.angle_floor);
          valid_rays[p] = kept;
        }
      },
      progress, progress_from, progress_to);
}

}  // namespace sdf
