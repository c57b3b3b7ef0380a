// SPDX-License-Identifier: GPL-3.0-or-later
#include "segment/edge_weights.h"

#include <algorithm>
#include <cmath>

#include "util/parallel.h"

namespace sdf::segment {
namespace {

struct Vec {
  double x, y, z;
};
Vec sub(Vec a, Vec b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
Vec cross(Vec a, Vec b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
double dot(Vec a, Vec b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

// Angle in degrees between the planes (a, b, c) and (a, b, d) around the edge ab, signed:
// atan2 of the sine (the volume a, b, c, d spans) over the cosine (normals' dot product).
double dihedral_degrees(Vec a, Vec b, Vec c, Vec d) {
  const Vec ab = sub(b, a), ac = sub(c, a), ad = sub(d, a);
  const Vec abad = cross(ab, ad);
  const double x = dot(cross(ab, ac), abad);
  const double y = std::sqrt(dot(ab, ab)) * dot(ac, abad);
  return std::atan2(y, x) * 180.0 / 3.14159265358979323846;
}

}  // namespace

std::vector<double> edge_weights(const FaceGraph& graph, const double* vertices,
                                 const std::int64_t* triangles, double smoothness, unsigned threads,
                                 const WorkCheck& check) {
  const double scale = std::max(0.0, smoothness) * 100.0;
  auto point = [&](std::uint32_t face, unsigned corner) {
    const double* p = vertices + 3 * triangles[3 * face + corner % 3];
    return Vec{p[0], p[1], p[2]};
  };
  std::vector<double> weights(graph.pairs.size());
  parallel_for(
      weights.size(), 8192, threads,
      [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i) {
          const FacePair& p = graph.pairs[i];
          // The first face's edge runs b -> a; c its third corner, d the second face's.
          const Vec b = point(p.first, p.first_corner), a = point(p.first, p.first_corner + 1u);
          const Vec c = point(p.first, p.first_corner + 2u);
          const Vec d = point(p.second, p.second_corner + 2u);
          const double turn = dihedral_degrees(a, b, c, d) / 180.0;
          const bool concave = turn > 0;
          double w = 1.0 - std::abs(turn);
          if (!concave) w *= 0.08;
          weights[i] = -std::log(std::max(w, 5e-6)) * scale;
        }
      },
      as_progress(check));
  return weights;
}

}  // namespace sdf::segment
