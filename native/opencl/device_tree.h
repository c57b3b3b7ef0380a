// SPDX-License-Identifier: GPL-3.0-or-later
// A BVH made on the device (kernels/cl/sdf_lbvh_kernels.cl) from the mesh alone, in place of a
// tree and points made on the host: the faces' Morton codes, their sort
// (kernels/cl/sdf_sort_kernels.cl), Karras's tree over them and its boxes. The tree has the host
// tree's layout and boxes grown by the same margin, so the cast kernels read it unchanged and
// return the same values; the faces' points are made from the mesh by the cast itself.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "device_state.h"
#include "mesh/mesh.h"
#include "util/uninitialized_vector.h"

namespace sdf::cl {

// What the cast kernels read, on the device, made and waited for.
struct DeviceTree {
  // The mesh (the cast makes each face's point from it: sdf_start_of_face) and the cast
  // order: faces with area in Morton order, then the others.
  std::unique_ptr<Buffer> vertices, faces, order;
  // The SdfBvhNode and SdfTriangle arrays.
  std::unique_ptr<Buffer> nodes, triangles;
  UninitializedVector<std::uint32_t> host_order;  // `order`, read back: results go to faces
  std::size_t with_area = 0;     // faces with area: 0 leaves nothing to cast (and no tree)
  std::uint64_t peak_bytes = 0;  // the most device memory held at once while making them
  // Seconds for the mesh's upload, then for the rest.
  double upload_seconds = 0.0, build_seconds = 0.0;
};

// The most faces a device-made tree takes: its slots (up to 2 x faces - 1, the root in slot 1)
// keep the kernels' float4 indices (2 x slot + 1, and the traversal's 2 x first + 3) within
// 32-bit ints. Larger meshes keep the host's tree.
constexpr std::size_t kDeviceTreeMaxFaces = std::size_t{1} << 29;

// Whether `device` can make the tree: its sort needs work groups of 256 items.
bool makes_trees(const Device& device);

// Throws Error when an OpenCL call fails or the buffers cannot fit the device. The program
// (build options `options`) is built or loaded after the mesh's upload; uploaded, when set, is
// called once the mesh is on the device (the host may then load its cores).
DeviceTree build_device_tree(const Device& device, DeviceState& s, const std::string& options,
                             const Mesh& mesh, const std::function<void()>& uploaded = nullptr);

// Makes `tree` (made by build_device_tree for a mesh) the tree of `mesh`, the same mesh with
// some faces reversed: a face's box, and so the faces' order and the nodes, do not depend on
// its winding, so only the faces are uploaded again and the triangles' records remade.
// Throws Error when an OpenCL call fails; uploaded as for build_device_tree.
void rewind_device_tree(const Device& device, DeviceState& s, const std::string& options,
                        DeviceTree& tree, const Mesh& mesh,
                        const std::function<void()>& uploaded = nullptr);

// The faces' sort as the device makes it: every face, those with area first in Morton order
// of their box centres (ties in face order), then the others in face order; the codes of the
// first `with_area`; the margin the tree's boxes grow by.
struct TreeKeys {
  UninitializedVector<std::uint32_t> order, codes;
  std::size_t with_area = 0;
  float margin = 0.0f;
};

// Test hook: the keys device `index` makes for `mesh`.
TreeKeys device_tree_keys(int index, const Mesh& mesh);

}  // namespace sdf::cl
