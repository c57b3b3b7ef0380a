// SPDX-License-Identifier: GPL-3.0-or-later
// Meshes built in code for the smoothing tests: grids, a box with split sides, an icosphere.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <random>
#include <utility>
#include <vector>

#include "test_meshes.h"

namespace sdf::test {

// An nx x ny grid of squares (2 triangles each) in the plane z = 0 from (x0, y0), squares of
// side h, counter-clockwise seen from +z. Vertex (i, j) has index j * (nx + 1) + i.
inline Arrays grid(int nx, int ny, double h = 1.0, double x0 = 0.0, double y0 = 0.0) {
  Arrays a;
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i)
      a.vertices.insert(a.vertices.end(), {x0 + i * h, y0 + j * h, 0.0});
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const std::int64_t v = j * (nx + 1) + i, r = v + nx + 1;
      a.triangles.insert(a.triangles.end(), {v, v + 1, r + 1, v, r + 1, r});
    }
  return a;
}

// The unit cube [-1, 1]^3 with each side an n x n grid of its own vertices: the sides share no
// vertex index (as a file split at normal seams stores them), only positions.
inline Arrays split_cube(int n) {
  Arrays a;
  // Each side: a point of it is o + s * u + t * v, (s, t) in [0, 2]^2, u x v = outward normal.
  const double sides[6][9] = {
      {-1, -1, 1, 1, 0, 0, 0, 1, 0}, {-1, 1, -1, 1, 0, 0, 0, -1, 0},   // +z, -z
      {-1, 1, -1, 0, 0, 1, 1, 0, 0}, {-1, -1, -1, 1, 0, 0, 0, 0, 1},   // +y, -y
      {1, -1, -1, 0, 1, 0, 0, 0, 1}, {-1, -1, -1, 0, 0, 1, 0, 1, 0}};  // +x, -x
  for (const auto& s : sides) {
    const std::int64_t base = static_cast<std::int64_t>(a.vertices.size() / 3);
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) {
        const double p = 2.0 * i / n, q = 2.0 * j / n;
        for (int k = 0; k < 3; ++k) a.vertices.push_back(s[k] + p * s[3 + k] + q * s[6 + k]);
      }
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const std::int64_t v = base + j * (n + 1) + i, r = v + n + 1;
        a.triangles.insert(a.triangles.end(), {v, v + 1, r + 1, v, r + 1, r});
      }
  }
  return a;
}

// An icosphere of radius r: the icosahedron subdivided `level` times, counter-clockwise from
// outside.
inline Arrays icosphere(int level, double r = 1.0) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<std::array<double, 3>> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0},
                                          {0, -1, t}, {0, 1, t}, {0, -1, -t}, {0, 1, -t},
                                          {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  std::vector<std::array<std::int64_t, 3>> f = {
      {0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
      {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
      {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  auto unit = [](std::array<double, 3> p) {
    const double l = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    return std::array<double, 3>{p[0] / l, p[1] / l, p[2] / l};
  };
  for (auto& p : v) p = unit(p);
  for (int l = 0; l < level; ++l) {
    std::map<std::pair<std::int64_t, std::int64_t>, std::int64_t> mid;
    auto middle = [&](std::int64_t a, std::int64_t b) {
      const auto key = std::make_pair(std::min(a, b), std::max(a, b));
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      v.push_back(unit({v[a][0] + v[b][0], v[a][1] + v[b][1], v[a][2] + v[b][2]}));
      const std::int64_t id = static_cast<std::int64_t>(v.size()) - 1;
      mid[key] = id;
      return id;
    };
    std::vector<std::array<std::int64_t, 3>> next;
    for (const auto& tri : f) {
      const std::int64_t a = middle(tri[0], tri[1]), b = middle(tri[1], tri[2]),
                         c = middle(tri[2], tri[0]);
      next.push_back({tri[0], a, c});
      next.push_back({tri[1], b, a});
      next.push_back({tri[2], c, b});
      next.push_back({a, b, c});
    }
    f.swap(next);
  }
  Arrays out;
  for (const auto& p : v)
    for (int k = 0; k < 3; ++k) out.vertices.push_back(r * p[k]);
  for (const auto& tri : f) out.triangles.insert(out.triangles.end(), tri.begin(), tri.end());
  return out;
}

// Values with uniform noise of half-width `amplitude` around `base`.
inline std::vector<float> noisy(std::size_t n, float base, float amplitude, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-amplitude, amplitude);
  std::vector<float> out(n);
  for (float& x : out) x = base + u(rng);
  return out;
}

inline double variance(const std::vector<float>& x) {
  double mean = 0.0;
  for (float v : x) mean += v;
  mean /= x.size();
  double s = 0.0;
  for (float v : x) s += (v - mean) * (v - mean);
  return s / x.size();
}

}  // namespace sdf::test
