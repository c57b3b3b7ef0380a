// SPDX-License-Identifier: GPL-3.0-or-later
#include "bvh4.h"

#include <algorithm>
#include <limits>
#include <utility>

namespace sdf {

namespace {

float half_area(const kern::SdfBvhNode& n) {
  const float dx = n.hi_x - n.lo_x, dy = n.hi_y - n.lo_y, dz = n.hi_z - n.lo_z;
  return dx * dy + dy * dz + dz * dx;
}

class Collapser {
 public:
  Collapser(const Bvh& bvh, Bvh4& out) : bvh_(bvh), out_(out) {}

  // Emits the wide node for binary node `index` and returns its position.
  std::int32_t emit(std::int32_t index) {
    // Gather up to four binary nodes below `index`: open the largest inner child until full.
    std::int32_t slots[4] = {bvh_.nodes[index].first, bvh_.nodes[index].first + 1, -1, -1};
    int used = 2;
    while (used < 4) {
      int best = -1;
      float best_area = -1.0f;
      for (int i = 0; i < used; ++i) {
        const kern::SdfBvhNode& n = bvh_.nodes[slots[i]];
        if (n.count == 0 && half_area(n) > best_area) {
          best_area = half_area(n);
          best = i;
        }
      }
      if (best < 0) break;
      const std::int32_t opened = slots[best];
      slots[best] = bvh_.nodes[opened].first;
      slots[used++] = bvh_.nodes[opened].first + 1;
    }
    const std::int32_t me = static_cast<std::int32_t>(out_.nodes.size());
    out_.nodes.emplace_back();
    for (int i = 0; i < 4; ++i) {
      if (i < used) {
        const kern::SdfBvhNode n = bvh_.nodes[slots[i]];
        set_box(me, i, n);
        if (n.count > 0) {
          out_.nodes[me].child[i] = ~n.first;
          out_.nodes[me].count[i] = n.count;
        } else {
          const std::int32_t child = emit(slots[i]);  // may reallocate out_.nodes
          out_.nodes[me].child[i] = child;
          out_.nodes[me].count[i] = 0;
        }
      } else {
        clear_slot(me, i);
      }
    }
    return me;
  }

  // A tree whose root is a leaf: one wide node with one slot.
  void emit_leaf_root() {
    out_.nodes.emplace_back();
    const kern::SdfBvhNode& n = bvh_.nodes[0];
    set_box(0, 0, n);
    out_.nodes[0].child[0] = ~n.first;
    out_.nodes[0].count[0] = n.count;
    for (int i = 1; i < 4; ++i) clear_slot(0, i);
  }

 private:
  void set_box(std::int32_t node, int i, const kern::SdfBvhNode& n) {
    Bvh4Node& w = out_.nodes[node];
    w.lo_x[i] = n.lo_x;
    w.lo_y[i] = n.lo_y;
    w.lo_z[i] = n.lo_z;
    w.hi_x[i] = n.hi_x;
    w.hi_y[i] = n.hi_y;
    w.hi_z[i] = n.hi_z;
  }

  void clear_slot(std::int32_t node, int i) {
    const float inf = std::numeric_limits<float>::infinity();
    Bvh4Node& w = out_.nodes[node];
    w.lo_x[i] = w.lo_y[i] = w.lo_z[i] = inf;
    w.hi_x[i] = w.hi_y[i] = w.hi_z[i] = -inf;
    w.child[i] = ~0;
    w.count[i] = 0;
  }

  const Bvh& bvh_;
  Bvh4& out_;
};

}  // namespace

Bvh4 collapse_to_bvh4(const Bvh& bvh) {
  Bvh4 out;
  out.triangles = &bvh.triangles;
  if (bvh.empty()) return out;
  out.nodes.reserve(bvh.nodes.size() / 2 + 1);
  Collapser collapser(bvh, out);
  if (bvh.nodes[0].count > 0) {
    collapser.emit_leaf_root();
  } else {
    collapser.emit(0);
  }
  return out;
}

int bvh4_depth(const Bvh4& bvh) {
  if (bvh.empty()) return 0;
  int deepest = 0;
  std::vector<std::pair<std::int32_t, int>> stack{{0, 0}};
  while (!stack.empty()) {
    const auto [index, depth] = stack.back();
    stack.pop_back();
    deepest = std::max(deepest, depth);
    for (int i = 0; i < 4; ++i) {
      const Bvh4Node& n = bvh.nodes[index];
      if (n.child[i] >= 0) stack.push_back({n.child[i], depth + 1});
    }
  }
  return deepest;
}

}  // namespace sdf
