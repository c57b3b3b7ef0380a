// SPDX-License-Identifier: GPL-3.0-or-later
// The set of ray directions in each point's cone (host side of kernels/ray/sdf_rays.h).
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

namespace sdf {

enum class Sampling { Fibonacci = 0, Random = 1, Cgal = 2 };

// The most rays per point: the reduction sorts them in registers on a device.
constexpr int kMaxRays = 1024;

struct Cone {
  int rays = 30;
  Sampling sampling = Sampling::Fibonacci;
  std::uint32_t seed = 0;
  // Of the cone's half-angle. 1 - cos rather than cos: it stays exact for narrow cones.
  float one_minus_cos_half = 0.5f, sin_half = 0.8660254f;
  // The smallest angle a weight 1/angle uses: the angle of the innermost Fibonacci ray,
  // acos(1 - (1 - cos_half) / (2 rays)). Fibonacci rays never go below it; a random ray nearer
  // the axis (or CGAL's on-axis sample) weighs as that innermost ray instead of infinitely.
  float angle_floor = 0.0f;
  // Local directions and their angles to the axis, for samplings that are the same at every
  // point (all but Random), computed once instead of once a point.
  std::vector<glm::vec3> local;
  std::vector<float> local_angle;
};

// cone_angle_degrees is the full apex angle, in (0, 180). Throws std::invalid_argument for a
// ray count outside [1, kMaxRays] or an angle outside that range.
Cone make_cone(int rays, double cone_angle_degrees, Sampling sampling, std::uint32_t seed);

// World directions (unit) and their angles to `axis` (unit, inward) for one point with unit
// `tangent` (perpendicular to the axis: SamplePoints::tangents); `point` is the point's index,
// which seeds random sampling. CGAL sampling ignores the tangent (it has CGAL's frame).
void cone_rays(const Cone& cone, glm::vec3 axis, glm::vec3 tangent, std::uint32_t point,
               glm::vec3* directions, float* angles);

// A unit vector perpendicular to unit `axis`, for points whose mesh gives no tangent: the
// direction of cross(axis, g) for a fixed, deliberately skewed g. Continuous except where the
// axis is parallel to g, a direction no mesh normal takes in practice (axis-aligned normals,
// common in CAD, are far from it).
glm::vec3 fallback_tangent(glm::vec3 axis);

}  // namespace sdf
