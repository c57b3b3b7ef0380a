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
  // The face graph and the values (filtered: the costliest step) serve every try. Progress:
  // a share for them, then each try its share of the longest search (an early end jumps to
  // the end); one share's end is the next one's start to the bit, so it never steps back.
  const double prepared_share = options.filter ? 0.5 : 0.05;
  auto share = [&](double from, double to) -> ProgressFn {
    if (!progress) return nullptr;
    return [&progress, from, to](double f) {
      return progress(f >= 1.0 ? to : from + (to - from) * f);
    };
  };
  const SegmentInput input = prepare_segment_input(triangles, face_count, vertex_count, values,
                                                   options, share(0.0, prepared_share));
  Segmentation best;
  bool found_any = false;
  for (std::size_t i = 0; i < tries.size(); ++i) {
    SegmentOptions run = options;
    std::tie(run.clusters, run.smoothness) = tries[i];
    const double span = 1.0 - prepared_share;
    const double from = prepared_share + span * double(i) / double(tries.size());
    const double to = prepared_share + span * double(i + 1) / double(tries.size());
    Segmentation s = segment_prepared(input, vertices, vertex_count, triangles, face_count, run,
                                      share(from, to));
    if (!found_any ||
        distance(s.segment_count, segments) < distance(best.segment_count, segments)) {
      best = std::move(s);
      found_any = true;
    }
    if (best.segment_count == segments) break;
  }
  add_time(&best.timings, "count_search", watch.lap());
  if (progress && !progress(1.0)) throw Cancelled();
  return best;
}

}  // namespace sdf::segment
