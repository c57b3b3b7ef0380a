// SPDX-License-Identifier: GPL-3.0-or-later
#include "accel/bvh8.h"

#include <algorithm>
#include <limits>

#include "accel/bvh_collapse.h"
#include "util/test_overrides.h"

namespace sdf {

namespace {

class Collapser {
 public:
  Collapser(const Bvh& bvh, Bvh8& out, int merge_up_to)
      : bvh_(bvh), out_(out), merge_up_to_(merge_up_to), triangles_below_(bvh.nodes.size(), -1) {
    count_triangles(0);
  }

  // Emits the wide node for binary node `index` and returns its position.
  std::int32_t emit(std::int32_t index) {
    std::int32_t slots[8];
    const int used = gather_wide_children(
        bvh_, index, [&](std::int32_t node) { return is_leaf(node); }, slots);
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
    set_wide_box(out_.nodes[node], i, n);
  }

  // A binary leaf, or a subtree small enough to become one: its triangles in a packet or two
  // cost one SIMD test each, less than visiting the boxes that would separate them.
  bool is_leaf(std::int32_t index) const {
    return bvh_.nodes[index].count > 0 || triangles_below_[index] <= merge_up_to_;
  }

  int count_triangles(std::int32_t index) {
    const kern::SdfBvhNode& n = bvh_.nodes[index];
    const int below =
        n.count > 0 ? n.count : count_triangles(n.first) + count_triangles(n.first + 1);
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

  void clear_slot(std::int32_t node, int i) { clear_wide_slot(out_.nodes[node], i); }

  const Bvh& bvh_;
  Bvh8& out_;
  int merge_up_to_;
  std::vector<int> triangles_below_;  // per binary node
  std::vector<std::int32_t> leaf_;
};

}  // namespace

bool bvh8_supported() {
#if SDF_HAVE_BVH8
  // Tests act out a CPU without AVX2, to run the 4-wide fallback end to end on the machines
  // they have.
  if (test_overrides().cpu_without_avx2) return false;
  return cpu_features().avx2 && cpu_features().fma;
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
