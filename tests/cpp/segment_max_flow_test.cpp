// SPDX-License-Identifier: GPL-3.0-or-later
// The max-flow against every cut of small random networks.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "segment/max_flow.h"

namespace {

using sdf::segment::FlowEdge;
using sdf::segment::MaxFlow;

struct Network {
  std::size_t nodes;
  std::vector<double> terminal;
  std::vector<FlowEdge> edges;
};

Network random_network(std::mt19937& rng, std::size_t nodes, double density) {
  std::uniform_real_distribution<double> capacity(0.0, 10.0), coin(0.0, 1.0);
  Network net{nodes, std::vector<double>(nodes), {}};
  for (double& t : net.terminal) t = coin(rng) < 0.2 ? 0.0 : capacity(rng) - 5.0;
  for (std::uint32_t i = 0; i < nodes; ++i)
    for (std::uint32_t j = i + 1; j < nodes; ++j)
      if (coin(rng) < density)
        net.edges.push_back(FlowEdge{i, j, coin(rng) < 0.3 ? 0.0 : capacity(rng),
                                     coin(rng) < 0.3 ? 0.0 : capacity(rng)});
  return net;
}

// The capacity of the cut whose sink side is `sink` (bit i: node i).
double cut_value(const Network& net, unsigned sink) {
  double value = 0.0;
  for (std::size_t i = 0; i < net.nodes; ++i) {
    const bool t = (sink >> i) & 1u;
    if (t && net.terminal[i] > 0) value += net.terminal[i];   // source -> i cut
    if (!t && net.terminal[i] < 0) value -= net.terminal[i];  // i -> sink cut
  }
  for (const FlowEdge& e : net.edges) {
    const bool tf = (sink >> e.from) & 1u, tt = (sink >> e.to) & 1u;
    if (!tf && tt) value += e.capacity;
    if (tf && !tt) value += e.reverse_capacity;
  }
  return value;
}

TEST(SegmentMaxFlow, MatchesEveryCutOfSmallNetworks) {
  std::mt19937 rng(7);
  MaxFlow flow;
  for (int network_index = 0; network_index < 400; ++network_index) {
    const std::size_t nodes = 1 + network_index % 10;
    const Network net = random_network(rng, nodes, network_index % 3 == 0 ? 0.8 : 0.35);
    double best = INFINITY;
    for (unsigned s = 0; s < (1u << nodes); ++s) best = std::min(best, cut_value(net, s));
    flow.reset(net.nodes, net.terminal, net.edges);
    const double value = flow.solve();
    EXPECT_NEAR(value, best, 1e-9 * (1 + best)) << "network_index " << network_index;
    unsigned smallest = 0, largest = 0;
    for (std::size_t i = 0; i < nodes; ++i) {
      smallest |= flow.in_smallest_sink_side(i) ? 1u << i : 0u;
      largest |= flow.in_largest_sink_side(i) ? 1u << i : 0u;
    }
    EXPECT_NEAR(cut_value(net, smallest), best, 1e-9 * (1 + best))
        << "network_index " << network_index;
    EXPECT_NEAR(cut_value(net, largest), best, 1e-9 * (1 + best))
        << "network_index " << network_index;
    // Every optimal cut's sink side holds the smallest and lies within the largest.
    for (unsigned s = 0; s < (1u << nodes); ++s)
      if (cut_value(net, s) <= best + 1e-9 * (1 + best)) {
        EXPECT_EQ(smallest & ~s, 0u) << "network_index " << network_index;
        EXPECT_EQ(s & ~largest, 0u) << "network_index " << network_index;
      }
  }
}

}  // namespace

namespace {

// A long chain with alternating terminals: a search of many steps.
TEST(SegmentMaxFlow, ACheckIsCalledDuringTheSearchAndCanStopIt) {
  const std::uint32_t nodes = 100000;
  std::vector<double> terminal(nodes);
  std::vector<FlowEdge> edges;
  for (std::uint32_t i = 0; i < nodes; ++i) {
    terminal[i] = i % 2 ? 1.0 : -1.0;
    if (i + 1 < nodes) edges.push_back(FlowEdge{i, i + 1, 0.5, 0.5});
  }
  MaxFlow flow;
  flow.reset(nodes, terminal, edges);
  const double unchecked = flow.solve();
  int calls = 0;
  flow.reset(nodes, terminal, edges);
  EXPECT_EQ(flow.solve([&] { ++calls; }), unchecked);
  EXPECT_GE(calls, 10);  // every 4096 steps of at least one per node
  struct Stop {};
  flow.reset(nodes, terminal, edges);
  calls = 0;
  EXPECT_THROW(flow.solve([&] {
    if (++calls == 3) throw Stop{};
  }),
               Stop);
  // The next reset gives a usable network again.
  flow.reset(nodes, terminal, edges);
  EXPECT_EQ(flow.solve(), unchecked);
}

// Per edge capacities each way, in the network's edge order.
void edge_capacities(const Network& net, std::vector<double>& capacity,
                     std::vector<double>& reverse) {
  capacity.clear();
  reverse.clear();
  for (const FlowEdge& e : net.edges) {
    capacity.push_back(e.capacity);
    reverse.push_back(e.reverse_capacity);
  }
}

// A flow resumed after the capacities change (terminals of either sign, edges up or down to
// zero) finds the same minimum cuts as a solve from scratch.
TEST(SegmentMaxFlow, ResumedFlowFindsTheCutsOfTheChangedNetwork) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> coin(0.0, 1.0), capacity(0.0, 10.0);
  MaxFlow resumed, fresh;
  for (int network_index = 0; network_index < 300; ++network_index) {
    const std::size_t nodes = 1 + network_index % 10;
    const Network before = random_network(rng, nodes, 0.5);
    Network after = before;
    for (double& t : after.terminal)
      if (coin(rng) < 0.4) t = coin(rng) < 0.2 ? 0.0 : capacity(rng) - 5.0;
    for (FlowEdge& e : after.edges) {
      if (coin(rng) < 0.4) e.capacity = coin(rng) < 0.3 ? 0.0 : capacity(rng);
      if (coin(rng) < 0.4) e.reverse_capacity = coin(rng) < 0.3 ? 0.0 : capacity(rng);
    }
    std::vector<double> old_capacity, old_reverse, new_capacity, new_reverse;
    edge_capacities(before, old_capacity, old_reverse);
    edge_capacities(after, new_capacity, new_reverse);
    resumed.reset(before.nodes, before.terminal, before.edges);
    resumed.solve();
    MaxFlow::Residuals saved;
    resumed.save(saved);
    resumed.resume(saved, before.terminal.data(), old_capacity.data(), old_reverse.data(),
                   after.terminal.data(), new_capacity.data(), new_reverse.data());
    resumed.solve();
    fresh.reset(after.nodes, after.terminal, after.edges);
    fresh.solve();
    double best = INFINITY;
    for (unsigned s = 0; s < (1u << nodes); ++s) best = std::min(best, cut_value(after, s));
    unsigned smallest = 0, largest = 0;
    for (std::size_t i = 0; i < nodes; ++i) {
      smallest |= resumed.in_smallest_sink_side(i) ? 1u << i : 0u;
      largest |= resumed.in_largest_sink_side(i) ? 1u << i : 0u;
      EXPECT_EQ(resumed.in_smallest_sink_side(i), fresh.in_smallest_sink_side(i))
          << "network_index " << network_index << " node " << i;
      EXPECT_EQ(resumed.in_largest_sink_side(i), fresh.in_largest_sink_side(i))
          << "network_index " << network_index << " node " << i;
    }
    EXPECT_NEAR(cut_value(after, smallest), best, 1e-9 * (1 + best))
        << "network_index " << network_index;
    EXPECT_NEAR(cut_value(after, largest), best, 1e-9 * (1 + best))
        << "network_index " << network_index;
  }
}

}  // namespace
