// SPDX-License-Identifier: GPL-3.0-or-later
#include "segment/max_flow.h"

#include <algorithm>
#include <limits>

#include "util/parallel.h"
#include "util/prefetch.h"

namespace sdf::segment {

void MaxFlow::reset(std::size_t nodes, const std::vector<double>& terminal,
                    const std::vector<FlowEdge>& edges) {
  std::vector<std::pair<std::uint32_t, std::uint32_t>> ends(edges.size());
  std::vector<double> capacity(edges.size()), reverse(edges.size());
  for (std::size_t e = 0; e < edges.size(); ++e) {
    ends[e] = {edges[e].from, edges[e].to};
    capacity[e] = edges[e].capacity;
    reverse[e] = edges[e].reverse_capacity;
  }
  set_topology(nodes, ends);
  set_capacities(terminal.data(), capacity.data(), reverse.data());
}

void MaxFlow::set_topology(std::size_t nodes,
                           const std::vector<std::pair<std::uint32_t, std::uint32_t>>& ends) {
  nodes_ = nodes;
  first_.assign(nodes + 1, 0);
  for (const auto& [from, to] : ends) {
    ++first_[from + 1];
    ++first_[to + 1];
  }
  for (std::size_t i = 0; i < nodes; ++i) first_[i + 1] += first_[i];
  arcs_.resize(first_[nodes]);
  edge_arc_.resize(ends.size());
  std::vector<std::uint32_t> fill(first_.begin(), first_.end() - 1);
  for (std::size_t e = 0; e < ends.size(); ++e) {
    const auto [from, to] = ends[e];
    const std::uint32_t a = fill[from]++, b = fill[to]++;
    arcs_[a] = Arc{to, b, 0.0};
    arcs_[b] = Arc{from, a, 0.0};
    edge_arc_[e] = a;
  }
  node_.resize(nodes);
}

void MaxFlow::set_capacities(const double* terminal, const double* capacity,
                             const double* reverse_capacity, unsigned threads) {
  parallel_for(edge_arc_.size(), 1 << 15, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t e = begin; e < end; ++e) {
      Arc& arc = arcs_[edge_arc_[e]];
      arc.residual = capacity[e];
      arcs_[arc.sister].residual = reverse_capacity[e];
    }
  });
  for (std::size_t i = 0; i < nodes_; ++i) node_[i].terminal = terminal[i];
  start_trees();
}

// Every node with a terminal residual the root of its tree, active; the others free.
void MaxFlow::start_trees() {
  queue_.clear();
  orphans_.clear();
  queue_head_ = 0;
  time_ = 0;
  flow_ = 0.0;
  for (std::uint32_t i = 0; i < nodes_; ++i) {
    Node& v = node_[i];
    v = Node{v.terminal, kNone, 0, 0, kFree, 0};
    if (v.terminal == 0.0) continue;
    v.tree = v.terminal > 0.0 ? kSource : kSink;
    v.parent = kTerminal;
    v.distance = 1;
    activate(i);
  }
}

void MaxFlow::save(Residuals& out) const {
  out.node.resize(nodes_);
  out.arc.resize(arcs_.size());
  for (std::size_t i = 0; i < nodes_; ++i) out.node[i] = node_[i].terminal;
  for (std::size_t a = 0; a < arcs_.size(); ++a) out.arc[a] = arcs_[a].residual;
}

void MaxFlow::resume(const Residuals& saved, const double* old_terminal, const double* old_capacity,
                     const double* old_reverse, const double* terminal, const double* capacity,
                     const double* reverse_capacity) {
  for (std::size_t i = 0; i < nodes_; ++i)
    node_[i].terminal = terminal[i] == old_terminal[i]
                            ? saved.node[i]
                            : saved.node[i] + (terminal[i] - old_terminal[i]);
  for (std::size_t a = 0; a < arcs_.size(); ++a) arcs_[a].residual = saved.arc[a];
  for (std::size_t e = 0; e < edge_arc_.size(); ++e) {
    if (capacity[e] == old_capacity[e] && reverse_capacity[e] == old_reverse[e]) continue;
    Arc& forward = arcs_[edge_arc_[e]];
    Arc& back = arcs_[forward.sister];
    const std::uint32_t from = back.head, to = forward.head;
    const double flow = old_capacity[e] - forward.residual;  // from -> to
    forward.residual = capacity[e] - flow;
    back.residual = reverse_capacity[e] + flow;
    // Flow beyond the new capacity goes back: its tail keeps what it sent, its head misses it.
    double excess = 0.0;
    std::uint32_t tail = from, head = to;
    if (forward.residual < 0.0) {
      excess = -forward.residual;
      forward.residual = 0.0;
      back.residual = capacity[e] + reverse_capacity[e];
    } else if (back.residual < 0.0) {
      excess = -back.residual;
      back.residual = 0.0;
      forward.residual = capacity[e] + reverse_capacity[e];
      tail = to, head = from;
    }
    node_[tail].terminal += excess;
    node_[head].terminal -= excess;
  }
  start_trees();
}

void MaxFlow::activate(std::uint32_t i) {
  if (node_[i].active) return;
  node_[i].active = 1;
  queue_.push_back(i);
}

// Grows i's tree by its free neighbours; returns the arc (source tree -> sink tree) of a path
// found, or -1.
std::int32_t MaxFlow::grow(std::uint32_t i) {
  Node& v = node_[i];
  const bool from_source = v.tree == kSource;
  // The neighbours (and, growing from the source, the arcs back) are scattered: ask for all
  // of them at once rather than miss the cache on each in turn.
  for (std::uint32_t a = first_[i]; a < first_[i + 1]; ++a) {
    prefetch(&node_[arcs_[a].head]);
    if (from_source) prefetch(&arcs_[arcs_[a].sister]);
  }
  for (std::uint32_t a = first_[i]; a < first_[i + 1]; ++a) {
    const Arc& arc = arcs_[a];
    // Residual in the direction the tree grows: away from the source, toward the sink.
    if (!((from_source ? arc.residual : arcs_[arc.sister].residual) > 0.0)) continue;
    Node& w = node_[arc.head];
    if (w.tree == kFree) {
      w.tree = v.tree;
      w.parent = static_cast<std::int32_t>(arc.sister);
      w.stamp = v.stamp;
      w.distance = v.distance + 1;
      activate(arc.head);
    } else if (w.tree != v.tree) {
      return static_cast<std::int32_t>(from_source ? a : arc.sister);
    } else if (w.stamp <= v.stamp && w.distance > v.distance) {
      // A shorter way to the terminal: keeps the trees shallow.
      w.parent = static_cast<std::int32_t>(arc.sister);
      w.stamp = v.stamp;
      w.distance = v.distance + 1;
    }
  }
  return -1;
}

// Pushes the bottleneck along source -> ... -> middle -> ... -> sink; nodes whose arc to
// their parent saturates become orphans.
void MaxFlow::augment(std::int32_t middle) {
  const std::uint32_t s_end = arcs_[arcs_[middle].sister].head, t_end = arcs_[middle].head;
  double delta = arcs_[middle].residual;
  std::uint32_t x = s_end;
  for (; node_[x].parent != kTerminal; x = arcs_[node_[x].parent].head)
    delta = std::min(delta, arcs_[arcs_[node_[x].parent].sister].residual);
  delta = std::min(delta, node_[x].terminal);
  for (x = t_end; node_[x].parent != kTerminal; x = arcs_[node_[x].parent].head)
    delta = std::min(delta, arcs_[node_[x].parent].residual);
  delta = std::min(delta, -node_[x].terminal);

  arcs_[middle].residual -= delta;
  arcs_[arcs_[middle].sister].residual += delta;
  auto orphan = [&](std::uint32_t y) {
    node_[y].parent = kOrphan;
    orphans_.push_back(y);
  };
  for (x = s_end;;) {
    const std::int32_t a = node_[x].parent;
    if (a == kTerminal) {
      node_[x].terminal -= delta;
      if (!(node_[x].terminal > 0.0)) orphan(x);
      break;
    }
    Arc& down = arcs_[arcs_[a].sister];  // parent -> x, the way the flow goes
    down.residual -= delta;
    arcs_[a].residual += delta;
    const std::uint32_t up = arcs_[a].head;
    if (!(down.residual > 0.0)) orphan(x);
    x = up;
  }
  for (x = t_end;;) {
    const std::int32_t a = node_[x].parent;
    if (a == kTerminal) {
      node_[x].terminal += delta;
      if (!(node_[x].terminal < 0.0)) orphan(x);
      break;
    }
    arcs_[a].residual -= delta;
    arcs_[arcs_[a].sister].residual += delta;
    const std::uint32_t up = arcs_[a].head;
    if (!(arcs_[a].residual > 0.0)) orphan(x);
    x = up;
  }
  flow_ += delta;
}

// Whether j still reaches its terminal through parents, and how far (stamped for this round).
bool MaxFlow::origin_distance(std::uint32_t j, std::uint32_t& distance) {
  std::uint32_t d = 0;
  for (std::uint32_t x = j;; x = arcs_[node_[x].parent].head) {
    Node& v = node_[x];
    if (v.stamp == time_) {
      d += v.distance;
      break;
    }
    ++d;
    if (v.parent == kTerminal) {
      v.stamp = time_;
      v.distance = 1;
      break;
    }
    if (v.parent == kOrphan || v.parent == kNone) return false;
  }
  distance = d;
  for (std::uint32_t x = j; node_[x].stamp != time_; x = arcs_[node_[x].parent].head) {
    node_[x].stamp = time_;
    node_[x].distance = d--;
  }
  return true;
}

// Finds the orphan a new parent in its tree, or frees it (and orphans its children).
void MaxFlow::adopt(std::uint32_t o) {
  const std::uint8_t tree = node_[o].tree;
  const bool source = tree == kSource;
  std::int32_t best_arc = -1;
  std::uint32_t best = std::numeric_limits<std::uint32_t>::max();
  for (std::uint32_t a = first_[o]; a < first_[o + 1]; ++a) {
    prefetch(&node_[arcs_[a].head]);
    if (source) prefetch(&arcs_[arcs_[a].sister]);
  }
  for (std::uint32_t a = first_[o]; a < first_[o + 1]; ++a) {
    const Arc& arc = arcs_[a];
    if (node_[arc.head].tree != tree ||
        !((source ? arcs_[arc.sister].residual : arc.residual) > 0.0))
      continue;
    std::uint32_t d;
    if (origin_distance(arc.head, d) && d < best) {
      best = d;
      best_arc = static_cast<std::int32_t>(a);
    }
  }
  if (best_arc >= 0) {
    node_[o].parent = best_arc;
    node_[o].stamp = time_;
    node_[o].distance = best + 1;
    return;
  }
  for (std::uint32_t a = first_[o]; a < first_[o + 1]; ++a) {
    const Arc& arc = arcs_[a];
    Node& w = node_[arc.head];
    if (w.tree != tree) continue;
    if ((source ? arcs_[arc.sister].residual : arc.residual) > 0.0) activate(arc.head);
    if (w.parent >= 0 && arcs_[w.parent].head == o) {
      w.parent = kOrphan;
      orphans_.push_back(arc.head);
    }
  }
  node_[o].tree = kFree;
  node_[o].parent = kNone;
}

double MaxFlow::solve(const std::function<void()>& check) {
  constexpr std::uint32_t kCheckEvery = 4096;
  std::uint32_t steps = 0;
  std::int64_t current = -1;
  for (;;) {
    if (check && ++steps == kCheckEvery) {
      steps = 0;
      check();
    }
    std::uint32_t i;
    if (current >= 0 && node_[current].tree != kFree) {
      i = static_cast<std::uint32_t>(current);
    } else {
      while (queue_head_ < queue_.size() && node_[queue_[queue_head_]].tree == kFree)
        node_[queue_[queue_head_++]].active = 0;
      if (queue_head_ == queue_.size()) break;
      i = queue_[queue_head_++];
      node_[i].active = 0;
      if (queue_head_ + 8 < queue_.size()) {  // the node taken a few steps later
        const std::uint32_t later = queue_[queue_head_ + 8];
        prefetch(&node_[later]);
        // A pointer, not an index: a last node without arcs starts one past the end.
        prefetch(arcs_.data() + first_[later]);
      }
      if (queue_head_ > 4096 && queue_head_ * 2 > queue_.size()) {
        queue_.erase(queue_.begin(), queue_.begin() + static_cast<std::ptrdiff_t>(queue_head_));
        queue_head_ = 0;
      }
    }
    current = -1;
    const std::int32_t middle = grow(i);
    if (middle < 0) continue;
    current = i;
    ++time_;
    augment(middle);
    // Orphans in the order found (first in, first out); adoption appends the children it
    // orphans.
    for (std::size_t k = 0; k < orphans_.size(); ++k) adopt(orphans_[k]);
    orphans_.clear();
  }
  return flow_;
}

}  // namespace sdf::segment
