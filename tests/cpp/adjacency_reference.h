// SPDX-License-Identifier: GPL-3.0-or-later
// The serial adjacency lists that native/mesh/mesh_weld.cpp's parallel ones replaced (a counting
// sort of the corners by vertex; per vertex, its faces' other corners sorted and deduplicated),
// kept as the reference the parallel ones must match exactly.
#pragma once

#include <algorithm>
#include <vector>

#include "mesh/mesh_weld.h"

namespace sdf::test_reference {

inline Adjacency reference_faces_of_vertices(const std::vector<glm::uvec3>& triangles,
                                             std::uint32_t vertex_count) {
  Adjacency a;
  a.offsets.assign(static_cast<std::size_t>(vertex_count) + 1, 0);
  auto distinct = [](const glm::uvec3& t, int k) {
    return (k == 0) || (k == 1 && t.y != t.x) || (k == 2 && t.z != t.x && t.z != t.y);
  };
  for (const glm::uvec3& t : triangles)
    for (int k = 0; k < 3; ++k)
      if (distinct(t, k)) ++a.offsets[t[k] + 1];
  for (std::size_t v = 0; v < vertex_count; ++v) a.offsets[v + 1] += a.offsets[v];
  a.items.resize(a.offsets.back());
  std::vector<std::uint32_t> cursor(a.offsets.begin(), a.offsets.end() - 1);
  for (std::size_t f = 0; f < triangles.size(); ++f)
    for (int k = 0; k < 3; ++k)
      if (distinct(triangles[f], k))
        a.items[cursor[triangles[f][k]]++] = static_cast<std::uint32_t>(f);
  return a;
}

inline Adjacency reference_vertex_neighbours(const std::vector<glm::uvec3>& triangles,
                                             const Adjacency& faces_of_vertices) {
  const std::size_t n = faces_of_vertices.size();
  Adjacency a;
  a.offsets.assign(n + 1, 0);
  std::vector<std::uint32_t> items;
  for (std::size_t v = 0; v < n; ++v) {
    const std::size_t begin = items.size();
    for (std::uint32_t i = faces_of_vertices.offsets[v]; i < faces_of_vertices.offsets[v + 1];
         ++i) {
      const glm::uvec3 t = triangles[faces_of_vertices.items[i]];
      for (int k = 0; k < 3; ++k)
        if (t[k] != v) items.push_back(t[k]);
    }
    std::sort(items.begin() + static_cast<std::ptrdiff_t>(begin), items.end());
    items.erase(std::unique(items.begin() + static_cast<std::ptrdiff_t>(begin), items.end()),
                items.end());
    a.offsets[v + 1] = static_cast<std::uint32_t>(items.size());
  }
  a.items.assign(items.begin(), items.end());
  return a;
}

}  // namespace sdf::test_reference
