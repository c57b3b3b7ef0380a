// SPDX-License-Identifier: GPL-3.0-or-later
#include "prepare/sampling.h"

#include "prepare/rays.h"
#include "util/morton.h"
#include "util/parallel.h"
#include "util/radix_sort.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace sdf {

namespace {

// Items per parallel_for chunk for the per-point loops: small enough to balance, large enough
// that handing out a chunk costs nothing next to its work.
constexpr std::size_t kGrain = 1 << 14;

}  // namespace

SamplePoints sample_points(const Mesh& mesh, PointKind kind, unsigned threads) {
  SamplePoints points;
  if (kind == PointKind::Faces) {
    const std::size_t n = mesh.triangles.size();
    points.origins.resize(n);
    points.axes.resize(n);
    points.own_face.resize(n);
    points.tangents.resize(n);
    parallel_for(n, kGrain, threads, [&](std::size_t begin, std::size_t end) {
      for (std::size_t f = begin; f < end; ++f) {
        prefetch_corners(mesh, f + kPrefetchFacesAhead);
        const glm::uvec3 t = mesh.triangles[f];
        kern::sdf_face_point(mesh.vertices[t.x], mesh.vertices[t.y], mesh.vertices[t.z],
                             &points.origins[f], &points.axes[f], &points.tangents[f]);
        points.own_face[f] = static_cast<std::int32_t>(f);
      }
    });
  } else {
    const std::size_t n = mesh.vertices.size();
    // Serial: each vertex's float sum must add its faces in face order, as it always has.
    std::vector<glm::vec3> normal_sum(n, glm::vec3(0.0f));
    // For each vertex, the next corner of the first triangle that uses it: its tangent edge.
    constexpr std::uint32_t kNone = 0xffffffffu;
    std::vector<std::uint32_t> next_corner(n, kNone);
    for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
      const glm::vec3 an = face_area_normal(mesh, f);  // length is twice the area: the weight
      const glm::uvec3 t = mesh.triangles[f];
      for (int k = 0; k < 3; ++k) {
        normal_sum[t[k]] += an;
        if (next_corner[t[k]] == kNone && t[(k + 1) % 3] != t[k])
          next_corner[t[k]] = t[(k + 1) % 3];
      }
    }
    points.origins.assign(mesh.vertices.begin(), mesh.vertices.end());
    points.axes.resize(n);
    points.tangents.resize(n);
    points.own_face.assign(n, -1);
    parallel_for(n, kGrain, threads, [&](std::size_t begin, std::size_t end) {
      for (std::size_t v = begin; v < end; ++v) {
        points.axes[v] = -kern::sdf_unit_or_zero(normal_sum[v]);
        const glm::vec3 edge = next_corner[v] == kNone
                                   ? glm::vec3(0.0f)
                                   : mesh.vertices[next_corner[v]] - mesh.vertices[v];
        points.tangents[v] = kern::sdf_tangent_from_edge(points.axes[v], edge);
      }
    });
  }
  return points;
}

std::vector<std::uint32_t> spatial_order(const SamplePoints& points, unsigned threads) {
  const std::size_t n = points.size();
  // Bounding box of the points that cast (a vertex no face uses casts nothing, and one far
  // away would crowd the others into a few cells): per-chunk boxes, then merged (min and max
  // are exact in any order).
  auto casts = [&](std::size_t i) { return points.axes[i] != glm::vec3(0.0f); };
  const std::size_t chunks = (n + kGrain - 1) / kGrain;
  std::vector<glm::vec3> chunk_lo(chunks, glm::vec3(INFINITY)),
      chunk_hi(chunks, glm::vec3(-INFINITY));
  parallel_for(n, kGrain, threads, [&](std::size_t begin, std::size_t end) {
    glm::vec3 lo(INFINITY), hi(-INFINITY);
    for (std::size_t i = begin; i < end; ++i)
      if (casts(i)) {
        lo = glm::min(lo, points.origins[i]);
        hi = glm::max(hi, points.origins[i]);
      }
    chunk_lo[begin / kGrain] = lo;
    chunk_hi[begin / kGrain] = hi;
  });
  glm::vec3 lo(INFINITY), hi(-INFINITY);
  for (std::size_t c = 0; c < chunks; ++c) {
    lo = glm::min(lo, chunk_lo[c]);
    hi = glm::max(hi, chunk_hi[c]);
  }
  if (!(lo.x <= hi.x)) lo = hi = glm::vec3(0.0f);  // no point casts: any order will do
  const glm::vec3 scale = 1023.0f / glm::max(hi - lo, glm::vec3(1e-30f));
  // (code << 32) | index, sorted stably on the code: the order of std::sort on (code, index).
  UninitializedVector<std::uint64_t> keyed(n);
  parallel_for(n, kGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      // Clamped: points that cast nothing may lie outside the box.
      const glm::uvec3 c = glm::uvec3(glm::clamp((points.origins[i] - lo) * scale, 0.0f, 1023.0f));
      const std::uint64_t code = morton_30(c);
      keyed[i] = (code << 32) | i;
    }
  });
  radix_sort_by_bits(keyed, 32, 30, threads);
  std::vector<std::uint32_t> order(n);
  parallel_for(n, kGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) order[i] = static_cast<std::uint32_t>(keyed[i]);
  });
  return order;
}

}  // namespace sdf
