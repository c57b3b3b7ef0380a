// SPDX-License-Identifier: GPL-3.0-or-later
#include "cpu_engine.h"

#include <cmath>
#include <vector>

#include "../kernels/sdf_bvh_traverse.h"
#include "../kernels/sdf_reduce.h"

namespace sdf {

void cast_cpu(const Bvh& bvh, const SamplePoints& points, const Cone& cone, float min_closeness,
              unsigned threads, float* raw, std::int32_t* valid_rays, const ProgressFn& progress,
              double progress_from, double progress_to) {
  // Chunks of a few hundred points: small enough for smooth progress and load balance, large
  // enough that handing them out costs nothing.
  constexpr std::size_t kGrain = 256;
  parallel_for(
      points.size(), kGrain, threads,
      [&](std::size_t begin, std::size_t end) {
        std::vector<glm::vec3> directions(cone.rays);
        std::vector<float> angles(cone.rays), lengths(cone.rays), kept_angles(cone.rays);
        for (std::size_t p = begin; p < end; ++p) {
          const glm::vec3 axis = points.axes[p];
          if (bvh.empty() || (axis.x == 0.0f && axis.y == 0.0f && axis.z == 0.0f)) {
            raw[p] = -1.0f;
            valid_rays[p] = 0;
            continue;
          }
          cone_rays(cone, axis, static_cast<std::uint32_t>(p), directions.data(), angles.data());
          int kept = 0;
          for (int r = 0; r < cone.rays; ++r) {
            const kern::SdfHit hit =
                kern::sdf_bvh_closest_hit(bvh.nodes.data(), bvh.triangles.data(), points.origins[p],
                                          directions[r], min_closeness, points.own_face[p]);
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
