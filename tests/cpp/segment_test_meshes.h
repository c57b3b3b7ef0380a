// SPDX-License-Identifier: GPL-3.0-or-later
// Meshes with known thickness for the segmentation tests: closed surfaces of revolution.
#pragma once

#include <cmath>
#include <cstdint>
#include <functional>
#include <vector>

#include "test_meshes.h"

namespace sdf::test {

// A closed surface of revolution around the x axis, outward faces: rings at the samples x[1]
// .. x[n-2] with radius profile(x), poles at x[0] and x[n-1]. `thickness` gets, per face, the
// diameter 2 profile(x) at the face's mean x (the SDF of a thin tube).
inline Arrays revolved(const std::function<double(double)>& profile, const std::vector<double>& x,
                       int sides, std::vector<double>* thickness = nullptr) {
  Arrays a;
  const int rings = static_cast<int>(x.size()) - 2;
  a.vertices.insert(a.vertices.end(), {x.front(), 0.0, 0.0});
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < sides; ++j) {
      const double t = 2.0 * M_PI * j / sides, r = profile(x[i + 1]);
      a.vertices.insert(a.vertices.end(), {x[i + 1], r * std::cos(t), r * std::sin(t)});
    }
  a.vertices.insert(a.vertices.end(), {x.back(), 0.0, 0.0});
  const std::int64_t last = 1 + std::int64_t{rings} * sides;
  for (int j = 0; j < sides; ++j) {
    const std::int64_t jn = (j + 1) % sides;
    a.triangles.insert(a.triangles.end(), {0, 1 + jn, 1 + j});
    for (int i = 0; i + 1 < rings; ++i) {
      const std::int64_t p = 1 + std::int64_t{i} * sides + j, q = 1 + std::int64_t{i} * sides + jn;
      a.triangles.insert(a.triangles.end(), {p, q, q + sides, p, q + sides, p + sides});
    }
    const std::int64_t base = 1 + std::int64_t{rings - 1} * sides;
    a.triangles.insert(a.triangles.end(), {last, base + j, base + jn});
  }
  if (thickness) {
    thickness->clear();
    for (std::size_t f = 0; f < a.triangles.size() / 3; ++f) {
      double mx = 0.0;
      for (int c = 0; c < 3; ++c) mx += a.vertices[3 * a.triangles[3 * f + c]] / 3.0;
      thickness->push_back(2.0 * profile(mx));
    }
  }
  return a;
}

// Where the neck meets each ball.
inline double dumbbell_neck_end() { return 1.6 - std::sqrt(1.0 - 0.25 * 0.25); }

// Balls of radius 1 at x = -1.6 and 1.6 joined by a neck of radius 0.25. `thickness`: per
// face, the ball's diameter or the neck's (the SDF of a ball is its diameter everywhere).
inline Arrays dumbbell(std::vector<double>* thickness = nullptr) {
  auto profile = [](double x) {
    const double d = std::abs(x) - 1.6;
    return std::max(std::sqrt(std::max(0.0, 1.0 - d * d)), 0.25);
  };
  std::vector<double> x{-2.6};
  for (int i = 0; i < 100; ++i) x.push_back(-2.58 + 5.16 * i / 99.0);
  x.push_back(2.6);
  Arrays a = revolved(profile, x, 32, thickness);
  if (thickness)
    for (std::size_t f = 0; f < thickness->size(); ++f) {
      double mx = 0.0;
      for (int c = 0; c < 3; ++c) mx += a.vertices[3 * a.triangles[3 * f + c]] / 3.0;
      (*thickness)[f] = std::abs(mx) > dumbbell_neck_end() ? 2.0 : 0.5;
    }
  return a;
}

}  // namespace sdf::test
