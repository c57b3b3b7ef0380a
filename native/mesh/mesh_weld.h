// SPDX-License-Identifier: GPL-3.0-or-later
// Merging vertices at equal (or nearly equal) positions. Files split a vertex wherever its UV
// or normal changes (OBJ exporters, glTF always), so the triangles on the two sides of a seam
// share no vertex index; smoothing on the mesh must see through that, or the seam becomes a
// wall (paper 4.4: "duplicated vertices have to be merged into one").
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "mesh/mesh.h"
#include "util/stopwatch.h"
#include "util/uninitialized_vector.h"

namespace sdf {

struct Weld {
  // Per input vertex: its merged vertex, numbered 0, 1, 2, ... in order of first appearance
  // (so a mesh without duplicates maps every vertex to itself).
  std::vector<std::uint32_t> merged;
  std::uint32_t count = 0;  // number of merged vertices
  // Per merged vertex: its first input vertex (the kept one, which the others joined).
  UninitializedVector<std::uint32_t> first;
};

// Each vertex its own merged vertex (no merging), on `threads` workers.
Weld identity_weld(std::size_t count, unsigned threads);

// A vertex joins the first earlier kept vertex within `tolerance` (Euclidean distance, mesh
// units); otherwise it is kept. tolerance 0 merges exactly equal positions only (+0 and -0
// count as equal). Greedy in index order, so the result does not depend on threads; chains
// (a near b near c, a far from c) are cut where the distance to the kept vertex exceeds the
// tolerance. Linear expected time: a hash grid of cells 2 to 64 tolerances wide, 1 to 8
// cells per query. On `threads` threads (0: every core) but for the greedy pass over the
// vertices that have a neighbour within the tolerance; the same result for any count.
// With `timings`, appends the seconds of its stages ("weld: ...").
Weld weld_vertices(const glm::vec3* positions, std::size_t count, float tolerance,
                   unsigned threads = 1, StageTimings* timings = nullptr);

// Merging tolerance for a mesh: `relative` times its largest bounding-box side. The default,
// 1e-6, is about 16 float ulps at the box's edge: it merges what an exporter duplicated
// (bit-identical or rounded once through text) and nothing a modeller placed on purpose.
constexpr double kDefaultWeldTolerance = 1e-6;
float weld_tolerance(const Mesh& mesh, double relative = kDefaultWeldTolerance);

// The triangles rewritten with merged indices.
std::vector<glm::uvec3> welded_triangles(const Mesh& mesh, const Weld& weld);

// Compressed lists: the items of key k are items[offsets[k] .. offsets[k + 1]). Flat arrays,
// so that a kernel can walk them as they are; filled in parallel, never zeroed first.
struct Adjacency {
  UninitializedVector<std::uint32_t> offsets, items;
  std::size_t size() const { return offsets.empty() ? 0 : offsets.size() - 1; }
};

// Faces around each vertex, in increasing face order. A face whose corners merged into one
// vertex is listed once per distinct corner. On `threads` workers (0 = every core); the
// result does not depend on it.
Adjacency faces_of_vertices(const glm::uvec3* triangles, std::size_t count,
                            std::uint32_t vertex_count, unsigned threads = 1);

// Vertices that share an edge with each vertex (each once, increasing; never the vertex itself).
// On `threads` workers (0 = every core); the result does not depend on it.
Adjacency vertex_neighbours(const glm::uvec3* triangles, const Adjacency& faces_of_vertices,
                            unsigned threads = 1);

}  // namespace sdf
