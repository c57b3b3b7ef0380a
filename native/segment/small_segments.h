// SPDX-License-Identifier: GPL-3.0-or-later
// A minimum part size: segments too small to be parts of their own joined to a neighbour.
#pragma once

#include <cstddef>
#include <cstdint>

#include "segment/face_graph.h"

namespace sdf::segment {

// Joins every segment whose area is below `min_share` times the mesh's total area to the
// adjacent segment it shares the longest boundary with (the summed length of the edges
// between them), until no segment is below that area or none of those below has a
// neighbour. The smallest segment goes first; ties, in area or in boundary length, go to the
// lowest index. Segments meet only through edges of the face graph, so separate solids (and
// parts touching at a vertex) never join: a separate solid below the share stays a segment
// of its own.
//
// segments: per face, in [0, count) on entry; renumbered by ascending mean of `values` over
// their faces (ties: the lowest index on entry), so with nothing joined they are unchanged.
// areas: per face. Returns the new number of segments.
std::size_t join_small_segments(const FaceGraph& graph, const double* vertices,
                                const std::int64_t* triangles, const double* areas,
                                const double* values, std::size_t n, double min_share,
                                int* segments, std::size_t count);

}  // namespace sdf::segment
