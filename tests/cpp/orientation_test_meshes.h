// SPDX-License-Identifier: GPL-3.0-or-later
// Meshes the orientation tests share: tori (shuffled or in grid order) and a mesh of every
// awkward case orient(Auto) meets.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <random>
#include <utility>
#include <vector>

#include "test_meshes.h"

namespace sdf::test {

// A closed torus of rows x cols quads (2 rows cols triangles), wound outward, centred at
// `centre`. Vertices and faces are shuffled with `seed` (0: kept in grid order) so that face
// order and vertex order disagree, as in a subdivided mesh.
inline Arrays torus(int rows, int cols, double cx, unsigned seed) {
  Arrays a;
  const double R = 1.0, r = 0.35, pi = std::acos(-1.0);
  for (int i = 0; i < rows; ++i)
    for (int j = 0; j < cols; ++j) {
      const double u = 2 * pi * i / rows, v = 2 * pi * j / cols;
      a.vertices.insert(a.vertices.end(), {cx + (R + r * std::cos(v)) * std::cos(u),
                                           (R + r * std::cos(v)) * std::sin(u), r * std::sin(v)});
    }
  auto at = [&](int i, int j) { return std::int64_t{(i % rows) * cols + (j % cols)}; };
  for (int i = 0; i < rows; ++i)
    for (int j = 0; j < cols; ++j)
      a.triangles.insert(a.triangles.end(), {at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j),
                                             at(i + 1, j + 1), at(i, j + 1)});
  if (seed == 0) return a;
  std::mt19937 rng(seed);
  const std::size_t nv = a.vertices.size() / 3, nf = a.triangles.size() / 3;
  std::vector<std::int64_t> new_index(nv);
  std::iota(new_index.begin(), new_index.end(), 0);
  std::shuffle(new_index.begin(), new_index.end(), rng);
  std::vector<double> vertices(a.vertices.size());
  for (std::size_t v = 0; v < nv; ++v)
    for (int k = 0; k < 3; ++k) vertices[3 * new_index[v] + k] = a.vertices[3 * v + k];
  std::vector<std::size_t> face_order(nf);
  std::iota(face_order.begin(), face_order.end(), 0);
  std::shuffle(face_order.begin(), face_order.end(), rng);
  std::vector<std::int64_t> triangles;
  for (std::size_t f : face_order)
    for (int k = 0; k < 3; ++k) triangles.push_back(new_index[a.triangles[3 * f + k]]);
  a.vertices = vertices;
  a.triangles = triangles;
  return a;
}

inline void append(Arrays& into, const Arrays& part) {
  const std::int64_t base = static_cast<std::int64_t>(into.vertices.size() / 3);
  into.vertices.insert(into.vertices.end(), part.vertices.begin(), part.vertices.end());
  for (std::int64_t v : part.triangles) into.triangles.push_back(v + base);
}

inline void reverse_every(Arrays& a, std::size_t step, std::size_t offset = 0) {
  for (std::size_t f = offset; f < a.triangles.size() / 3; f += step)
    std::swap(a.triangles[3 * f + 1], a.triangles[3 * f + 2]);
}

// A Moebius strip of 24 quads along a twisted band around (0, y, 0): no winding agrees all
// round.
inline Arrays moebius_strip(double y) {
  Arrays strip;
  const int quads = 24;
  const double pi = std::acos(-1.0);
  for (int i = 0; i < quads; ++i) {
    const double u = 2 * pi * i / quads;
    for (double s : {-0.2, 0.2})
      strip.vertices.insert(strip.vertices.end(),
                            {(1 + s * std::cos(u / 2)) * std::cos(u),
                             (1 + s * std::cos(u / 2)) * std::sin(u) + y, s * std::sin(u / 2)});
  }
  for (int i = 0; i < quads; ++i) {
    const std::int64_t a0 = 2 * i, a1 = 2 * i + 1;
    const bool last = i == quads - 1;
    const std::int64_t b0 = last ? 1 : 2 * (i + 1), b1 = last ? 0 : 2 * (i + 1) + 1;
    strip.triangles.insert(strip.triangles.end(), {a0, b0, b1, a0, b1, a1});
  }
  return strip;
}

// A torus inside out, one with a seam of duplicated vertices (an unwelded UV seam: equal
// positions, other indices, so two patches in one part), degenerate faces, an edge shared by
// three faces, and a Moebius strip (no consistent winding: the first face reached decides).
inline Arrays awkward_mesh() {
  Arrays a = torus(60, 40, 0.0, 0);  // grid order: the indices below are its vertices
  Arrays inside_out = torus(30, 20, 3.0, 0);
  reverse_every(inside_out, 1);
  append(a, inside_out);
  Arrays seam = torus(40, 30, -3.0, 0);
  const std::int64_t base = static_cast<std::int64_t>(seam.vertices.size() / 3);
  for (int j = 0; j < 30; ++j)  // copies of row 0, used by the faces of the last row
    seam.vertices.insert(seam.vertices.end(), seam.vertices.begin() + 3 * j,
                         seam.vertices.begin() + 3 * j + 3);
  for (std::size_t f = 39 * 30 * 2; f < seam.triangles.size() / 3; ++f)
    for (int k = 0; k < 3; ++k)
      if (seam.triangles[3 * f + k] < 30) seam.triangles[3 * f + k] += base;
  reverse_every(seam, 2 * 30 * 3, 5);  // and some faces flipped on both sides of the seam
  append(a, seam);
  // Degenerate and non-manifold faces on the first torus: (a, a, b), (a, b, a), a third
  // face on an edge, and a face using its edge twice.
  a.triangles.insert(a.triangles.end(), {0, 0, 1, 2, 3, 2, 10, 11, 0, 11, 10, 5, 40, 41, 40});
  append(a, moebius_strip(6.0));
  return a;
}

}  // namespace sdf::test
