// SPDX-License-Identifier: GPL-3.0-or-later
// What collapsing the binary BVH into a wide one (bvh4.cpp, bvh8.cpp) does the same way for
// any width: choosing which binary nodes become the children of a wide node, and writing a
// child's box or an empty slot into the wide node's structure-of-arrays.
#pragma once

#include <cstdint>
#include <limits>

#include "accel/bvh.h"

namespace sdf {

inline float half_area(const kern::SdfBvhNode& n) {
  const float dx = n.hi_x - n.lo_x, dy = n.hi_y - n.lo_y, dz = n.hi_z - n.lo_z;
  return dx * dy + dy * dz + dz * dx;
}

// Fills slots[0, k) with the binary nodes that become the children of the wide node for inner
// node `index`, and returns k <= Width: starting from its two children, the largest (by
// surface area: the chance that a ray through the parent enters it) that is not
// is_leaf(node) is opened into its two children until Width are reached or none can be opened.
template <int Width, class IsLeaf>
int gather_wide_children(const Bvh& bvh, std::int32_t index, IsLeaf is_leaf,
                         std::int32_t (&slots)[Width]) {
  slots[0] = bvh.nodes[index].first;
  slots[1] = bvh.nodes[index].first + 1;
  int used = 2;
  while (used < Width) {
    int best = -1;
    float best_area = -1.0f;
    for (int i = 0; i < used; ++i) {
      const kern::SdfBvhNode& n = bvh.nodes[slots[i]];
      if (!is_leaf(slots[i]) && half_area(n) > best_area) {
        best_area = half_area(n);
        best = i;
      }
    }
    if (best < 0) break;
    const std::int32_t opened = slots[best];
    slots[best] = bvh.nodes[opened].first;
    slots[used++] = bvh.nodes[opened].first + 1;
  }
  return used;
}

// Slot i of wide node w takes binary node n's box.
template <class WideNode>
void set_wide_box(WideNode& w, int i, const kern::SdfBvhNode& n) {
  w.lo_x[i] = n.lo_x;
  w.lo_y[i] = n.lo_y;
  w.lo_z[i] = n.lo_z;
  w.hi_x[i] = n.hi_x;
  w.hi_y[i] = n.hi_y;
  w.hi_z[i] = n.hi_z;
}

// Slot i of wide node w holds nothing: an empty box (lo = +inf, hi = -inf) that no ray enters.
template <class WideNode>
void clear_wide_slot(WideNode& w, int i) {
  const float inf = std::numeric_limits<float>::infinity();
  w.lo_x[i] = w.lo_y[i] = w.lo_z[i] = inf;
  w.hi_x[i] = w.hi_y[i] = w.hi_z[i] = -inf;
  w.child[i] = ~0;
  w.count[i] = 0;
}

}  // namespace sdf
