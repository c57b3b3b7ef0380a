// SPDX-License-Identifier: GPL-3.0-or-later
#include "segment/soft_clustering.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "segment/cgal_random.h"
#include "util/parallel.h"

namespace sdf::segment {
namespace {

// Sums are taken per fixed block of points, then the blocks in order: the same rounding for
// any thread count.
constexpr std::size_t kBlock = 1 << 14;

// body(block, begin, end) over the blocks of [0, n), in parallel.
template <class Body>
void for_blocks(std::size_t n, unsigned threads, Body&& body) {
  const std::size_t blocks = (n + kBlock - 1) / kBlock;
  parallel_for(blocks, 1, threads, [&](std::size_t b0, std::size_t b1) {
    for (std::size_t b = b0; b < b1; ++b) body(b, b * kBlock, std::min(n, (b + 1) * kBlock));
  });
}

std::size_t nearest(const std::vector<double>& means, double x) {
  std::size_t best = 0;
  double best_distance = std::abs(means[0] - x);
  for (std::size_t c = 1; c < means.size(); ++c) {
    const double d = std::abs(means[c] - x);
    if (d < best_distance) {
      best = c;
      best_distance = d;
    }
  }
  return best;
}

// k-means++: the first centre uniform, each next one with probability proportional to the
// squared distance to the nearest centre so far (CGAL's draws, in CGAL's order).
std::vector<double> plus_plus_seeds(const double* points, std::size_t n, std::size_t k) {
  CgalRandom random(1340818006u);
  std::vector<double> centres{points[random.uniform_index(n)]};
  std::vector<double> nearest_sq(n, std::numeric_limits<double>::max()), cumulative(n);
  while (centres.size() < k) {
    double total = 0.0;
    for (std::size_t j = 0; j < n; ++j) {
      const double d = (centres.back() - points[j]) * (centres.back() - points[j]);
      nearest_sq[j] = std::min(nearest_sq[j], d);
      total += nearest_sq[j];
      cumulative[j] = total;
    }
    if (!(total > 0.0)) break;  // every point sits on a centre: fewer distinct values than k
    const double pick = random.uniform_real(0.0, total);
    const std::size_t index =
        std::upper_bound(cumulative.begin(), cumulative.end(), pick) - cumulative.begin();
    centres.push_back(points[std::min(index, n - 1)]);  // n - 1: every point already a centre
  }
  return centres;
}

}  // namespace

void log_normalize(const double* values, std::size_t n, double alpha, double* out) {
  const double scale = std::log(alpha + 1.0);
  for (std::size_t f = 0; f < n; ++f) out[f] = std::log(values[f] * alpha + 1.0) / scale;
}

std::vector<double> kmeans_centres(const double* points, std::size_t n, std::size_t k,
                                   std::size_t max_iterations, unsigned threads,
                                   const WorkCheck& check) {
  std::vector<double> centres = plus_plus_seeds(points, n, k);
  k = centres.size();
  std::vector<std::uint32_t> assignment(n, std::numeric_limits<std::uint32_t>::max());
  const std::size_t blocks = (n + kBlock - 1) / kBlock;
  std::vector<double> sums(blocks * k), counts(blocks * k);
  std::vector<char> changed(blocks);
  for (std::size_t iteration = 0; iteration < max_iterations; ++iteration) {
    for_blocks(n, threads, [&](std::size_t b, std::size_t begin, std::size_t end) {
      double* sum = &sums[b * k];
      double* count = &counts[b * k];
      std::fill(sum, sum + k, 0.0);
      std::fill(count, count + k, 0.0);
      changed[b] = 0;
      for (std::size_t j = begin; j < end; ++j) {
        const auto c = static_cast<std::uint32_t>(nearest(centres, points[j]));
        changed[b] |= c != assignment[j];
        assignment[j] = c;
        sum[c] += points[j];
        count[c] += 1.0;
      }
    });
    for (std::size_t c = 0; c < k; ++c) {
      double sum = 0.0, count = 0.0;
      for (std::size_t b = 0; b < blocks; ++b) {
        sum += sums[b * k + c];
        count += counts[b * k + c];
      }
      if (count > 0) centres[c] = sum / count;
    }
    if (std::find(changed.begin(), changed.end(), 1) == changed.end()) break;
    if (check) check(static_cast<double>(iteration + 1) / static_cast<double>(max_iterations));
  }
  std::sort(centres.begin(), centres.end());
  return centres;
}

namespace {

double density(const Gaussian& g, double x) {
  if (g.deviation == 0.0) return x == g.mean ? 1.0 : 0.0;
  const double z = (x - g.mean) / g.deviation;
  return std::exp(-0.5 * z * z) / g.deviation;
}

std::vector<double> means_of(const std::vector<Gaussian>& mixture) {
  std::vector<double> means;
  for (const Gaussian& g : mixture) means.push_back(g.mean);
  return means;
}

// Posterior probabilities of each component per point (row-major n x k), and the
// log-likelihood. A point every density misses belongs to the nearest mean.
double expectation(const double* points, std::size_t n, const std::vector<Gaussian>& mixture,
                   unsigned threads, std::vector<double>& posterior) {
  const std::size_t k = mixture.size();
  const std::vector<double> means = means_of(mixture);
  std::vector<double> block_sums((n + kBlock - 1) / kBlock);
  for_blocks(n, threads, [&](std::size_t b, std::size_t begin, std::size_t end) {
    double sum = 0.0;
    for (std::size_t j = begin; j < end; ++j) {
      double* p = &posterior[j * k];
      double total = 0.0;
      for (std::size_t c = 0; c < k; ++c)
        total += p[c] = density(mixture[c], points[j]) * mixture[c].weight;
      if (total > 0.0 && std::isfinite(total)) {
        for (std::size_t c = 0; c < k; ++c) p[c] /= total;
        sum += std::log(total);
      } else {
        std::fill(p, p + k, 0.0);
        p[nearest(means, points[j])] = 1.0;
        sum += std::log(std::numeric_limits<double>::min());
      }
    }
    block_sums[b] = sum;
  });
  double likelihood = 0.0;
  for (double s : block_sums) likelihood += s;
  return likelihood;
}

// New means, deviations and weights from the posteriors. A component no point belongs to
// keeps its mean, with no spread and no weight.
void maximization(const double* points, std::size_t n, const std::vector<double>& posterior,
                  unsigned threads, std::vector<Gaussian>& mixture) {
  const std::size_t k = mixture.size(), blocks = (n + kBlock - 1) / kBlock;
  std::vector<double> mass(blocks * k), first(blocks * k), second(blocks * k);
  // Point by point, all components at once: one pass over the posteriors.
  for_blocks(n, threads, [&](std::size_t b, std::size_t begin, std::size_t end) {
    double* m = &mass[b * k];
    double* s = &first[b * k];
    for (std::size_t j = begin; j < end; ++j)
      for (std::size_t c = 0; c < k; ++c) {
        m[c] += posterior[j * k + c];
        s[c] += posterior[j * k + c] * points[j];
      }
  });
  std::vector<double> total(k, 0.0), means(k, 0.0);
  for (std::size_t c = 0; c < k; ++c) {
    double s = 0.0;
    for (std::size_t b = 0; b < blocks; ++b) {
      total[c] += mass[b * k + c];
      s += first[b * k + c];
    }
    means[c] = total[c] > 0.0 ? s / total[c] : mixture[c].mean;
  }
  for_blocks(n, threads, [&](std::size_t b, std::size_t begin, std::size_t end) {
    double* s = &second[b * k];
    for (std::size_t j = begin; j < end; ++j)
      for (std::size_t c = 0; c < k; ++c)
        s[c] += posterior[j * k + c] * (points[j] - means[c]) * (points[j] - means[c]);
  });
  for (std::size_t c = 0; c < k; ++c) {
    double s = 0.0;
    for (std::size_t b = 0; b < blocks; ++b) s += second[b * k + c];
    mixture[c].mean = means[c];
    mixture[c].deviation = total[c] > 0.0 ? std::sqrt(s / total[c]) : 0.0;
    mixture[c].weight = total[c] / static_cast<double>(n);
  }
}

// Equal weights; each component's deviation the RMS distance of the points nearest to it.
std::vector<Gaussian> initial_mixture(const double* points, std::size_t n,
                                      const std::vector<double>& centres) {
  std::vector<Gaussian> mixture(centres.size());
  std::vector<std::size_t> members(centres.size(), 0);
  for (std::size_t c = 0; c < centres.size(); ++c) {
    mixture[c].mean = centres[c];
    mixture[c].weight = 1.0 / static_cast<double>(centres.size());
  }
  for (std::size_t j = 0; j < n; ++j) {
    const std::size_t c = nearest(centres, points[j]);
    const double d = std::abs(centres[c] - points[j]);
    ++members[c];
    mixture[c].deviation += d * d;
  }
  for (std::size_t c = 0; c < centres.size(); ++c)
    if (members[c])
      mixture[c].deviation = std::sqrt(mixture[c].deviation / static_cast<double>(members[c]));
  return mixture;
}

}  // namespace

std::vector<Gaussian> fit_mixture(const double* points, std::size_t n,
                                  const std::vector<double>& centres, std::size_t max_iterations,
                                  double threshold, unsigned threads, const WorkCheck& check) {
  std::vector<Gaussian> mixture = initial_mixture(points, n, centres);
  std::vector<double> posterior(n * mixture.size());
  double likelihood = -std::numeric_limits<double>::max();
  for (std::size_t iteration = 0; iteration < max_iterations; ++iteration) {
    if (iteration == 0) {
      expectation(points, n, mixture, threads, posterior);
      if (check) check(0.0);
    }
    maximization(points, n, posterior, threads, mixture);
    const double previous = likelihood;
    likelihood = expectation(points, n, mixture, threads, posterior);
    if (likelihood - previous < threshold * std::abs(likelihood)) break;
    if (check) check(static_cast<double>(iteration + 1) / static_cast<double>(max_iterations));
  }
  std::sort(mixture.begin(), mixture.end(),
            [](const Gaussian& a, const Gaussian& b) { return a.mean < b.mean; });
  return mixture;
}

void cluster_costs(const double* points, std::size_t n, const std::vector<Gaussian>& mixture,
                   unsigned threads, double* costs, int* labels, const WorkCheck& check) {
  const std::size_t k = mixture.size();
  const std::vector<double> means = means_of(mixture);
  parallel_for(
      n, 4096, threads,
      [&](std::size_t begin, std::size_t end) {
        std::vector<double> p(k);
        for (std::size_t j = begin; j < end; ++j) {
          double total = 0.0, best = 0.0;
          int label = -1;
          for (std::size_t c = 0; c < k; ++c) {
            p[c] = density(mixture[c], points[j]) * mixture[c].weight;
            total += p[c];
            if (best < p[c]) {
              best = p[c];
              label = static_cast<int>(c);
            }
          }
          if (!(total > 0.0 && std::isfinite(total))) {
            label = static_cast<int>(nearest(means, points[j]));
            std::fill(p.begin(), p.end(), 0.0);
            p[label] = total = 1.0;
          }
          labels[j] = label;
          for (std::size_t c = 0; c < k; ++c) {
            const double cost = -std::log(std::max(p[c] / total, 5e-6));
            costs[j * k + c] = std::max(cost, std::numeric_limits<double>::epsilon());
          }
        }
      },
      as_progress(check));
}

}  // namespace sdf::segment
