// SPDX-License-Identifier: GPL-3.0-or-later
#include "cpu_engine.h"

#include <cmath>
#include <vector>

#include "../kernels/sdf_octree.h"
#include "../kernels/sdf_reduce.h"
#include "bvh4_traverse.h"
#include "bvh8_traverse.h"

namespace sdf {

namespace {

template <class ClosestHit>
void cast_points(const SamplePoints& points, const std::vector<std::uint32_t>& order,
                 const Cone& cone, unsigned threads, float* raw, std::int32_t* valid_rays,
                 const ProgressFn& progress, double progress_from, double progress_to,
                 const ClosestHit& closest_hit) {
  // Chunks of a few hundred points: small enough for smooth progress and load balance, large
  // enough that handing them out costs nothing.
  constexpr std::size_t kGrain = 256;
  parallel_for(
      points.size(), kGrain, threads,
      [&](std::size_t begin, std::size_t end) {
        std::vector<glm::vec3> directions(cone.rays);
        std::vector<float> angles(cone.rays), lengths(cone.rays), kept_angles(cone.rays);
        for (std::size_t i = begin; i < end; ++i) {
          const std::uint32_t p = order[i];
          const glm::vec3 axis = points.axes[p];
          if (axis.x == 0.0f && axis.y == 0.0f && axis.z == 0.0f) {
            raw[p] = -1.0f;
            valid_rays[p] = 0;
            continue;
          }
          cone_rays(cone, axis, points.tangents[p], p, directions.data(), angles.data());
          int kept = 0;
          for (int r = 0; r < cone.rays; ++r) {
            const kern::SdfHit hit = closest_hit(points.origins[p], directions[r], points.own_face[p]);
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

}  // namespace

void cast_cpu(const CpuScene& scene, const SamplePoints& points,
              const std::vector<std::uint32_t>& order, const Cone& cone, float min_closeness,
              unsigned threads, float* raw, std::int32_t* valid_rays, const ProgressFn& progress,
              double progress_from, double progress_to) {
#if SDF_HAVE_BVH8
  if (scene.bvh8) {
    const Bvh8& bvh = *scene.bvh8;
    cast_points(points, order, cone, threads, raw, valid_rays, progress, progress_from,
                progress_to, [&](glm::vec3 o, glm::vec3 d, std::int32_t own) {
                  return bvh8_closest_hit_avx2(bvh, o, d, min_closeness, own);
                });
    return;
  }
#endif
  if (scene.bvh4) {
    const Bvh4& bvh = *scene.bvh4;
    cast_points(points, order, cone, threads, raw, valid_rays, progress, progress_from,
                progress_to, [&](glm::vec3 o, glm::vec3 d, std::int32_t own) {
                  return bvh4_closest_hit(bvh, o, d, min_closeness, own);
                });
  } else {
    const Octree& tree = *scene.octree;
    cast_points(points, order, cone, threads, raw, valid_rays, progress, progress_from,
                progress_to, [&](glm::vec3 o, glm::vec3 d, std::int32_t own) {
                  return kern::sdf_octree_closest_hit(tree.nodes.data(), tree.leaves.data(),
                                                      tree.triangles.data(), tree.root, o, d,
                                                      min_closeness, own);
                });
  }
}

}  // namespace sdf
