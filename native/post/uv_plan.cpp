// SPDX-License-Identifier: GPL-3.0-or-later
#include "post/uv_plan.h"

#include "post/smoothing_texture.h"
#include "util/stopwatch.h"

namespace sdf {

UvPlan plan_uvs(const Mesh& mesh, const float* uvs, double weld_tolerance, bool need_merged,
                unsigned threads) {
  Stopwatch clock;
  TextureOptions size;  // the checks want a size: any valid one
  size.threads = threads;
  check_texture_input(uvs, mesh.triangles.size(), size);
  UvPlan plan;
  plan.islands = label_uv_islands(mesh, uvs, weld_tolerance, need_merged, threads);
  plan.layout = layout_uvs(uvs, plan.islands.face_island, threads);
  plan.face_count = mesh.triangles.size();
  plan.seconds = clock.lap();
  return plan;
}

bool plan_fits(const UvPlan& plan, std::size_t face_count, double weld_tolerance,
               bool need_merged) {
  return plan.face_count == face_count && plan.islands.weld_tolerance == weld_tolerance &&
         (!need_merged || plan.islands.need_merged);
}

}  // namespace sdf
