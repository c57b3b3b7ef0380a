// SPDX-License-Identifier: GPL-3.0-or-later
#include "cast/cpu_engine.h"

#include <cmath>
#include <vector>

#include "cast/bvh4_traverse.h"
#include "cast/bvh8_traverse.h"
#include "ray/sdf_reduce.h"
#include "traverse/sdf_bvh_traverse.h"
#include "traverse/sdf_octree.h"

namespace sdf {

namespace {

// closest_hits(origin, directions, count, own_face, hits): the nearest hit of each ray.
template <class ClosestHits>
void cast_points(const SamplePoints& points, const std::vector<std::uint32_t>& order,
                 const Cone& cone, unsigned threads, float* raw, std::int32_t* valid_rays,
                 const ProgressFn& progress, double progress_from, double progress_to,
                 const ClosestHits& closest_hits) {
  // Chunks of a few hundred points: small enough for smooth progress and load balance, large
  // enough that handing them out costs nothing.
  constexpr std::size_t kGrain = 256;
  parallel_for(
      points.size(), kGrain, threads,
      [&](std::size_t begin, std::size_t end) {
        std::vector<glm::vec3> directions(cone.rays);
        std::vector<float> angles(cone.rays), lengths(cone.rays), kept_angles(cone.rays);
        std::vector<kern::SdfHit> hits(cone.rays);
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
          closest_hits(points.origins[p], directions.data(), cone.rays, points.own_face[p],
                       hits.data());
          for (int r = 0; r < cone.rays; ++r) {
            const kern::SdfHit& hit = hits[r];
            if (kern::sdf_exit_hit(hit)) {
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

BvhWidths cpu_bvh_width() {
  BvhWidths w;
  w.eight = bvh8_supported();
  w.four = !w.eight && SDF_HAVE_BVH4_SSE;
  w.binary = !w.eight && !w.four;
  return w;
}

void cast_cpu(const Scene& scene, const SamplePoints& points,
              const std::vector<std::uint32_t>& order, const Cone& cone, float min_closeness,
              unsigned threads, float* raw, std::int32_t* valid_rays, const ProgressFn& progress,
              double progress_from, double progress_to) {
#if SDF_HAVE_BVH8
  if (scene.eight()) {
    const Bvh8& bvh = scene.bvh8;
    cast_points(
        points, order, cone, threads, raw, valid_rays, progress, progress_from, progress_to,
        [&](glm::vec3 o, const glm::vec3* d, int count, std::int32_t own, kern::SdfHit* hits) {
          bvh8_closest_hits_avx2(bvh, o, d, count, min_closeness, own, hits);
        });
    return;
  }
#endif
#if SDF_HAVE_BVH4_SSE
  if (scene.four()) {
    const Bvh4& bvh = scene.bvh4;
    cast_points(
        points, order, cone, threads, raw, valid_rays, progress, progress_from, progress_to,
        [&](glm::vec3 o, const glm::vec3* d, int count, std::int32_t own, kern::SdfHit* hits) {
          for (int r = 0; r < count; ++r)
            hits[r] = bvh4_closest_hit(bvh, o, d[r], min_closeness, own);
        });
    return;
  }
#endif
  if (scene.binary()) {
    const Bvh& bvh = scene.bvh;
    cast_points(
        points, order, cone, threads, raw, valid_rays, progress, progress_from, progress_to,
        [&](glm::vec3 o, const glm::vec3* d, int count, std::int32_t own, kern::SdfHit* hits) {
          for (int r = 0; r < count; ++r)
            hits[r] = kern::sdf_bvh_closest_hit(bvh.nodes.data(), bvh.triangles.data(), o, d[r],
                                                min_closeness, own);
        });
  } else {
    const Octree& tree = scene.octree;
    cast_points(
        points, order, cone, threads, raw, valid_rays, progress, progress_from, progress_to,
        [&](glm::vec3 o, const glm::vec3* d, int count, std::int32_t own, kern::SdfHit* hits) {
          for (int r = 0; r < count; ++r)
            hits[r] = kern::sdf_octree_closest_hit(tree.nodes.data(), tree.leaves.data(),
                                                   tree.triangles.data(), tree.root, o, d[r],
                                                   min_closeness, own);
        });
  }
}

}  // namespace sdf
