// SPDX-License-Identifier: GPL-3.0-or-later
#include "prepare/rays.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "ray/sdf_face_point.h"
#include "ray/sdf_rays.h"

namespace sdf {

Cone make_cone(int rays, double cone_angle_degrees, Sampling sampling, std::uint32_t seed) {
  if (rays < 1 || rays > kMaxRays)
    throw std::invalid_argument("rays must be in [1, " + std::to_string(kMaxRays) + "], got " +
                                std::to_string(rays));
  if (!(cone_angle_degrees > 0.0 && cone_angle_degrees < 180.0))
    throw std::invalid_argument("cone_angle must be in (0, 180) degrees, got " +
                                std::to_string(cone_angle_degrees));
  Cone cone;
  cone.rays = rays;
  cone.sampling = sampling;
  cone.seed = seed;
  const double half = 0.5 * cone_angle_degrees * M_PI / 180.0;
  // 1 - cos(h) = 2 sin^2(h / 2): no cancellation for narrow cones.
  const double one_minus_cos = 2.0 * std::sin(0.5 * half) * std::sin(0.5 * half);
  cone.one_minus_cos_half = static_cast<float>(one_minus_cos);
  cone.sin_half = static_cast<float>(std::sin(half));
  // acos(1 - x) = 2 asin(sqrt(x / 2)), accurate for tiny x; floored so a weight stays finite.
  const double x = one_minus_cos / (2.0 * rays);
  cone.angle_floor = static_cast<float>(std::max(2.0 * std::asin(std::sqrt(0.5 * x)), 1e-30));
  if (sampling != Sampling::Random) {
    cone.local.resize(rays);
    cone.local_angle.resize(rays);
    for (int i = 0; i < rays; ++i) {
      cone.local[i] = kern::sdf_ray_local(static_cast<int>(sampling), i, rays,
                                          cone.one_minus_cos_half, cone.sin_half, seed, 0u);
      cone.local_angle[i] = kern::sdf_ray_angle(cone.local[i]);
    }
  }
  return cone;
}

void cone_rays(const Cone& cone, glm::vec3 axis, glm::vec3 tangent, std::uint32_t point,
               glm::vec3* directions, float* angles) {
  glm::vec3 b1, b2;
  kern::sdf_frame(static_cast<int>(cone.sampling), axis, tangent, &b1, &b2);
  for (int i = 0; i < cone.rays; ++i) {
    glm::vec3 local;
    if (cone.sampling == Sampling::Random) {
      local = kern::sdf_ray_local(SDF_SAMPLING_RANDOM, i, cone.rays, cone.one_minus_cos_half,
                                  cone.sin_half, cone.seed, point);
      angles[i] = kern::sdf_ray_angle(local);
    } else {
      local = cone.local[i];
      angles[i] = cone.local_angle[i];
    }
    directions[i] = kern::sdf_to_world(local, b1, b2, axis);
  }
}

glm::vec3 fallback_tangent(glm::vec3 axis) { return kern::sdf_fallback_tangent(axis); }

}  // namespace sdf
