// SPDX-License-Identifier: GPL-3.0-or-later
#include "accel/bvh_margin.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "ray/sdf_intersect.h"
#include "util/parallel.h"

namespace sdf {

float bvh_box_margin(const Bvh& bvh, unsigned threads) {
  if (bvh.empty()) return 0.0f;
  // The longest edge component, per chunk then over chunks (max is exact in any order).
  constexpr std::size_t kGrain = 1 << 16;
  std::vector<float> chunk_edge((bvh.triangles.size() + kGrain - 1) / kGrain, 0.0f);
  parallel_for(bvh.triangles.size(), kGrain, threads, [&](std::size_t begin, std::size_t end) {
    float edge = 0.0f;
    for (std::size_t i = begin; i < end; ++i) {
      const kern::SdfTriangle& t = bvh.triangles[i];
      edge = std::max({edge, std::fabs(t.e1_x), std::fabs(t.e1_y), std::fabs(t.e1_z),
                       std::fabs(t.e2_x), std::fabs(t.e2_y), std::fabs(t.e2_z)});
    }
    chunk_edge[begin / kGrain] = edge;
  });
  const float edge = *std::max_element(chunk_edge.begin(), chunk_edge.end());
  const kern::SdfBvhNode& root = bvh.nodes[0];
  return tree_margin(glm::vec3(root.lo_x, root.lo_y, root.lo_z),
                     glm::vec3(root.hi_x, root.hi_y, root.hi_z), edge);
}

float tree_margin(glm::vec3 lo, glm::vec3 hi, float edge) {
  if (!(lo.x <= hi.x)) return 0.0f;
  const float coordinate = std::max({std::fabs(lo.x), std::fabs(lo.y), std::fabs(lo.z),
                                     std::fabs(hi.x), std::fabs(hi.y), std::fabs(hi.z)});
  // A hit lies within slack * (|e1| + |e2|) of its triangle on each axis: 4 x covers that
  // and the rounding of the triangle test itself.
  return 4.0f * SDF_BARYCENTRIC_SLACK * edge + std::ldexp(coordinate, -20) +
         std::numeric_limits<float>::min();
}

void grow_boxes_to_cover_hits(Bvh& bvh, unsigned threads) {
  const float m = bvh_box_margin(bvh, threads);
  parallel_for(bvh.nodes.size(), 1 << 16, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      kern::SdfBvhNode& n = bvh.nodes[i];
      n.lo_x -= m;
      n.lo_y -= m;
      n.lo_z -= m;
      n.hi_x += m;
      n.hi_y += m;
      n.hi_z += m;
    }
  });
}

}  // namespace sdf
