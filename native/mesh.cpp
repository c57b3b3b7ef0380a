// SPDX-License-Identifier: GPL-3.0-or-later
#include "mesh.h"

#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>

namespace sdf {

Mesh make_mesh(const double* vertices, std::size_t vertex_count, const std::int64_t* triangles,
               std::size_t triangle_count) {
  if (vertex_count == 0) throw std::invalid_argument("the mesh has no vertices");
  if (triangle_count == 0) throw std::invalid_argument("the mesh has no triangles");
  if (vertex_count > std::numeric_limits<std::uint32_t>::max())
    throw std::invalid_argument("more than 2^32 - 1 vertices are not supported");

  glm::dvec3 lo(std::numeric_limits<double>::infinity());
  glm::dvec3 hi(-std::numeric_limits<double>::infinity());
  for (std::size_t i = 0; i < vertex_count; ++i) {
    const glm::dvec3 p(vertices[3 * i], vertices[3 * i + 1], vertices[3 * i + 2]);
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
      throw std::invalid_argument("vertex " + std::to_string(i) +
                                  " has a coordinate that is not finite");
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }

  Mesh mesh;
  mesh.center = 0.5 * (lo + hi);
  const glm::dvec3 size = hi - lo;
  mesh.max_extent = std::max(size.x, std::max(size.y, size.z));
  // The engines compute in 32-bit floats on coordinates centred on the box: past ~1e30 the
  // sums and differences of a centroid or an edge leave the float range (found by fuzzing).
  if (!(mesh.max_extent <= 1e30))
  {
    char extent[32];
    std::snprintf(extent, sizeof extent, "%.3g", mesh.max_extent);
    throw std::invalid_argument(std::string("the mesh spans ") + extent +
                                " units on an axis, more than the 1e30 that 32-bit floats "
                                "leave room for; scale it down");
  }
  mesh.vertices.resize(vertex_count);
  for (std::size_t i = 0; i < vertex_count; ++i) {
    const glm::dvec3 p(vertices[3 * i], vertices[3 * i + 1], vertices[3 * i + 2]);
    mesh.vertices[i] = glm::vec3(p - mesh.center);
  }
  mesh.triangles.resize(triangle_count);
  for (std::size_t f = 0; f < triangle_count; ++f) {
    for (int k = 0; k < 3; ++k) {
      const std::int64_t v = triangles[3 * f + k];
      if (v < 0 || static_cast<std::uint64_t>(v) >= vertex_count)
        throw std::invalid_argument("triangle " + std::to_string(f) + " uses vertex index " +
                                    std::to_string(v) + ", outside [0, " +
                                    std::to_string(vertex_count) + ")");
      mesh.triangles[f][k] = static_cast<std::uint32_t>(v);
    }
  }
  return mesh;
}

glm::vec3 face_area_normal(const Mesh& mesh, std::size_t face) {
  const glm::uvec3 t = mesh.triangles[face];
  const glm::vec3 v0 = mesh.vertices[t.x];
  return glm::cross(mesh.vertices[t.y] - v0, mesh.vertices[t.z] - v0);
}

float minimum_closeness(const Mesh& mesh) { return static_cast<float>(2e-5 * mesh.max_extent); }

}  // namespace sdf
