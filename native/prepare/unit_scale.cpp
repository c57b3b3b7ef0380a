// SPDX-License-Identifier: GPL-3.0-or-later
#include "prepare/unit_scale.h"

#include <cmath>

#include "util/parallel.h"

namespace sdf {

namespace {

constexpr std::size_t kGrain = 1 << 16;

glm::vec3 ldexp3(glm::vec3 v, int exponent) {
  return {std::ldexp(v.x, exponent), std::ldexp(v.y, exponent), std::ldexp(v.z, exponent)};
}

}  // namespace

int unit_scale_exponent(double max_extent) {
  if (!(max_extent > 0.0) || (max_extent >= 0x1p-20 && max_extent <= 0x1p30)) return 0;
  int e = 0;
  std::frexp(max_extent, &e);  // max_extent = m 2^e, m in [0.5, 1)
  return 1 - e;
}

void scale_mesh(Mesh& mesh, int exponent, unsigned threads) {
  parallel_for(mesh.vertices.size(), kGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t v = begin; v < end; ++v) mesh.vertices[v] = ldexp3(mesh.vertices[v], exponent);
  });
  mesh.max_extent = std::ldexp(mesh.max_extent, exponent);
}

void scale_lengths(float* values, std::size_t count, int exponent) {
  for (std::size_t i = 0; i < count; ++i) values[i] = std::ldexp(values[i], exponent);
}

SamplePoints scaled_points(const SamplePoints& points, int exponent) {
  SamplePoints out;
  out.origins.resize(points.size());
  for (std::size_t i = 0; i < points.size(); ++i)
    out.origins[i] = ldexp3(points.origins[i], exponent);
  out.axes = points.axes;
  out.tangents = points.tangents;
  out.own_face = points.own_face;
  return out;
}

}  // namespace sdf
