// SPDX-License-Identifier: GPL-3.0-or-later
#include "accel/bvh_stats.h"

namespace sdf {

namespace {

double half_area(const kern::SdfBvhNode& n) {
  const double dx = double(n.hi_x) - n.lo_x, dy = double(n.hi_y) - n.lo_y,
               dz = double(n.hi_z) - n.lo_z;
  return dx * dy + dy * dz + dz * dx;
}

}  // namespace

double bvh_sah_cost(const Bvh& bvh) {
  if (bvh.nodes.empty()) return 0.0;
  const double root = half_area(bvh.nodes[0]);
  // Every node is reached from the root and appears once in the array, so a flat sum suffices.
  double sum = 0.0;
  for (const kern::SdfBvhNode& n : bvh.nodes) sum += half_area(n) * (n.count > 0 ? n.count : 1);
  return root > 0.0 ? sum / root : sum;
}

}  // namespace sdf
