// SPDX-License-Identifier: GPL-3.0-or-later
// Alpha expansion: never above the starting energy, within the factor 2 of the optimum that
// expansion guarantees for Potts energies, and CGAL's single move.
#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "segment/alpha_expansion.h"
#include "segment/face_graph.h"
#include "segment_test_meshes.h"

namespace {

using namespace sdf::segment;

struct Problem {
  FaceGraph graph;
  std::size_t n = 0, k = 0;
  std::vector<double> weights, costs;
  std::vector<int> labels;
};

// A random Potts problem on the faces of `mesh`, with clamped costs as segmentation makes
// them (ties included).
Problem random_problem(const sdf::test::Arrays& mesh, std::size_t k, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Problem p;
  p.n = mesh.triangles.size() / 3;
  p.k = k;
  p.graph = build_face_graph(mesh.triangles.data(), p.n, mesh.vertices.size() / 3, 1);
  for (std::size_t i = 0; i < p.graph.pairs.size(); ++i)
    p.weights.push_back(u(rng) < 0.3 ? 12.2 : 3 * u(rng));
  for (std::size_t i = 0; i < p.n * k; ++i) p.costs.push_back(u(rng) < 0.3 ? 12.2 : 5 * u(rng));
  for (std::size_t f = 0; f < p.n; ++f) p.labels.push_back(static_cast<int>(rng() % k));
  return p;
}

TEST(SegmentAlphaExpansion, NeverAboveTheStartingEnergy) {
  const auto mesh = sdf::test::dumbbell();
  for (unsigned seed = 0; seed < 6; ++seed)
    for (bool first_only : {true, false})
      for (bool ties_move : {true, false}) {
        Problem p = random_problem(mesh, 2 + seed % 5, seed);
        const double start =
            potts_energy(p.graph, p.weights.data(), p.costs.data(), p.k, p.labels.data(), p.n, 1);
        const double end =
            alpha_expansion(p.graph, p.weights.data(), p.costs.data(), p.k,
                            ExpansionRules{ties_move, first_only}, p.labels.data(), p.n, 2);
        EXPECT_LE(end, start * (1 + 1e-12));
        EXPECT_DOUBLE_EQ(end, potts_energy(p.graph, p.weights.data(), p.costs.data(), p.k,
                                           p.labels.data(), p.n, 1));
      }
}

// The energy written out directly, for the brute force.
double energy(const Problem& p, const std::vector<int>& labels) {
  double e = 0.0;
  for (std::size_t f = 0; f < p.n; ++f) e += p.costs[f * p.k + labels[f]];
  for (std::size_t i = 0; i < p.graph.pairs.size(); ++i)
    if (labels[p.graph.pairs[i].first] != labels[p.graph.pairs[i].second]) e += p.weights[i];
  return e;
}

TEST(SegmentAlphaExpansion, WithinTwiceTheOptimumOnSmallMeshes) {
  const auto mesh = sdf::test::box(1, 1, 1);  // 12 faces, 3 labels: 531441 labellings
  for (unsigned seed = 0; seed < 3; ++seed) {
    Problem p = random_problem(mesh, 3, seed + 10);
    std::vector<int> all(p.n);
    double best = INFINITY;
    for (std::size_t code = 0; code < 531441; ++code) {
      std::size_t c = code;
      for (std::size_t f = 0; f < p.n; ++f, c /= 3) all[f] = static_cast<int>(c % 3);
      best = std::min(best, energy(p, all));
    }
    const double found = alpha_expansion(p.graph, p.weights.data(), p.costs.data(), 3,
                                         ExpansionRules{false, false}, p.labels.data(), p.n, 1);
    EXPECT_NEAR(found, energy(p, p.labels), 1e-9);
    EXPECT_GE(found, best - 1e-9);
    EXPECT_LE(found, 2 * best + 1e-9);
  }
}

Problem tied_problem(const sdf::test::Arrays& mesh, std::size_t k, unsigned seed) {
  Problem p = random_problem(mesh, k, seed);
  std::mt19937 rng(seed);
  for (double& w : p.weights) w = 0.1 * static_cast<double>(1 + rng() % 3);
  for (double& c : p.costs) c = 0.1 * static_cast<double>(rng() % 4);
  return p;
}

std::vector<int> expand(const Problem& p, bool ties_move, bool resume, unsigned threads) {
  std::vector<int> labels = p.labels;
  ExpansionRules rules{ties_move, false};
  rules.resume_flows = resume;
  alpha_expansion(p.graph, p.weights.data(), p.costs.data(), p.k, rules, labels.data(), p.n,
                  threads);
  return labels;
}

TEST(SegmentAlphaExpansion, ResumedFlowsGiveTheLabelsOfMovesFromScratch) {
  // Values as segmentation makes them: continuous, clamped ones tied.
  const auto mesh = sdf::test::dumbbell();
  for (unsigned seed = 0; seed < 6; ++seed)
    for (bool ties_move : {true, false}) {
      const Problem p = random_problem(mesh, 5, seed);
      EXPECT_EQ(expand(p, ties_move, true, 2), expand(p, ties_move, false, 2)) << seed;
    }
}

TEST(SegmentAlphaExpansion, ResumedFlowsAreTheSameForAnyThreadCount) {
  // Costs and weights of a few decimal values, whose cuts tie exactly: there a resumed flow's
  // residuals, sums made in another order (0.1 + 0.2 - 0.3 is not 0), may break a tie the
  // other way than a move from scratch (both minimum cuts, within rounding); the labels
  // still depend on nothing but the input.
  const auto mesh = sdf::test::dumbbell();
  for (unsigned seed = 0; seed < 4; ++seed)
    for (bool ties_move : {true, false}) {
      const Problem p = tied_problem(mesh, 5, seed);
      EXPECT_EQ(expand(p, ties_move, true, 1), expand(p, ties_move, true, 2)) << seed;
    }
}

TEST(SegmentAlphaExpansion, CgalRulesMakeOnlyTheFirstMove) {
  const auto mesh = sdf::test::dumbbell();
  Problem p = random_problem(mesh, 4, 3);
  std::vector<int> labels = p.labels;
  alpha_expansion(p.graph, p.weights.data(), p.costs.data(), p.k, ExpansionRules{true, true},
                  labels.data(), p.n, 1);
  for (std::size_t f = 0; f < p.n; ++f)
    if (labels[f] != p.labels[f]) EXPECT_EQ(labels[f], 0);  // moves to alpha = 0 only
}

}  // namespace
