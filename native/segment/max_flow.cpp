// SPDX-License-Identifier: GPL-3.0-or-later
#include "segment/max_flow.h"

#include <algorithm>
#include <limits>

namespace sdf::segment {

void MaxFlow::reset(std::size_t nodes, const std::vector<double>& terminal,
                    const std::vector<FlowEdge>& edges) {
  nodes_ = nodes;
  first_.assign(nodes + 1, 0);
  for (const FlowEdge& e : edges) {
    ++first_[e.from + 1];
    ++first_[e.to + 1];
  }
  for (std::size_t i = 0; i < nodes; ++i) first_[i + 1] += first_[i];
  const std::size_t arcs = first_[nodes];
  head_.resize(arcs);
  sister_.resize(arcs);
  residual_.resize(arcs);
  std::vector<std::uint32_t> fill(first_.begin(), first_.end() - 1);
  for (const FlowEdge& e : edges) {
    const std::uint32_t a = fill[e.from]++, b = fill[e.to]++;
    head_[a] = e.to;
    head_[b] = e.from;
    sister_[a] = b;
    sister_[b] = a;
    residual_[a] = e.capacity;
    residual_[b] = e.reverse_capacity;
  }
  terminal_.assign(terminal.begin(), terminal.begin() + static_cast<std::ptrdiff_t>(nodes));
  parent_.assign(nodes, kNone);
  tree_.assign(nodes, kFree);
  active_.assign(nodes, 0);
  stamp_.assign(nodes, 0);
  distance_.assign(nodes, 0);
  queue_.clear();
  orphans_.clear();
  queue_head_ = 0;
  time_ = 0;
  flow_ = 0.0;
  for (std::uint32_t i = 0; i < nodes; ++i) {
    if (terminal_[i] == 0.0) continue;
    tree_[i] = terminal_[i] > 0.0 ? kSource : kSink;
    parent_[i] = kTerminal;
    distance_[i] = 1;
    activate(i);
  }
}

void MaxFlow::activate(std::uint32_t i) {
  if (active_[i]) return;
  active_[i] = 1;
  queue_.push_back(i);
}

// Grows i's tree by its free neighbours; returns the arc (source tree -> sink tree) of a path
// found, or -1.
std::int32_t MaxFlow::grow(std::uint32_t i) {
  const bool from_source = tree_[i] == kSource;
  for (std::uint32_t a = first_[i]; a < first_[i + 1]; ++a) {
    const std::uint32_t j = head_[a];
    // Residual in the direction the tree grows: away from the source, toward the sink.
    if (!(residual_[from_source ? a : sister_[a]] > 0.0)) continue;
    if (tree_[j] == kFree) {
      tree_[j] = tree_[i];
      parent_[j] = static_cast<std::int32_t>(sister_[a]);
      stamp_[j] = stamp_[i];
      distance_[j] = distance_[i] + 1;
      activate(j);
    } else if (tree_[j] != tree_[i]) {
      return static_cast<std::int32_t>(from_source ? a : sister_[a]);
    } else if (stamp_[j] <= stamp_[i] && distance_[j] > distance_[i]) {
      // A shorter way to the terminal: keeps the trees shallow.
      parent_[j] = static_cast<std::int32_t>(sister_[a]);
      stamp_[j] = stamp_[i];
      distance_[j] = distance_[i] + 1;
    }
  }
  return -1;
}

// Pushes the bottleneck along source -> ... -> middle -> ... -> sink; nodes whose arc to
// their parent saturates become orphans.
void MaxFlow::augment(std::int32_t middle) {
  double delta = residual_[middle];
  std::uint32_t x = head_[sister_[middle]];
  for (; parent_[x] != kTerminal; x = head_[parent_[x]])
    delta = std::min(delta, residual_[sister_[parent_[x]]]);
  delta = std::min(delta, terminal_[x]);
  for (x = head_[middle]; parent_[x] != kTerminal; x = head_[parent_[x]])
    delta = std::min(delta, residual_[parent_[x]]);
  delta = std::min(delta, -terminal_[x]);

  residual_[middle] -= delta;
  residual_[sister_[middle]] += delta;
  for (x = head_[sister_[middle]];; ) {
    const std::int32_t a = parent_[x];
    if (a == kTerminal) {
      terminal_[x] -= delta;
      if (!(terminal_[x] > 0.0)) parent_[x] = kOrphan, orphans_.push_back(x);
      break;
    }
    residual_[sister_[a]] -= delta;
    residual_[a] += delta;
    const std::uint32_t up = head_[a];
    if (!(residual_[sister_[a]] > 0.0)) parent_[x] = kOrphan, orphans_.push_back(x);
    x = up;
  }
  for (x = head_[middle];;) {
    const std::int32_t a = parent_[x];
    if (a == kTerminal) {
      terminal_[x] += delta;
      if (!(terminal_[x] < 0.0)) parent_[x] = kOrphan, orphans_.push_back(x);
      break;
    }
    residual_[a] -= delta;
    residual_[sister_[a]] += delta;
    const std::uint32_t up = head_[a];
    if (!(residual_[a] > 0.0)) parent_[x] = kOrphan, orphans_.push_back(x);
    x = up;
  }
  flow_ += delta;
}

// Whether j still reaches its terminal through parents, and how far (stamped for this round).
bool MaxFlow::origin_distance(std::uint32_t j, std::uint32_t& distance) {
  std::uint32_t d = 0;
  for (std::uint32_t x = j;; x = head_[parent_[x]]) {
    if (stamp_[x] == time_) {
      d += distance_[x];
      break;
    }
    const std::int32_t a = parent_[x];
    ++d;
    if (a == kTerminal) {
      stamp_[x] = time_;
      distance_[x] = 1;
      break;
    }
    if (a == kOrphan || a == kNone) return false;
  }
  distance = d;
  for (std::uint32_t x = j; stamp_[x] != time_; x = head_[parent_[x]]) {
    stamp_[x] = time_;
    distance_[x] = d--;
  }
  return true;
}

// Finds the orphan a new parent in its tree, or frees it (and orphans its children).
void MaxFlow::adopt(std::uint32_t o) {
  const bool source = tree_[o] == kSource;
  std::int32_t best_arc = -1;
  std::uint32_t best = std::numeric_limits<std::uint32_t>::max();
  for (std::uint32_t a = first_[o]; a < first_[o + 1]; ++a) {
    const std::uint32_t j = head_[a];
    if (tree_[j] != tree_[o] || !(residual_[source ? sister_[a] : a] > 0.0)) continue;
    std::uint32_t d;
    if (origin_distance(j, d) && d < best) {
      best = d;
      best_arc = static_cast<std::int32_t>(a);
    }
  }
  if (best_arc >= 0) {
    parent_[o] = best_arc;
    stamp_[o] = time_;
    distance_[o] = best + 1;
    return;
  }
  for (std::uint32_t a = first_[o]; a < first_[o + 1]; ++a) {
    const std::uint32_t j = head_[a];
    if (tree_[j] != tree_[o]) continue;
    if (residual_[source ? sister_[a] : a] > 0.0) activate(j);
    const std::int32_t p = parent_[j];
    if (p >= 0 && head_[p] == o) {
      parent_[j] = kOrphan;
      orphans_.push_back(j);
    }
  }
  tree_[o] = kFree;
  parent_[o] = kNone;
}

double MaxFlow::solve() {
  std::int64_t current = -1;
  for (;;) {
    std::uint32_t i;
    if (current >= 0 && tree_[current] != kFree) {
      i = static_cast<std::uint32_t>(current);
    } else {
      while (queue_head_ < queue_.size() && tree_[queue_[queue_head_]] == kFree)
        active_[queue_[queue_head_++]] = 0;
      if (queue_head_ == queue_.size()) break;
      i = queue_[queue_head_++];
      active_[i] = 0;
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
    while (!orphans_.empty()) {
      const std::uint32_t o = orphans_.back();
      orphans_.pop_back();
      adopt(o);
    }
  }
  return flow_;
}

}  // namespace sdf::segment
