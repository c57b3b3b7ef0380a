// SPDX-License-Identifier: GPL-3.0-or-later
#include "bvh8.h"

#include <algorithm>
#include <limits>

namespace sdf {

namespace {

float half_area(const kern::SdfBvhNode& n) {
  const float dx = n.hi_x - n.lo_x, dy = n.hi_y - n.lo_y, dz = n.hi_z - n.lo_z;
  return dx * dy + dy * dz + dz * dx;
}

class Collapser {
 public:
  Collapser(const Bvh& bvh, Bvh8& out, int merge_up_to)
      : bvh_(bvh), out_(out), merge_up_to_(merge_up_to), triangles_below_(bvh.nodes.size(), -1) {
    count_triangles(0);
  }

  // Emits the wide node for binary node `index` and returns its position.
  std::int32_t emit(std::int32_t index) {
    // Gather up to eight binary nodes below `index`: open the largest inner child until full
    // (surface area is the chance that a ray through the parent enters it).
    std::int32_t slots[8];
    slots[0] = bvh_.nodes[index].first;
    slots[1] = bvh_.nodes[index].first + 1;
    int used = 2;
    while (used < 8) {
      int best = -1;
      float best_area = -1.0f;
      for (int i = 0; i < used; ++i) {
        const kern::SdfBvhNode& n = bvh_.nodes[slots[i]];
        if (!is_leaf(slots[i]) && half_area(n) > best_area) {
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
    for (int i = 0; i < 8; ++i) {
      if (i < used) {
        const kern::SdfBvhNode n = bvh_.nodes[slots[i]];
        set_box(me, i, n);
        if (is_leaf(slots[i])) {
          set_leaf(me, i, slots[i]);
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

  bool root_is_leaf() const { return is_leaf(0); }

  // A tree whose root is a leaf: one wide node with one slot.
  void emit_leaf_root() {
    out_.nodes.emplace_back();
    set_box(0, 0, bvh_.nodes[0]);
    set_leaf(0, 0, 0);
    for (int i = 1; i < 8; ++i) clear_slot(0, i);
  }

 private:
  void set_box(std::int32_t node, int i, const kern::SdfBvhNode& n) {
    Bvh8Node& w = out_.nodes[node];
    w.lo_x[i] = n.lo_x;
    w.lo_y[i] = n.lo_y;
    w.lo_z[i] = n.lo_z;
    w.hi_x[i] = n.hi_x;
    w.hi_y[i] = n.hi_y;
    w.hi_z[i] = n.hi_z;
  }

  // A binary leaf, or a subtree small enough to become one: its triangles in a packet or two
  // cost one SIMD test each, less than visiting the boxes that would separate them.
  bool is_leaf(std::int32_t index) const {
    return bvh_.nodes[index].count > 0 || triangles_below_[index] <= merge_up_to_;
  }

  int count_triangles(std::int32_t index) {
    const kern::SdfBvhNode& n = bvh_.nodes[index];
    const int below = n.count > 0 ? n.count
                                  : count_triangles(n.first) + count_triangles(n.first + 1);
    return triangles_below_[index] = below;
  }

  // The triangles of the binary leaves below `index`, in tree order.
  void gather(std::int32_t index, std::vector<std::int32_t>& out) const {
    const kern::SdfBvhNode& n = bvh_.nodes[index];
    if (n.count > 0) {
      for (std::int32_t k = n.first; k < n.first + n.count; ++k) out.push_back(k);
    } else {
      gather(n.first, out);
      gather(n.first + 1, out);
    }
  }

  // Repacks the triangles below binary node `index`, four to a packet.
  void set_leaf(std::int32_t node, int i, std::int32_t index) {
    leaf_.clear();
    gather(index, leaf_);
    const std::int32_t first = static_cast<std::int32_t>(out_.packets.size());
    for (std::size_t k = 0; k < leaf_.size(); ++k) {
      if (k % 4 == 0) out_.packets.push_back(empty_packet());
      TrianglePacket4& p = out_.packets.back();
      const kern::SdfTriangle& t = bvh_.triangles[leaf_[k]];
      const int lane = k % 4;
      p.v0_x[lane] = t.v0_x;
      p.v0_y[lane] = t.v0_y;
      p.v0_z[lane] = t.v0_z;
      p.e1_x[lane] = t.e1_x;
      p.e1_y[lane] = t.e1_y;
      p.e1_z[lane] = t.e1_z;
      p.e2_x[lane] = t.e2_x;
      p.e2_y[lane] = t.e2_y;
      p.e2_z[lane] = t.e2_z;
      p.id[lane] = t.id;
    }
    out_.nodes[node].child[i] = ~first;
    out_.nodes[node].count[i] = static_cast<std::int32_t>(out_.packets.size()) - first;
  }

  static TrianglePacket4 empty_packet() {
    TrianglePacket4 p{};
    std::fill(std::begin(p.id), std::end(p.id), std::numeric_limits<std::int32_t>::max());
    return p;
  }

  void clear_slot(std::int32_t node, int i) {
    const float inf = std::numeric_limits<float>::infinity();
    Bvh8Node& w = out_.nodes[node];
    w.lo_x[i] = w.lo_y[i] = w.lo_z[i] = inf;
    w.hi_x[i] = w.hi_y[i] = w.hi_z[i] = -inf;
    w.child[i] = ~0;
    w.count[i] = 0;
  }

  const Bvh& bvh_;
  Bvh8& out_;
  int merge_up_to_;
  std::vector<int> triangles_below_;  // per binary node
  std::vector<std::int32_t> leaf_;
};

}  // namespace

bool bvh8_supported() {
#if SDF_HAVE_BVH8
  return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
#else
  return false;
#endif
}

Bvh8 collapse_to_bvh8(const Bvh& bvh, int merge_up_to) {
  Bvh8 out;
  if (bvh.empty()) return out;
  out.nodes.reserve(bvh.nodes.size() / 4 + 1);
  out.packets.reserve(bvh.triangles.size() / 2 + 1);
  Collapser collapser(bvh, out, merge_up_to);
  if (collapser.root_is_leaf()) {
    collapser.emit_leaf_root();
  } else {
    collapser.emit(0);
  }
  return out;
}

}  // namespace sdf
