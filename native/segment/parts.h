// SPDX-License-Identifier: GPL-3.0-or-later
// What rigging reads from a segmentation: a label and soft weights per vertex, and where the
// segments meet (boundary loops with their centroid and length).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "segment/face_graph.h"
#include "segment/stage_progress.h"

namespace sdf::segment {

// Per vertex, the segment with the largest area among the faces around it (the smaller
// segment on a tie); -1 for a vertex no face uses.
// areas: per face (any positive multiple of the area will do).
std::vector<int> vertex_labels(std::size_t vertex_count, const std::int64_t* triangles,
                               const double* areas, const int* segments, std::size_t n);

// Soft weights, sparse: vertex v's entries are [offsets[v], offsets[v+1]) of segment and
// weight, weights summing to 1. A vertex's weight for a segment is the area of that
// segment's faces within `rings` rings of faces around it (ring 0: the faces at the vertex),
// ring r counting (rings + 1 - r) / (rings + 1): 1 deep inside a segment, falling off
// linearly over `rings` rings on each side of a boundary. A vertex no face uses has none.
struct VertexWeights {
  std::vector<std::uint32_t> offsets;
  std::vector<std::int32_t> segment;
  std::vector<float> weight;
};
// `check` is called between the steps (on this thread) and may throw to stop.
VertexWeights vertex_weights(std::size_t vertex_count, const std::int64_t* triangles,
                             const double* areas, const int* segments, std::size_t n,
                             std::size_t rings, unsigned threads, const WorkCheck& check = nullptr);

// A boundary loop: a connected run of edges between faces of segments a < b.
struct Boundary {
  int a, b;
  double centroid[3];  // mean of the edges' midpoints, weighted by length
  double length;
  std::size_t edges;
};

// Every loop between two segments, sorted by (a, b) then by first edge met in pair order.
// Edges join into one loop where they share a vertex.
std::vector<Boundary> boundaries(const FaceGraph& graph, const double* vertices,
                                 std::size_t vertex_count, const std::int64_t* triangles,
                                 const int* segments);

}  // namespace sdf::segment
