// SPDX-License-Identifier: GPL-3.0-or-later
// Our side of the GPU comparison: the tree the product makes on the device, its cast kernel
// (sdf_cast_bvh_per_ray_faces, one work item per ray) launched with the product's arguments
// and group size, and the same kernel compiled with one of the kernels' promises relaxed at a
// time (build options or a one-line source change), to measure what each costs.
// Benchmark code only.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "mesh/mesh.h"
#include "opencl/device_tree.h"
#include "prepare/rays.h"

namespace bench {

// One way of compiling the cast kernel. `missing` says why it could not be made (an option the
// device does not take, a source line not found); it is then not timed.
struct CastVariant {
  std::string name, options, source, missing;
};

class OurCast {
 public:
  // Makes the tree on the device as the product does and compiles every variant.
  OurCast(const sdf::cl::Device& device, sdf::cl::DeviceState& s, cl_command_queue queue,
          const sdf::Mesh& mesh, const sdf::Cone& cone, float tmin);
  ~OurCast();
  OurCast(const OurCast&) = delete;
  OurCast& operator=(const OurCast&) = delete;

  // The faces in cast order (those with area first, in the tree's Morton order), and how many
  // of them have area: only those are cast.
  const std::vector<std::uint32_t>& order() const { return order_; }
  std::size_t with_area() const { return with_area_; }
  const std::vector<CastVariant>& variants() const { return variants_; }

  // The cast of every face with area in one launch of variant v (0: as the product builds
  // it): the kernel's milliseconds; raw receives the values in cast order.
  double cast_ms(std::size_t v, std::vector<float>* raw = nullptr);

  // Every ray as the cast kernel makes it (origin and direction, 3 floats each, point-major in
  // cast order) and its nearest hit of either facing (t: INFINITY for none; the triangle id),
  // by the product's traversal on the product's tree.
  void ray_hits(std::vector<float>& origins, std::vector<float>& directions, std::vector<float>& t,
                std::vector<int>& id);

  double tree_seconds = 0.0;  // the device tree's build, as build_device_tree times it

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::vector<std::uint32_t> order_;
  std::size_t with_area_ = 0;
  std::vector<CastVariant> variants_;
};

}  // namespace bench
