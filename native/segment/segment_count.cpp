// SPDX-License-Identifier: GPL-3.0-or-later
#include "segment/segment_count.h"

#include <algorithm>
#include <stdexcept>
#include <tuple>
#include <utility>
#include <vector>

#include "util/stopwatch.h"

namespace sdf::segment {
namespace {

// The (clusters, smoothness) pairs in the order they are tried.
std::vector<std::pair<std::size_t, double>> schedule(const SegmentOptions& options) {
  const auto start = static_cast<long>(
      std::min(std::max(options.clusters, kMinSearchClusters), kMaxSearchClusters));
  std::vector<std::size_t> clusters{static_cast<std::size_t>(start)};
  for (long d = 1; d <= static_cast<long>(kMaxSearchClusters); ++d) {
    for (const long k : {start - d, start + d}) {
      if (k >= static_cast<long>(kMinSearchClusters) && k <= static_cast<long>(kMaxSearchClusters))
        clusters.push_back(static_cast<std::size_t>(k));
    }
  }
  std::vector<std::pair<std::size_t, double>> out;
  for (const double factor : kSmoothnessFactors) {
    for (const std::size_t k : clusters) out.emplace_back(k, options.smoothness * factor);
  }
  return out;
}

std::size_t distance(std::size_t a, std::size_t b) { return a > b ? a - b : b - a; }

}  // namespace

Segmentation segment_to_count(const double* vertices, std::size_t vertex_count,
                              const std::int64_t* triangles, std::size_t face_count,
                              const double* values, const SegmentOptions& options,
                              std::size_t segments, const ProgressFn& progress) {
  if (segments < 1) throw std::invalid_argument("segments must be at least 1");
  const auto tries = schedule(options);
  Stopwatch watch;
  Segmentation best;
  bool have = false;
  for (std::size_t i = 0; i < tries.size(); ++i) {
    SegmentOptions run = options;
    std::tie(run.clusters, run.smoothness) = tries[i];
    // Each run reports its share of the longest search (an early end jumps to the end);
    // one run's end is the next one's start to the bit, so the fractions never step back.
    const double from = double(i) / double(tries.size());
    const double to = double(i + 1) / double(tries.size());
    const ProgressFn told =
        progress
            ? ProgressFn([&](double f) { return progress(f >= 1.0 ? to : from + (to - from) * f); })
            : ProgressFn();
    Segmentation s = segment_mesh(vertices, vertex_count, triangles, face_count, values, run, told);
    if (!have || distance(s.segment_count, segments) < distance(best.segment_count, segments)) {
      best = std::move(s);
      have = true;
    }
    if (best.segment_count == segments) break;
  }
  add_time(&best.timings, "count_search", watch.lap());
  if (progress && !progress(1.0)) throw Cancelled();
  return best;
}

}  // namespace sdf::segment
