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

// The network of one expansion move, over every face and pair: a face labelled alpha stays
// alpha, so its node gets no terminal arc and its pairs no capacity (the search never enters
// it); every other face is on the sink's side if it moves to alpha. A pair's Potts term
// E(p, q) over {keep, alpha}^2 is written as terminal capacities and one arc each (Kolmogorov
// and Zabih, "What energy functions can be minimized via graph cuts?", PAMI 2004): same
// labels, an arc of w each way; different labels, w when q keeps plus an arc p -> q of w
// (paid when p keeps and q moves); one of them alpha, w when the other keeps. The edges are
// laid out once; each move only writes capacities, face by face and pair by pair in parallel,
// each face summing its terms in pair order.
class ExpansionNetwork {
 public:
  ExpansionNetwork(const FaceGraph& graph, std::size_t n, unsigned threads)
      : graph_(graph), n_(n), threads_(threads) {
    std::vector<std::pair<std::uint32_t, std::uint32_t>> ends(graph.pairs.size());
    pair_at_.resize(graph.neighbours.size());
    std::vector<std::uint32_t> fill(graph.offsets.begin(), graph.offsets.end() - 1);
    for (std::size_t p = 0; p < graph.pairs.size(); ++p) {
      ends[p] = {graph.pairs[p].first, graph.pairs[p].second};
      pair_at_[fill[graph.pairs[p].first]++] = static_cast<std::uint32_t>(p);
      pair_at_[fill[graph.pairs[p].second]++] = static_cast<std::uint32_t>(p);
    }
    flow_.set_topology(n, ends);
  }

  // `check` (may be empty) between the passes, each over every face or pair. With `reuse`,
  // a move to an alpha solved before starts from the flow found then (dynamic graph cuts):
  // later sweeps change few labels, so little flow is left to find.
  void build(const double* weights, const double* costs, std::size_t k, const int* labels,
             int alpha, bool reuse, const std::function<void()>& check) {
    capacities(weights, costs, k, labels, alpha, terminal_, capacity_, reverse_);
    if (check) check();
    reuse_ = reuse && remember(alpha, k);
    const Saved* saved = reuse_ ? &saved_[static_cast<std::size_t>(alpha)] : nullptr;
    if (saved && !saved->labels.empty()) {
      capacities(weights, costs, k, saved->labels.data(), alpha, old_terminal_, old_capacity_,
                 old_reverse_);
      if (check) check();
      flow_.resume(saved->flow, old_terminal_.data(), old_capacity_.data(), old_reverse_.data(),
                   terminal_.data(), capacity_.data(), reverse_.data());
    } else {
      flow_.set_capacities(terminal_.data(), capacity_.data(), reverse_.data(), threads_);
    }
    labels_ = labels;
  }

  // Solves the cut and writes the moved labels into `out` (a copy of the current labels).
  void move(int alpha, bool ties_move, int* out, const std::function<void()>& check) {
    flow_.solve(check);
    if (reuse_) {
      Saved& saved = saved_[static_cast<std::size_t>(alpha)];
      saved.labels.assign(labels_, labels_ + n_);
      flow_.save(saved.flow);
    }
    for (std::size_t f = 0; f < n_; ++f) {
      if (out[f] == alpha) continue;
      if (ties_move ? flow_.in_largest_sink_side(f) : flow_.in_smallest_sink_side(f))
        out[f] = alpha;
    }
  }

 private:
  // What a move to one alpha left: the labels its network was built for, and its flow.
  struct Saved {
    std::vector<int> labels;
    MaxFlow::Residuals flow;
  };

  // Whether alpha's flow may be kept: the flows of all k labels within kSavedBytes.
  bool remember(int alpha, std::size_t k) {
    constexpr double kSavedBytes = 384.0 * (1 << 20);
    const double each = static_cast<double>(n_) * (sizeof(int) + sizeof(double)) +
                        static_cast<double>(graph_.neighbours.size()) * sizeof(double);
    if (saved_.size() < k) saved_.resize(k);
    return static_cast<double>(alpha + 1) * each <= kSavedBytes;
  }

  // The terminal capacities per face and the arcs' capacities per pair of the move to alpha
  // from `labels`.
  void capacities(const double* weights, const double* costs, std::size_t k, const int* labels,
                  int alpha, std::vector<double>& terminal, std::vector<double>& capacity,
                  std::vector<double>& reverse) const {
    terminal.resize(n_);
    capacity.resize(graph_.pairs.size());
    reverse.resize(graph_.pairs.size());
    parallel_for(n_, 1 << 14, threads_, [&](std::size_t begin, std::size_t end) {
      for (std::size_t f = begin; f < end; ++f) {
        if (labels[f] == alpha) {
          terminal[f] = 0.0;
          continue;
        }
        double keep = costs[f * k + static_cast<std::size_t>(labels[f])];
        const double move = costs[f * k + static_cast<std::size_t>(alpha)];
        for (std::uint32_t i = graph_.offsets[f]; i < graph_.offsets[f + 1]; ++i) {
          const int other = labels[graph_.neighbours[i]];
          const std::uint32_t p = pair_at_[i];
          if (other == alpha || (other != labels[f] && graph_.pairs[p].second == f))
            keep += weights[p];
        }
        terminal[f] = move - keep;
      }
    });
    parallel_for(capacity.size(), 1 << 14, threads_, [&](std::size_t begin, std::size_t end) {
      for (std::size_t p = begin; p < end; ++p) {
        const int a = labels[graph_.pairs[p].first], b = labels[graph_.pairs[p].second];
        const bool both = a != alpha && b != alpha;
        capacity[p] = both ? weights[p] : 0.0;
        reverse[p] = both && a == b ? weights[p] : 0.0;
      }
    });
  }

  const FaceGraph& graph_;
  std::size_t n_;
  unsigned threads_;
  std::vector<std::uint32_t> pair_at_;  // the pair of each entry of graph_.neighbours
  std::vector<double> terminal_, capacity_, reverse_;
  std::vector<double> old_terminal_, old_capacity_, old_reverse_;
  std::vector<Saved> saved_;     // per alpha
  const int* labels_ = nullptr;  // those of the last build
  bool reuse_ = false;
  MaxFlow flow_;
};

}  // namespace

double alpha_expansion(const FaceGraph& graph, const double* weights, const double* costs,
                       std::size_t k, const ExpansionRules& rules, int* labels, std::size_t n,
                       unsigned threads, StageProgress* progress, double from, double to) {
  ExpansionNetwork network(graph, n, threads);
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
      network.build(weights, costs, k, labels, a, rules.resume_flows && !rules.first_move_only,
                    inside);
      std::copy(labels, labels + n, candidate.begin());
      network.move(a, rules.ties_move, candidate.data(), inside);
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
