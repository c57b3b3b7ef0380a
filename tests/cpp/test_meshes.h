// SPDX-License-Identifier: GPL-3.0-or-later
// Small meshes built in code for the C++ tests.
#pragma once

#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "mesh/mesh.h"

namespace sdf::test {

struct Arrays {
  std::vector<double> vertices;
  std::vector<std::int64_t> triangles;
  Mesh mesh() const {
    return make_mesh(vertices.data(), vertices.size() / 3, triangles.data(), triangles.size() / 3);
  }
};

// An axis-aligned closed box of size (sx, sy, sz) centred at the origin, 12 triangles,
// counter-clockwise from outside.
inline Arrays box(double sx, double sy, double sz) {
  Arrays a;
  for (int i = 0; i < 8; ++i) {
    a.vertices.push_back((i & 1 ? 0.5 : -0.5) * sx);
    a.vertices.push_back((i & 2 ? 0.5 : -0.5) * sy);
    a.vertices.push_back((i & 4 ? 0.5 : -0.5) * sz);
  }
  const std::int64_t quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                    {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : quads) {
    a.triangles.insert(a.triangles.end(), {q[0], q[1], q[2], q[0], q[2], q[3]});
  }
  return a;
}

// Random triangles in the unit cube: a soup with every kind of overlap.
inline Arrays soup(int count, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Arrays a;
  for (int t = 0; t < count; ++t) {
    const double cx = u(rng), cy = u(rng), cz = u(rng);
    for (int k = 0; k < 3; ++k) {
      a.vertices.push_back(cx + 0.2 * u(rng));
      a.vertices.push_back(cy + 0.2 * u(rng));
      a.vertices.push_back(cz + 0.2 * u(rng));
      a.triangles.push_back(3 * t + k);
    }
  }
  return a;
}

}  // namespace sdf::test
