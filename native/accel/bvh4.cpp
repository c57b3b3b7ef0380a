// SPDX-License-Identifier: GPL-3.0-or-later
#include "accel/bvh4.h"

#include <algorithm>
#include <limits>

#include "accel/bvh_collapse.h"

namespace sdf {

namespace {

class Collapser {
 public:
  Collapser(const Bvh& bvh, Bvh4& out) : bvh_(bvh), out_(out) {}

  // Emits the wide node for binary node `index`, `depth` wide levels below the root, and
  // returns its position.
  std::int32_t emit(std::int32_t index, int depth) {
    out_.depth = std::max(out_.depth, depth);
    std::int32_t slots[4];
    const int used = gather_wide_children(
        bvh_, index, [&](std::int32_t node) { return bvh_.nodes[node].count > 0; }, slots);
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
          const std::int32_t child = emit(slots[i], depth + 1);  // may reallocate out_.nodes
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
    set_wide_box(out_.nodes[node], i, n);
  }
  void clear_slot(std::int32_t node, int i) { clear_wide_slot(out_.nodes[node], i); }

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
    collapser.emit(0, 0);
  }
  return out;
}

}  // namespace sdf
