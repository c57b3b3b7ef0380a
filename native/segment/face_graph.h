// SPDX-License-Identifier: GPL-3.0-or-later
// Faces that share an edge: the graph segmentation smooths and cuts over.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "segment/stage_progress.h"

namespace sdf::segment {

// Two faces meeting at an edge. In `first`, the shared edge runs from corner `first_corner`
// to the next corner (counter-clockwise order of its triangle); `second_corner` is the corner
// of `second` where its copy of the edge starts. The dihedral angle reads them.
struct FacePair {
  std::uint32_t first, second;
  std::uint8_t first_corner, second_corner;
};

struct FaceGraph {
  std::vector<FacePair> pairs;            // each pair once, first < second
  std::vector<std::uint32_t> offsets;     // face f's neighbours: neighbours[offsets[f]..[f+1])
  std::vector<std::uint32_t> neighbours;  // one entry per pair and direction
};

// Builds the graph of triangles (face_count, 3), 0-based indices below vertex_count.
// An edge with two faces gives one pair. An edge with more (non-manifold) joins every two of
// them when there are at most eight, else each face to the next around the list, so a fan of
// many faces on one edge costs linear time. Edges of a degenerate face that repeat a vertex
// join nothing; open edges join nothing. Faces sharing no edge (separate parts, parts joined
// at a vertex) are never neighbours. The result does not depend on `threads`. `check` is
// called between the steps and may throw to stop.
FaceGraph build_face_graph(const std::int64_t* triangles, std::size_t face_count,
                           std::size_t vertex_count, unsigned threads,
                           const WorkCheck& check = nullptr);

}  // namespace sdf::segment
