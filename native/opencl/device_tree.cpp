// SPDX-License-Identifier: GPL-3.0-or-later
#include "device_tree.h"

#include <algorithm>
#include <climits>
#include <mutex>
#include <string>
#include <vector>

#include "accel/bvh_margin.h"
#include "common/sdf_layout.h"
#include "util/stopwatch.h"

namespace sdf::cl {

namespace {

// One item each over [0, count): groups of `local` on GPUs (NVIDIA's driver would otherwise
// pick a divisor of the global size, down to 1); the driver's choice on CPUs unless asked.
void launch_items(const Device& device, DeviceState& s, const Kernel& kernel, std::size_t count,
                  std::size_t local = 64, bool exact = false) {
  const std::size_t global = (std::max<std::size_t>(count, 1) + local - 1) / local * local;
  check(api()->clEnqueueNDRangeKernel(s.queue, kernel.get(), 1, nullptr, &global,
                                      device.gpu || exact ? &local : nullptr, 0, nullptr, nullptr),
        "clEnqueueNDRangeKernel");
}

// Tiles of the sort kernels (SDF_SORT_GROUP in sdf_sort_kernels.cl).
constexpr std::size_t kSortGroup = 256;

// The faces' keys (Morton codes, 2^30 for faces without area) and values (face indices), in
// `keys` and `values`, sorted stably by key on the device, and how many faces have area and
// the tree's margin (bvh_margin.h), from the box of those faces and their longest edge
// component. Waits for the device.
void sort_faces_on_device(const Device& device, DeviceState& s, cl_program program,
                          const Buffer& vertices, const Buffer& triangles, std::size_t faces,
                          const Buffer& keys, const Buffer& values, std::size_t* with_area,
                          float* margin) {
  const cl_uint count = static_cast<cl_uint>(faces);
  const int start_extent[8] = {INT_MAX, INT_MAX, INT_MAX, INT_MIN, INT_MIN, INT_MIN, 0, 0};
  Buffer extent(s, sizeof start_extent, start_extent);
  Kernel box(program, "sdf_lbvh_extent");
  box.arg(0, vertices.get());
  box.arg(1, triangles.get());
  box.arg(2, count);
  box.arg(3, extent.get());
  launch_items(device, s, box, faces, 64, true);  // its local table needs 8 items a group
  Kernel codes(program, "sdf_lbvh_codes");
  codes.arg(0, vertices.get());
  codes.arg(1, triangles.get());
  codes.arg(2, count);
  codes.arg(3, extent.get());
  codes.arg(4, keys.get());
  codes.arg(5, values.get());
  launch_items(device, s, codes, faces);

  const std::size_t tiles = (faces + kSortGroup - 1) / kSortGroup;
  Buffer other_keys(s, faces * 4, nullptr), other_values(s, faces * 4, nullptr);
  Buffer counts(s, tiles * 16 * 4, nullptr);
  Kernel count_digits(program, "sdf_sort_count"), scan(program, "sdf_sort_scan"),
      scatter(program, "sdf_sort_scatter");
  const cl_uint entries = static_cast<cl_uint>(tiles * 16);
  scan.arg(0, counts.get());
  scan.arg(1, entries);
  const Buffer* from[2] = {&keys, &values};
  const Buffer* to[2] = {&other_keys, &other_values};
  // 31-bit keys, 4 bits a pass: 8 passes, an even count, so the result ends where it began.
  for (int shift = 0; shift < 31; shift += 4) {
    count_digits.arg(0, from[0]->get());
    count_digits.arg(1, count);
    count_digits.arg(2, static_cast<cl_int>(shift));
    count_digits.arg(3, counts.get());
    launch_items(device, s, count_digits, faces, kSortGroup, true);
    launch_items(device, s, scan, kSortGroup, kSortGroup, true);
    scatter.arg(0, from[0]->get());
    scatter.arg(1, from[1]->get());
    scatter.arg(2, count);
    scatter.arg(3, static_cast<cl_int>(shift));
    scatter.arg(4, counts.get());
    scatter.arg(5, to[0]->get());
    scatter.arg(6, to[1]->get());
    launch_items(device, s, scatter, faces, kSortGroup, true);
    std::swap(from, to);
  }
  std::int32_t found[8];
  read_buffer(s, extent.get(), found, sizeof found);
  using kern::sdf_ordered_float;
  *with_area = static_cast<std::size_t>(found[7]);
  *margin = tree_margin(glm::vec3(sdf_ordered_float(found[0]), sdf_ordered_float(found[1]),
                                  sdf_ordered_float(found[2])),
                        glm::vec3(sdf_ordered_float(found[3]), sdf_ordered_float(found[4]),
                                  sdf_ordered_float(found[5])),
                        sdf_ordered_float(found[6]));  // a length >= 0: its bits as they are
}

// The triangles' records of the faces with area, in the cast order (SdfTriangle units, as
// the host writes them), then the order read back for the results: waits for the device.
void make_records(const Device& device, DeviceState& s, cl_program program, DeviceTree& tree,
                  std::size_t faces) {
  const std::size_t n = tree.with_area;
  if (!tree.triangles)
    tree.triangles = std::make_unique<Buffer>(s, n * sizeof(kern::SdfTriangle), nullptr);
  Kernel records(program, "sdf_lbvh_triangles");
  records.arg(0, tree.vertices->get());
  records.arg(1, tree.faces->get());
  records.arg(2, tree.order->get());
  records.arg(3, static_cast<cl_uint>(n));
  records.arg(4, tree.triangles->get());
  launch_items(device, s, records, n);
  if (tree.host_order.size() != faces) {
    tree.host_order.resize(faces);
    read_buffer(s, tree.order->get(), tree.host_order.data(), faces * 4);
  }
  check(api()->clFinish(s.queue), "clFinish (device tree)");
}

}  // namespace

bool makes_trees(const Device& device) { return device.max_group >= kSortGroup; }

DeviceTree build_device_tree(const Device& device, DeviceState& s, const std::string& options,
                             const Mesh& mesh, const std::function<void()>& uploaded) {
  // make_plan asks only such devices for a tree; a test override may ask any.
  if (!makes_trees(device))
    throw Error("OpenCL device '" + device.name + "' cannot run work groups of " +
                    std::to_string(kSortGroup) +
                    " items, which its tree's sort needs: "
                    "let the host build the tree",
                CL_INVALID_WORK_GROUP_SIZE);
  const std::size_t faces = mesh.triangles.size();
  // Checked at the most faces can ask: the sort's buffers (the mesh, the order and codes and
  // their second copies, the digit counts); the tree's (the mesh, the order, the codes, the
  // nodes, slot_of, the inner nodes, made_in); the triangles' records, made once that scratch
  // is freed (the mesh, the order, the nodes, the records); the cast's (the same and the
  // results). The cast makes the faces' points from the mesh as it goes, so they never take
  // memory of their own.
  const std::size_t slots = 2 * faces, most_inner = faces;
  const std::size_t mesh_bytes = bytes_of(mesh.vertices) + bytes_of(mesh.triangles);
  const std::size_t node_bytes = slots * sizeof(kern::SdfBvhNode),
                    record_bytes = faces * sizeof(kern::SdfTriangle);
  const std::vector<std::vector<std::size_t>> phases = {
      {mesh_bytes, 4 * faces * 4, (faces / kSortGroup + 1) * 64},
      {mesh_bytes, faces * 4, faces * 4, node_bytes, slots * 4, most_inner * 16, most_inner * 4},
      {mesh_bytes, faces * 4, node_bytes, record_bytes, faces * 8}};
  DeviceTree tree;
  for (const auto& sizes : phases) {
    check_fits(device, sizes);
    std::uint64_t total = 0;
    for (std::size_t b : sizes) total += b;
    tree.peak_bytes = std::max(tree.peak_bytes, total);
  }

  Stopwatch clock;
  tree.vertices = std::make_unique<Buffer>(s, bytes_of(mesh.vertices), mesh.vertices.data());
  tree.faces = std::make_unique<Buffer>(s, bytes_of(mesh.triangles), mesh.triangles.data());
  const Buffer& vertices = *tree.vertices;
  const Buffer& triangles = *tree.faces;
  check(api()->clFinish(s.queue), "clFinish (upload)");
  tree.upload_seconds = clock.lap();
  if (uploaded) uploaded();
  // Compiled (or loaded from the cache) here, once the host has started orienting the mesh.
  cl_program program = program_for(device, s, options);
  clock.lap();

  // The faces' order and codes.
  tree.order = std::make_unique<Buffer>(s, faces * 4, nullptr);
  auto codes = std::make_unique<Buffer>(s, faces * 4, nullptr);
  float margin = 0.0f;
  sort_faces_on_device(device, s, program, vertices, triangles, faces, *codes, *tree.order,
                       &tree.with_area, &margin);
  const std::size_t n = tree.with_area;
  if (n == 0) return tree;  // nothing can be hit: no tree, nothing to cast

  const std::size_t inner = std::max<std::size_t>(n, 2) - 1;
  // 2n - 1 nodes from slot SDF_LBVH_ROOT = 1 on.
  tree.nodes = std::make_unique<Buffer>(s, 2 * n * sizeof(kern::SdfBvhNode), nullptr);
  {
    Buffer slot_of(s, (2 * n - 1) * 4, nullptr), inner_nodes(s, inner * 16, nullptr),
        made_in(s, inner * 4, nullptr);
    const cl_int count = static_cast<cl_int>(n);
    Kernel karras(program, "sdf_lbvh_inner");
    karras.arg(0, codes->get());
    karras.arg(1, count);
    karras.arg(2, slot_of.get());
    karras.arg(3, inner_nodes.get());
    karras.arg(4, made_in.get());
    launch_items(device, s, karras, inner);
    Kernel leaves(program, "sdf_lbvh_leaves");
    leaves.arg(0, vertices.get());
    leaves.arg(1, triangles.get());
    leaves.arg(2, tree.order->get());
    leaves.arg(3, count);
    leaves.arg(4, slot_of.get());
    leaves.arg(5, margin);
    leaves.arg(6, tree.nodes->get());
    launch_items(device, s, leaves, n);
    // One launch per level of height. Down any path the common prefix of a node's keys grows
    // by at least one bit a level: at most 30 code bits, then the index bits of the ties.
    int index_bits = 0;
    while ((std::size_t{1} << index_bits) < n) ++index_bits;
    const int levels = n > 1 ? 31 + index_bits : 0;
    Kernel level(program, "sdf_lbvh_level");
    level.arg(0, count);
    level.arg(2, slot_of.get());
    level.arg(3, inner_nodes.get());
    level.arg(4, made_in.get());
    level.arg(5, tree.nodes->get());
    for (int l = 1; l <= levels; ++l) {
      level.arg(1, static_cast<cl_int>(l));
      launch_items(device, s, level, inner);
    }
    codes.reset();
    // The tree is waited for, so that its scratch is freed before the records take memory.
    check(api()->clFinish(s.queue), "clFinish (device tree)");
  }
  make_records(device, s, program, tree, faces);
  tree.build_seconds = clock.lap();
  return tree;
}

void rewind_device_tree(const Device& device, DeviceState& s, const std::string& options,
                        DeviceTree& tree, const Mesh& mesh, const std::function<void()>& uploaded) {
  Stopwatch clock;
  write_buffer(s, tree.faces->get(), mesh.triangles.data(), bytes_of(mesh.triangles));
  check(api()->clFinish(s.queue), "clFinish (upload)");
  tree.upload_seconds = clock.lap();
  if (uploaded) uploaded();
  make_records(device, s, program_for(device, s, options), tree, mesh.triangles.size());
  tree.build_seconds = clock.lap();
}

TreeKeys device_tree_keys(int index, const Mesh& mesh) {
  const Device& device = *select_devices("opencl:" + std::to_string(index)).front();
  DeviceState& s = state_of(device);
  std::lock_guard<std::mutex> lock(s.mutex);
  cl_program program = program_for(device, s, build_options(device, 30));
  const std::size_t faces = mesh.triangles.size();
  Buffer vertices(s, bytes_of(mesh.vertices), mesh.vertices.data());
  Buffer triangles(s, bytes_of(mesh.triangles), mesh.triangles.data());
  Buffer codes(s, faces * 4, nullptr), order(s, faces * 4, nullptr);
  TreeKeys keys;
  sort_faces_on_device(device, s, program, vertices, triangles, faces, codes, order,
                       &keys.with_area, &keys.margin);
  keys.order.resize(faces);
  keys.codes.resize(keys.with_area);
  read_buffer(s, order.get(), keys.order.data(), faces * 4);
  read_buffer(s, codes.get(), keys.codes.data(), keys.with_area * 4);
  return keys;
}

}  // namespace sdf::cl
