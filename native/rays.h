// SPDX-License-Identifier: GPL-3.0-or-later
// The set of ray directions in each point's cone (host side of kernels/sdf_rays.h).
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
  float cos_half = 0.5f, sin_half = 0.8660254f;
  float angle_floor = 0.0f;  // smallest angle a weight uses (sdf_angle_floor)
  // Local directions and their angles to the axis, for samplings that are the same at every
  // point (all but Random), computed once instead of once a point.
  std::vector<glm::vec3> local;
  std::vector<float> local_angle;
};

// cone_angle_degrees is the full apex angle, in (0, 180). Throws std::invalid_argument for a
// ray count outside [1, kMaxRays] or an angle outside that range.
Cone make_cone(int rays, double cone_angle_degrees, Sampling sampling, std::uint32_t seed);

// World directions (unit) and their angles to `axis` (unit, inward) for one point; `point` is
// the point's index, which seeds random sampling.
void cone_rays(const Cone& cone, glm::vec3 axis, std::uint32_t point, glm::vec3* directions,
               float* angles);

}  // namespace sdf
