// SPDX-License-Identifier: GPL-3.0-or-later
#include "post/uv_plan.h"

#include <cstring>

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
  plan.vertex_count = mesh.vertices.size();
  plan.uv_fingerprint = uv_fingerprint(uvs, plan.face_count);
  plan.seconds = clock.lap();
  return plan;
}

std::uint64_t uv_fingerprint(const float* uvs, std::size_t face_count) {
  // FNV-1a over the floats' bits, one 32-bit word a step: about 10 ms for a million faces.
  std::uint64_t hash = 14695981039346656037ull;
  for (std::size_t i = 0; i < 6 * face_count; ++i) {
    std::uint32_t bits;
    std::memcpy(&bits, uvs + i, sizeof bits);
    hash = (hash ^ bits) * 1099511628211ull;
  }
  return hash;
}

bool plan_fits(const UvPlan& plan, std::size_t face_count, std::size_t vertex_count,
               const float* uvs, double weld_tolerance, bool need_merged) {
  return plan.face_count == face_count && plan.vertex_count == vertex_count && uvs &&
         plan.uv_fingerprint == uv_fingerprint(uvs, face_count) &&
         plan.islands.weld_tolerance == weld_tolerance &&
         (!need_merged || plan.islands.need_merged);
}

}  // namespace sdf
