// SPDX-License-Identifier: GPL-3.0-or-later
// The faces' points and a BVH made on the device (kernels/sdf_lbvh_kernels.cl) from the mesh
// and the host's TreeKeys, in place of a tree and points made on the host: the host then only
// orients the mesh and sorts its faces. The tree has the host tree's layout and boxes grown by
// the same margin, so the cast kernels read it unchanged and return the same values.
#pragma once

#include <cstdint>
#include <memory>

#include "../device_tree_keys.h"
#include "../mesh.h"
#include "device_state.h"

namespace sdf::cl {

// What the cast kernels read, on the device, made and waited for.
struct DeviceTree {
  // The points of every face (SamplePoints' arrays, face order) and the cast order.
  std::unique_ptr<Buffer> origins, axes, tangents, own_face, order;
  // The SdfBvhNode and SdfTriangle arrays.
  std::unique_ptr<Buffer> nodes, triangles;
  std::uint64_t peak_bytes = 0;  // the most device memory held at once while making them
  // Seconds for the uploads (the mesh, the order and the codes), then for the kernels.
  double upload_seconds = 0.0, build_seconds = 0.0;
};

// keys.with_area must be at least 1. Throws Error when an OpenCL call fails or the buffers
// cannot fit the device.
DeviceTree build_device_tree(const Device& device, DeviceState& s, cl_program program,
                             const Mesh& mesh, const TreeKeys& keys);

}  // namespace sdf::cl
