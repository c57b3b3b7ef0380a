// SPDX-License-Identifier: GPL-3.0-or-later
// Soft clustering of the SDF: a one-dimensional Gaussian mixture fitted by expectation
// maximisation, started from k-means (CGAL's Expectation_maximization with k-means
// initialisation, one run).
#pragma once

#include <cstddef>
#include <vector>

#include "segment/stage_progress.h"

namespace sdf::segment {

// log(alpha x + 1) / log(alpha + 1) of values in [0, 1]: spreads the thin end, where parts
// differ most. CGAL's segmentation uses alpha = 5.
void log_normalize(const double* values, std::size_t n, double alpha, double* out);

// Means of k clusters of `points`, ascending: k-means++ seeding from CGAL's random sequence
// (seed 1340818006, so the same centres as CGAL), then Lloyd iterations until no point
// changes cluster, at most `max_iterations`. A cluster left empty keeps its mean. Needs
// n >= k >= 1. Fewer than k means when the points hold fewer than k distinct values (seeding
// stops when every point sits on a centre). The result does not depend on `threads`.
// `check`, when given, is called after each iteration with the share of the most done.
std::vector<double> kmeans_centres(const double* points, std::size_t n, std::size_t k,
                                   std::size_t max_iterations, unsigned threads,
                                   const WorkCheck& check = nullptr);

struct Gaussian {
  double mean = 0.0, deviation = 0.0, weight = 0.0;  // weight: the mixing coefficient
};

// Fits a mixture of Gaussians to `points` by expectation maximisation, starting from
// `centres` (each with the RMS distance of the points closest to it and equal weights), at
// most `max_iterations` iterations, stopping when the log-likelihood gains less than
// `threshold` times its magnitude. Components sorted by mean. Densities are CGAL's:
// exp(-z^2 / 2) / deviation, without the 1/sqrt(2 pi) that cancels everywhere it is used.
// `check` as for kmeans_centres.
std::vector<Gaussian> fit_mixture(const double* points, std::size_t n,
                                  const std::vector<double>& centres, std::size_t max_iterations,
                                  double threshold, unsigned threads,
                                  const WorkCheck& check = nullptr);

// Per point and component (row-major n x k): the cost -log(max(p, 5e-6)) (at least machine
// epsilon) of the component's posterior probability p; and per point the component of
// largest weighted density (the starting labels). A point no component reaches (every
// density underflows) takes the component of nearest mean with probability 1.
// `check` as for kmeans_centres (called now and then, on this thread).
void cluster_costs(const double* points, std::size_t n, const std::vector<Gaussian>& mixture,
                   unsigned threads, double* costs, int* labels, const WorkCheck& check = nullptr);

}  // namespace sdf::segment
