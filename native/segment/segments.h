// SPDX-License-Identifier: GPL-3.0-or-later
// Segments: the connected pieces of each cluster, numbered by thickness.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "segment/face_graph.h"

namespace sdf::segment {

// Writes to `segments` a segment per face: faces joined through edges whose faces share a
// cluster form one segment. Segments are numbered by ascending mean of `values` over their
// faces (ties in the order first met, faces in index order); returns their number. Faces of
// separate parts never share a segment.
std::size_t number_segments(const FaceGraph& graph, const int* clusters, const double* values,
                            std::size_t n, int* segments);

// Per segment: its area, and the plain mean of `values` over its faces.
struct SegmentStats {
  std::vector<double> area, mean_value;
};
SegmentStats segment_stats(const double* areas, const double* values, const int* segments,
                           std::size_t n, std::size_t segment_count);

// Per face, its area.
std::vector<double> face_areas(const double* vertices, const std::int64_t* triangles, std::size_t n,
                               unsigned threads);

}  // namespace sdf::segment
