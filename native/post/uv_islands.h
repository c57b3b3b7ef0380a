// SPDX-License-Identifier: GPL-3.0-or-later
// UV islands for texture-space smoothing (smoothing_texture.h, step 1): faces that share a
// corner (same merged vertex, same UV) belong to one island.
//
// Linear time on the CPU threads: corners of one vertex with equal UVs join their faces in a
// union-find whose roots are the smallest faces (so the islands, and their numbering, do not
// depend on the threads).
//
// Merging vertices (mesh_weld.h) is the costly part, and it can only change the islands
// where two distinct vertices within merging distance share a UV, or a face has two such
// corners: files split a vertex at a normal seam with one UV (glTF), not OBJ or Blender,
// which keep one vertex per position. label_uv_islands looks for those cases first (a sort of
// the distinct (vertex, UV) pairs) and welds only when it finds one.
#pragma once

#include <cstdint>
#include <vector>

#include "mesh/mesh.h"

namespace sdf {

struct UvIslands {
  std::vector<std::int32_t> face_island;  // per face: 0, 1, 2, ... by each island's first face
  std::int32_t count = 0;
  // The key the corners are grouped by: per vertex, its merged vertex (when vertices were
  // merged), else empty (the vertex index: no merging was asked for, or needed).
  std::vector<std::uint32_t> merged;
  std::uint32_t merged_count = 0;  // keys: merged vertices, or vertices
  // What they were found for (smooth_texture checks islands given to it against these).
  std::size_t vertex_count = 0;
  double weld_tolerance = -1.0;
  bool need_merged = false;
};

// weld_tolerance: relative to the largest bounding-box side, as for weld_vertices; < 0: no
// merging. need_merged: merge vertices even where the islands do not need it (vertex values
// are averaged over merged vertices). uvs: 6 floats a face, finite.
UvIslands label_uv_islands(const Mesh& mesh, const float* uvs, double weld_tolerance,
                           bool need_merged, unsigned threads);

// The islands only: one id per face, 0, 1, 2, ... in order of each island's first face.
std::vector<std::int32_t> uv_islands(const Mesh& mesh, const float* uvs, double weld_tolerance,
                                     unsigned threads = 0);

}  // namespace sdf
