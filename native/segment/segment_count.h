// SPDX-License-Identifier: GPL-3.0-or-later
// Segmentation to a number of segments: the user says how many parts they want (the legs,
// the arms, the head) rather than how many thickness levels. The clusters and smoothness
// that give it are searched for, since the segment count follows neither monotonically.
#pragma once

#include <cstddef>
#include <cstdint>

#include "segment/segmentation.h"

namespace sdf::segment {

// The smoothness factors tried, in order, after options.smoothness itself (x 1): lambda
// 0.26 (CGAL's default) becomes 0.104 and 0.52. Measured on the Princeton Segmentation
// Benchmark subset: the three together reach the count asked for more often than clusters
// alone, and cost at most three times the search over clusters.
inline constexpr double kSmoothnessFactors[] = {1.0, 0.4, 2.0};
inline constexpr std::size_t kMinSearchClusters = 2, kMaxSearchClusters = 9;

// segment_mesh with the clusters in [2, 9] and the smoothness among options.smoothness x
// kSmoothnessFactors whose segment count is nearest `segments`: at each smoothness in
// order, the clusters by distance from options.clusters (nearer first, the smaller of two
// equally near); the first segmentation with exactly `segments` ends the search, else the
// nearest count wins, an earlier one on a tie. Every run uses the other options as given
// (the minimum part size too). Segmentation::timings are the chosen run's, with
// "count_search" (seconds of all the runs) added. Throws std::invalid_argument for
// segments < 1, and what segment_mesh throws.
Segmentation segment_to_count(const double* vertices, std::size_t vertex_count,
                              const std::int64_t* triangles, std::size_t face_count,
                              const double* values, const SegmentOptions& options,
                              std::size_t segments, const ProgressFn& progress = nullptr);

}  // namespace sdf::segment
