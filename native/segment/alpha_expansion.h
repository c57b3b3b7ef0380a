// SPDX-License-Identifier: GPL-3.0-or-later
// Hard clustering: labels that minimise a Potts energy over the face graph, by alpha
// expansion (Boykov, Veksler and Zabih, "Fast approximate energy minimization via graph
// cuts", PAMI 2001) with CGAL's schedule.
#pragma once

#include <cstddef>
#include <vector>

#include "segment/face_graph.h"
#include "segment/stage_progress.h"

namespace sdf::segment {

// E(labels) = sum over faces of costs[f * k + labels[f]] + sum over pairs whose faces differ
// of weights[pair]. Summed per fixed block, so the same for any thread count.
double potts_energy(const FaceGraph& graph, const double* weights, const double* costs,
                    std::size_t k, const int* labels, std::size_t n, unsigned threads);

// How the moves are made.
struct ExpansionRules {
  // Of equally good moves, make the largest (every face the cut leaves undecided moves to
  // alpha, as CGAL's max-flow decides) or the smallest. Costs and weights are clamped (at
  // -log 5e-6), so ties are common.
  bool ties_move = true;
  // Stop after the first move (alpha = 0). CGAL 5.5's max-flow keeps its total flow from one
  // move to the next (its clear() leaves it), so every move after the first looks worse than
  // the one before and is rejected: CGAL's labels are the first expansion of the starting
  // ones. Its energy stays far above a converged expansion's (386718 against 140785 on the
  // 75k-face bunny, k = 5, lambda = 0.26).
  bool first_move_only = true;
  // Start a move to a label from the flow its previous move found (dynamic graph cuts): the
  // same cuts up to exact ties (max_flow.h), and later sweeps, which change few labels, find
  // little flow left to push. False solves every move from scratch (to compare the two).
  bool resume_flows = true;
};

// Improves `labels` (in [0, k)) in place: sweeps alpha = 0..k-1, each time moving to alpha
// the set of faces that lowers the energy most (a minimum cut), keeping a move only if it
// lowers the energy found so far by more than a relative 1e-10 (the first move is always
// kept); stops after a sweep that keeps none. Returns the final energy, which is never above
// that of the starting labels. `progress`, when given, is told at each move, and polled
// inside each cut, the share of the moves made, mapped to [from, to] (m / (m + k) after m
// moves: the number of sweeps is not known); if it throws, `labels` hold the last move kept.
double alpha_expansion(const FaceGraph& graph, const double* weights, const double* costs,
                       std::size_t k, const ExpansionRules& rules, int* labels, std::size_t n,
                       unsigned threads, StageProgress* progress = nullptr, double from = 0.0,
                       double to = 1.0);

}  // namespace sdf::segment
