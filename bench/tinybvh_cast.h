// SPDX-License-Identifier: GPL-3.0-or-later
// The reference GPU caster of the comparison: tinybvh's BVH_GPU layout (Aila and Laine's
// 2-wide, 64-byte nodes), built on the host by tiny_bvh.h, cast by its batch_ailalaine kernel
// from traverse.cl. Both come from a folder given at run time (bench/CMakeLists.txt compiles
// tiny_bvh.h from it): tinybvh is a reference the benchmark builds, never part of the product.
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "opencl/device_state.h"

namespace bench {

class TinybvhCast {
 public:
  // triangles: 3 corners x (x, y, z) per triangle, its index the triangle's id in hits();
  // origins and directions: 3 floats per ray. The ray records (origin, direction, its
  // reciprocal, hit: 64 bytes) are made and uploaded here, once.
  TinybvhCast(const sdf::cl::Device& device, sdf::cl::DeviceState& s, cl_command_queue queue,
              const std::string& folder, const std::vector<float>& triangles,
              const std::vector<float>& origins, const std::vector<float>& directions);
  ~TinybvhCast();
  TinybvhCast(const TinybvhCast&) = delete;
  TinybvhCast& operator=(const TinybvhCast&) = delete;

  // Casts every ray in one launch; the kernel's time in milliseconds.
  double cast_ms();
  // Per ray: t (1e30 for a miss), then the triangle's id (meaningful for a hit).
  void hits(std::vector<float>& t, std::vector<int>& id);

  double build_seconds = 0.0;  // tinybvh's host build and its conversion to BVH_GPU
  std::size_t nodes = 0;
  std::string options;  // the kernel's build options

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace bench
