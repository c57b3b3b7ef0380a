// SPDX-License-Identifier: GPL-3.0-or-later
#include "segment/alpha_expansion.h"

#include <algorithm>
#include <cstdint>
#include <functional>
#include <limits>

#include "segment/max_flow.h"
#include "util/parallel.h"

namespace sdf::segment {

double potts_energy(const FaceGraph& graph, const double* weights, const double* costs,
                    std::size_t k, const int* labels, std::size_t n, unsigned threads) {
  constexpr std::size_t kBlock = 1 << 14;
  const std::size_t pairs = graph.pairs.size();
  const std::size_t blocks = (std::max(n, pairs) + kBlock - 1) / kBlock;
  std::vector<double> sums(blocks, 0.0);
  parallel_for(blocks, 1, threads, [&](std::size_t b0, std::size_t b1) {
    for (std::size_t b = b0; b < b1; ++b) {
      double s = 0.0;
      for (std::size_t f = b * kBlock; f < std::min(n, (b + 1) * kBlock); ++f)
        s += costs[f * k + static_cast<std::size_t>(labels[f])];
      for (std::size_t p = b * kBlock; p < std::min(pairs, (b + 1) * kBlock); ++p)
        if (labels[graph.pairs[p].first] != labels[graph.pairs[p].second]) s += weights[p];
      sums[b] = s;
    }
  });
  double energy = 0.0;
  for (double s : sums) energy += s;
  return energy;
}

namespace {

// The network of one expansion move. Faces labelled alpha stay alpha and are left out; every
// other face is a node, on the sink's side if it moves to alpha. A pair's Potts term E(p, q)
// over {keep, alpha}^2 is written as terminal capacities and one arc each (Kolmogorov and
// Zabih, "What energy functions can be minimized via graph cuts?", PAMI 2004): same labels,
// an arc of w each way; different labels, w when q keeps plus an arc p -> q of w (paid when p
// keeps and q moves); one of them alpha, w when the other keeps.
class ExpansionNetwork {
 public:
  // `check` (may be empty) between the passes, each over every face or pair.
  void build(const FaceGraph& graph, const double* weights, const double* costs, std::size_t k,
             const int* labels, std::size_t n, int alpha, const std::function<void()>& check) {
    node_.assign(n, -1);
    std::size_t nodes = 0;
    for (std::size_t f = 0; f < n; ++f)
      if (labels[f] != alpha) node_[f] = static_cast<std::int32_t>(nodes++);
    keep_.assign(nodes, 0.0);
    move_.assign(nodes, 0.0);
    for (std::size_t f = 0; f < n; ++f) {
      if (node_[f] < 0) continue;
      keep_[node_[f]] = costs[f * k + static_cast<std::size_t>(labels[f])];
      move_[node_[f]] = costs[f * k + static_cast<std::size_t>(alpha)];
    }
    if (check) check();
    edges_.clear();
    for (std::size_t p = 0; p < graph.pairs.size(); ++p) {
      const std::uint32_t f = graph.pairs[p].first, g = graph.pairs[p].second;
      const std::int32_t u = node_[f], v = node_[g];
      const double w = weights[p];
      if (u < 0 && v < 0) continue;
      if (u < 0 || v < 0) {
        keep_[u < 0 ? v : u] += w;
      } else if (labels[f] == labels[g]) {
        edges_.push_back(
            FlowEdge{static_cast<std::uint32_t>(u), static_cast<std::uint32_t>(v), w, w});
      } else {
        keep_[v] += w;
        edges_.push_back(
            FlowEdge{static_cast<std::uint32_t>(u), static_cast<std::uint32_t>(v), w, 0.0});
      }
    }
    // Source side = keep: a node pays keep_ by cutting its arc to the sink, move_ by cutting
    // the source's arc to it. Only the difference matters to the cut.
    terminal_.resize(nodes);
    for (std::size_t i = 0; i < nodes; ++i) terminal_[i] = move_[i] - keep_[i];
    if (check) check();
    flow_.reset(nodes, terminal_, edges_);
  }

  // Solves the cut and writes the moved labels into `out` (a copy of the current labels).
  void move(int alpha, bool ties_move, std::size_t n, int* out,
            const std::function<void()>& check) {
    flow_.solve(check);
    for (std::size_t f = 0; f < n; ++f) {
      if (node_[f] < 0) continue;
      const auto i = static_cast<std::size_t>(node_[f]);
      if (ties_move ? flow_.in_largest_sink_side(i) : flow_.in_smallest_sink_side(i))
        out[f] = alpha;
    }
  }

 private:
  std::vector<std::int32_t> node_;
  std::vector<double> keep_, move_, terminal_;
  std::vector<FlowEdge> edges_;
  MaxFlow flow_;
};

}  // namespace

double alpha_expansion(const FaceGraph& graph, const double* weights, const double* costs,
                       std::size_t k, const ExpansionRules& rules, int* labels, std::size_t n,
                       unsigned threads, StageProgress* progress, double from, double to) {
  ExpansionNetwork network;
  std::vector<int> candidate(n);
  double best = std::numeric_limits<double>::max();
  // A move to alpha from labels it has already been tried on, or from the labels its own
  // kept move made, finds nothing better (every expansion of the moved labels is an expansion
  // of the labels it moved from): such moves are skipped, which leaves the result as it was
  // and saves most of the last sweep.
  std::vector<long> tried(k, -1);
  long moves = 0, last_kept = 0;
  bool improved = true;
  while (improved) {
    improved = false;
    for (std::size_t alpha = 0; alpha < k; ++alpha) {
      if (tried[alpha] >= last_kept) continue;
      const double done =
          from + (to - from) * static_cast<double>(moves) / static_cast<double>(moves + k);
      std::function<void()> inside;
      if (progress) {
        progress->report(done);
        inside = [progress, done] { progress->poll(done); };
      }
      tried[alpha] = ++moves;
      const int a = static_cast<int>(alpha);
      network.build(graph, weights, costs, k, labels, n, a, inside);
      std::copy(labels, labels + n, candidate.begin());
      network.move(a, rules.ties_move, n, candidate.data(), inside);
      const double energy = potts_energy(graph, weights, costs, k, candidate.data(), n, threads);
      if (best - energy <= energy * 1e-10) continue;
      best = energy;
      improved = true;
      last_kept = moves;
      std::copy(candidate.begin(), candidate.end(), labels);
      if (rules.first_move_only) return best;
    }
  }
  return best == std::numeric_limits<double>::max()
             ? potts_energy(graph, weights, costs, k, labels, n, threads)
             : best;
}

}  // namespace sdf::segment
