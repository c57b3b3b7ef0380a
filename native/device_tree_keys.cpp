// SPDX-License-Identifier: GPL-3.0-or-later
#include "device_tree_keys.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "../kernels/sdf_intersect.h"
#include "morton.h"
#include "parallel.h"
#include "radix_sort.h"

namespace sdf {

namespace {

constexpr std::size_t kGrain = 1 << 14;

// A face's box as build_bvh makes it (+ 0: a -0 corner becomes +0, whatever the winding), and
// whether the face has area (its cross product is not zero, as build_bvh tests).
struct FaceBox {
  glm::vec3 lo, hi;
  bool area;
};

FaceBox face_box(const Mesh& mesh, std::size_t f) {
  const glm::uvec3 t = mesh.triangles[f];
  const glm::vec3 v0 = mesh.vertices[t.x], v1 = mesh.vertices[t.y], v2 = mesh.vertices[t.z];
  const glm::vec3 normal = glm::cross(v1 - v0, v2 - v0);
  return {glm::min(v0, glm::min(v1, v2)) + 0.0f, glm::max(v0, glm::max(v1, v2)) + 0.0f,
          normal.x != 0.0f || normal.y != 0.0f || normal.z != 0.0f};
}

// Bounds of the faces with area and their longest edge component (of v1 - v0 and v2 - v0,
// as the triangle records hold them).
struct Extent {
  glm::vec3 lo{INFINITY}, hi{-INFINITY};
  float edge = 0.0f;
};

}  // namespace

TreeKeys make_tree_keys(const Mesh& mesh, unsigned threads, StageTimings* steps) {
  StageClock step(steps);
  const std::size_t n = mesh.triangles.size();
  const std::size_t chunks = (n + kGrain - 1) / kGrain;
  // One pass over the corners (scattered reads: most of the time): each face's box centre,
  // NaN for a face without area, and the extent of the rest. The codes then read the centres
  // in order (reading the corners twice took twice as long).
  UninitializedVector<glm::vec3> centres(n);
  std::vector<Extent> chunk_extent(chunks);
  parallel_for(n, kGrain, threads, [&](std::size_t begin, std::size_t end) {
    Extent e;
    for (std::size_t f = begin; f < end; ++f) {
      const FaceBox box = face_box(mesh, f);
      if (!box.area) {
        centres[f] = glm::vec3(NAN);
        continue;
      }
      centres[f] = (box.lo + box.hi) * 0.5f;
      e.lo = glm::min(e.lo, box.lo);
      e.hi = glm::max(e.hi, box.hi);
      const glm::uvec3 t = mesh.triangles[f];
      const glm::vec3 v0 = mesh.vertices[t.x];
      const glm::vec3 e1 = glm::abs(mesh.vertices[t.y] - v0), e2 = glm::abs(mesh.vertices[t.z] - v0);
      e.edge = std::max({e.edge, e1.x, e1.y, e1.z, e2.x, e2.y, e2.z});
    }
    chunk_extent[begin / kGrain] = e;
  });
  Extent all;
  for (const Extent& e : chunk_extent) {
    all.lo = glm::min(all.lo, e.lo);
    all.hi = glm::max(all.hi, e.hi);
    all.edge = std::max(all.edge, e.edge);
  }
  step.lap("keys: boxes");
  TreeKeys keys;
  // bvh_box_margin's formula, from the root box and the longest edge component.
  const float coordinate = std::max({std::fabs(all.lo.x), std::fabs(all.lo.y), std::fabs(all.lo.z),
                                     std::fabs(all.hi.x), std::fabs(all.hi.y), std::fabs(all.hi.z)});
  keys.margin = 4.0f * SDF_BARYCENTRIC_SLACK * all.edge + std::ldexp(coordinate, -20) +
                std::numeric_limits<float>::min();
  if (!(all.lo.x <= all.hi.x)) keys.margin = 0.0f;  // no face with area: no tree

  // (code << 32) | face; zero-area faces get code 2^30, past every 30-bit code, so they sort
  // last; sorted stably on 31 bits.
  constexpr std::uint64_t kNoArea = 1u << 30;
  const glm::vec3 scale = 1023.0f / glm::max(all.hi - all.lo, glm::vec3(1e-30f));
  UninitializedVector<std::uint64_t> keyed(n);
  std::vector<std::size_t> chunk_with_area(chunks, 0);
  parallel_for(n, kGrain, threads, [&](std::size_t begin, std::size_t end) {
    std::size_t with_area = 0;
    for (std::size_t f = begin; f < end; ++f) {
      const glm::vec3 centre = centres[f];
      std::uint64_t code = kNoArea;
      if (!std::isnan(centre.x)) {
        const glm::uvec3 c = glm::uvec3(glm::clamp((centre - all.lo) * scale, 0.0f, 1023.0f));
        code = spread_bits_10(c.x) | (spread_bits_10(c.y) << 1) | (spread_bits_10(c.z) << 2);
        ++with_area;
      }
      keyed[f] = (code << 32) | f;
    }
    chunk_with_area[begin / kGrain] = with_area;
  });
  for (std::size_t c : chunk_with_area) keys.with_area += c;
  step.lap("keys: codes");
  radix_sort_by_bits(keyed, 32, 31, threads);
  keys.order.resize(n);
  keys.codes.resize(keys.with_area);
  parallel_for(n, kGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      keys.order[i] = static_cast<std::uint32_t>(keyed[i]);
      if (i < keys.with_area) keys.codes[i] = static_cast<std::uint32_t>(keyed[i] >> 32);
    }
  });
  step.lap("keys: sort");
  return keys;
}

}  // namespace sdf
