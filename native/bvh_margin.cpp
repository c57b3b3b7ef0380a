// SPDX-License-Identifier: GPL-3.0-or-later
#include "bvh_margin.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "../kernels/sdf_intersect.h"

namespace sdf {

float bvh_box_margin(const Bvh& bvh) {
  if (bvh.empty()) return 0.0f;
  float edge = 0.0f;
  for (const kern::SdfTriangle& t : bvh.triangles)
    edge = std::max({edge, std::fabs(t.e1_x), std::fabs(t.e1_y), std::fabs(t.e1_z),
                     std::fabs(t.e2_x), std::fabs(t.e2_y), std::fabs(t.e2_z)});
  const kern::SdfBvhNode& root = bvh.nodes[0];
  const float coordinate =
      std::max({std::fabs(root.lo_x), std::fabs(root.lo_y), std::fabs(root.lo_z),
                std::fabs(root.hi_x), std::fabs(root.hi_y), std::fabs(root.hi_z)});
  // A hit lies within slack * (|e1| + |e2|) of its triangle on each axis: 4 x covers that
  // and the rounding of the triangle test itself.
  return 4.0f * SDF_BARYCENTRIC_SLACK * edge + std::ldexp(coordinate, -20) +
         std::numeric_limits<float>::min();
}

void grow_boxes_to_cover_hits(Bvh& bvh) {
  const float m = bvh_box_margin(bvh);
  for (kern::SdfBvhNode& n : bvh.nodes) {
    n.lo_x -= m;
    n.lo_y -= m;
    n.lo_z -= m;
    n.hi_x += m;
    n.hi_y += m;
    n.hi_z += m;
  }
}

}  // namespace sdf
