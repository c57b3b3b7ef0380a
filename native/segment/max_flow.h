// SPDX-License-Identifier: GPL-3.0-or-later
// Minimum s-t cut by Boykov and Kolmogorov's augmenting-path algorithm ("An experimental
// comparison of min-cut/max-flow algorithms for energy minimization in vision", PAMI 2004):
// two search trees, one from the source and one from the sink, that are grown, augmented
// through and repaired rather than rebuilt, which suits the short paths of mesh graphs.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <utility>
#include <vector>

namespace sdf::segment {

// One undirected edge of the network with a capacity each way.
struct FlowEdge {
  std::uint32_t from, to;
  double capacity, reverse_capacity;  // from -> to, to -> from
};

class MaxFlow {
 public:
  // A network of `nodes` nodes. terminal[i] > 0: an arc source -> i of that capacity;
  // terminal[i] < 0: an arc i -> sink of capacity -terminal[i] (give a node both arcs as their
  // difference: the smaller one is flow that crosses any cut). Capacities >= 0, finite.
  // Buffers are kept between calls.
  void reset(std::size_t nodes, const std::vector<double>& terminal,
             const std::vector<FlowEdge>& edges);

  // The same in two steps, for networks solved many times over one set of edges (the moves
  // of an expansion): the edges' ends once (each node's arcs in the order of `ends`), then
  // before each solve the capacities, per edge in that order (an edge of capacity 0 both ways
  // is as if absent: the search never takes it). The edges are filled by `threads` threads;
  // the result does not depend on them.
  void set_topology(std::size_t nodes,
                    const std::vector<std::pair<std::uint32_t, std::uint32_t>>& ends);
  void set_capacities(const double* terminal, const double* capacity,
                      const double* reverse_capacity, unsigned threads = 1);

  // The residual network after solve(): per node its terminal residual (as `terminal`), per
  // arc (in this object's order) its residual capacity.
  struct Residuals {
    std::vector<double> node, arc;
  };
  void save(Residuals& out) const;

  // Starts from the flow `saved` found for capacities old_* (all per edge or node, as
  // set_capacities takes them) on the same edges, now that they are the new ones (Kohli and
  // Torr, "Dynamic graph cuts", PAMI 2007): a terminal's change is added to the node's
  // residual; flow an edge no longer holds is taken back and its ends' terminal arcs both
  // raised by it, which moves every cut by the same amount. solve() then finds a maximum
  // flow of the new network, so the same cuts as from scratch, up to exact ties (the
  // residuals are sums made in another order; rounding may then pick the other cut).
  void resume(const Residuals& saved, const double* old_terminal, const double* old_capacity,
              const double* old_reverse, const double* terminal, const double* capacity,
              const double* reverse_capacity);

  // The flow this call adds (from scratch: the maximum flow, not counting what `terminal`'s
  // differences took out; after resume(): only what it adds to the resumed flow). `check`,
  // when given, is called every few thousand steps of the search (about a millisecond on a
  // mesh graph) and may throw to stop it, leaving the network unusable until it is set again
  // (reset(), or set_capacities() or resume()).
  double solve(const std::function<void()>& check = nullptr);

  // After solve(): whether node i is on the sink's side of the minimum cut whose sink side is
  // smallest (the nodes with a residual path to the sink), or of the one whose sink side is
  // largest (the nodes with no residual path from the source). Either cut is the same whatever
  // the order of augmentations, so the same answer as any exact max-flow gives.
  bool in_smallest_sink_side(std::size_t i) const { return node_[i].tree == kSink; }
  bool in_largest_sink_side(std::size_t i) const { return node_[i].tree != kSource; }

 private:
  static constexpr std::int32_t kTerminal = -1, kOrphan = -2, kNone = -3;
  static constexpr std::uint8_t kFree = 0, kSource = 1, kSink = 2;

  std::int32_t grow(std::uint32_t i);
  void augment(std::int32_t middle);
  void adopt(std::uint32_t orphan);
  bool origin_distance(std::uint32_t j, std::uint32_t& distance);
  void activate(std::uint32_t i);
  void start_trees();

  // An arc of node i: arcs_[first_[i]..first_[i+1]); its sister runs the other way.
  struct Arc {
    std::uint32_t head, sister;
    double residual;
  };
  // What the search reads of a node together, in one cache line's share.
  struct Node {
    double terminal;      // > 0: residual from the source; < 0: residual to the sink
    std::int32_t parent;  // the arc to the parent (node -> parent), or a kind
    std::uint32_t stamp, distance;
    std::uint8_t tree, active;
  };

  std::size_t nodes_ = 0;
  std::vector<std::uint32_t> first_;
  std::vector<std::uint32_t> edge_arc_;  // edge e's arc from -> to (its sister runs back)
  std::vector<Arc> arcs_;
  std::vector<Node> node_;
  std::vector<std::uint32_t> queue_, orphans_;
  std::size_t queue_head_ = 0;
  std::uint32_t time_ = 0;
  double flow_ = 0.0;
};

}  // namespace sdf::segment
