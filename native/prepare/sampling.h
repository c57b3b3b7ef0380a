// SPDX-License-Identifier: GPL-3.0-or-later
// Stage 1: the points rays start from, with the cone axis of each (its inward direction).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "mesh/mesh.h"
#include "ray/sdf_face_point.h"
#include "util/uninitialized_vector.h"

namespace sdf {

enum class PointKind { Faces, Vertices };

// Uninitialised vectors: sample_points() writes every element from its parallel loop, which
// then also takes the first-touch page faults (measured: most of this stage's time on a cold
// run, on one thread, when the arrays were zeroed first).
struct SamplePoints {
  UninitializedVector<glm::vec3> origins;  // in the mesh's centred units
  UninitializedVector<glm::vec3> axes;     // unit inward direction; zero where it is undefined
  // Unit, perpendicular to the axis: where a point's ray set starts in azimuth. Taken from the
  // mesh (a face's first edge; for a vertex, the edge to the next corner of the first face that
  // uses it) so that rotating the mesh rotates the rays with it; fallback_tangent() where the
  // mesh gives none.
  UninitializedVector<glm::vec3> tangents;
  UninitializedVector<std::int32_t> own_face;  // face a ray must not hit (its own); -1 for vertices
  std::size_t size() const { return origins.size(); }
};

// Faces: the centroid, axis = minus the face normal; zero-area faces get a zero axis.
// Vertices: the vertex, axis = minus the area-weighted mean of the normals of the faces around
// it; a vertex with no face, or whose normals cancel, gets a zero axis.
// Points with a zero axis cast no ray and are filled from their neighbours later.
// `threads` as in Options (0 = every core); the result does not depend on it.
SamplePoints sample_points(const Mesh& mesh, PointKind kind, unsigned threads = 0);

// One face's point as sample_points() makes it (both from kernels/ray/sdf_face_point.h): the
// centroid, and the unit inward axis (zero for a zero-area face). For callers that need no tangent
// and no stored arrays (projected smoothing recomputes them on the fly each iteration). Inline:
// called once per face, a call cost as much as the arithmetic (measured at 1.5M faces).
inline void face_point(const Mesh& mesh, std::size_t face, glm::vec3* origin, glm::vec3* axis) {
  const glm::uvec3 t = mesh.triangles[face];
  kern::sdf_face_origin_axis(mesh.vertices[t.x], mesh.vertices[t.y], mesh.vertices[t.z], origin,
                             axis);
}

// Point indices in Morton (Z-curve) order of their origins. Neighbouring points cast similar
// rays through the same nodes, so working through them in space order keeps the tree in
// cache (measured 20-30% faster than file order on the bunny) and keeps GPU work items that
// run together coherent.
// Ties in the code keep index order; the order does not depend on `threads`.
std::vector<std::uint32_t> spatial_order(const SamplePoints& points, unsigned threads = 0);

}  // namespace sdf
