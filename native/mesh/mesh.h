// SPDX-License-Identifier: GPL-3.0-or-later
// The triangle mesh the engines work on: float vertices centred on their bounding box (so a
// mesh far from the origin keeps its float precision) and 32-bit triangle indices.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "util/prefetch.h"
#include "util/uninitialized_vector.h"

namespace sdf {

struct Mesh {
  UninitializedVector<glm::vec3> vertices;    // positions minus `center`
  UninitializedVector<glm::uvec3> triangles;  // counter-clockwise seen from outside
  glm::dvec3 center{0.0};   // bounding-box centre of the used vertices, input units
  double max_extent = 0.0;  // largest side of that box, in input units
};

// A mesh as the caller holds it: row-major vertices (vertex_count, 3) and 0-based triangles
// (triangle_count, 3), not owned.
struct MeshArrays {
  const double* vertices = nullptr;
  std::size_t vertex_count = 0;
  const std::int64_t* triangles = nullptr;
  std::size_t triangle_count = 0;
};

// Copies a mesh from row-major arrays: vertices (n, 3) and triangles (m, 3), 0-based.
// Throws std::invalid_argument naming the problem for an empty mesh, an index out of range, a
// coordinate that is not finite, a bounding box wider than 1e30 on an axis, or a vertex more
// than 1e30 from its centre. The box (center, max_extent) is of the vertices the triangles with
// area use (every triangle's where none has area): vertices no such triangle uses are allowed
// and take no part. Checks and copies on `threads` (0 = every core); the result, and which
// problem an error names (the first), do not depend on it.
Mesh make_mesh(const double* vertices, std::size_t vertex_count, const std::int64_t* triangles,
               std::size_t triangle_count, unsigned threads = 0);

inline Mesh make_mesh(const MeshArrays& mesh, unsigned threads = 0) {
  return make_mesh(mesh.vertices, mesh.vertex_count, mesh.triangles, mesh.triangle_count, threads);
}

// What the caller's checks report about a mesh's values, in one parallel pass (numpy's passes
// cost 6 ms on 1.2M faces on a 16-core host, most of the time outside compute()'s stages).
struct MeshValues {
  std::size_t not_finite = 0;                 // vertices with a NaN or infinite coordinate
  std::size_t first_not_finite = 0;           // the first of them (when not_finite > 0)
  std::int64_t min_index = 0, max_index = 0;  // over every corner (0 for no triangle)
};
MeshValues mesh_values(const double* vertices, std::size_t vertex_count,
                       const std::int64_t* triangles, std::size_t triangle_count,
                       unsigned threads = 0);

// Asks for a face's three corners ahead of use. The corners of consecutive faces lie anywhere
// in the vertex array (subdivided and remeshed models scatter them), and per-face loops whose
// arithmetic has divisions and square roots leave the core too little room to overlap those
// cache misses by itself: loops over faces call this some 16 faces ahead (measured 1.5x
// faster on 1.5M faces).
inline void prefetch_corners(const Mesh& mesh, std::size_t face) {
  if (face >= mesh.triangles.size()) return;
  const glm::uvec3 t = mesh.triangles[face];
  prefetch(&mesh.vertices[t.x]);
  prefetch(&mesh.vertices[t.y]);
  prefetch(&mesh.vertices[t.z]);
}

// How far ahead prefetch_corners looks (8 to 32 measured alike).
constexpr std::size_t kPrefetchFacesAhead = 16;

// Outward face normal scaled by twice the area (cross(v1 - v0, v2 - v0)). Inline: per-face
// loops over millions of faces call it (a call per face cost as much as its arithmetic).
inline glm::vec3 face_area_normal(const Mesh& mesh, std::size_t face) {
  const glm::uvec3 t = mesh.triangles[face];
  const glm::vec3 v0 = mesh.vertices[t.x];
  return glm::cross(mesh.vertices[t.y] - v0, mesh.vertices[t.z] - v0);
}

// The shortest ray hit kept, kNearCutoffShare of the largest bounding-box side (paper 4.2): it
// stops a ray from hitting the surface it starts on, and lets self-intersecting and
// non-manifold meshes work. In the engines' (centred) units, which equal input units.
constexpr double kNearCutoffShare = 2e-5;
float minimum_closeness(const Mesh& mesh);

// A copy of `mesh`, made on `threads` (0 = every core): one thread copies a million faces'
// 22 MB in several milliseconds, most of them first-touch page faults.
Mesh copy_mesh(const Mesh& mesh, unsigned threads = 0);

}  // namespace sdf
