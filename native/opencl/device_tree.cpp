// SPDX-License-Identifier: GPL-3.0-or-later
#include "device_tree.h"

#include <algorithm>
#include <chrono>
#include <vector>

#include "../../kernels/sdf_layout.h"

namespace sdf::cl {

namespace {

// One item each over [0, count): groups of 64 on GPUs (NVIDIA's driver would otherwise pick a
// divisor of the global size, down to 1); the driver's choice on CPUs.
void launch_items(const Device& device, DeviceState& s, const Kernel& kernel, std::size_t count) {
  const std::size_t local = 64;
  const std::size_t global = (std::max<std::size_t>(count, 1) + local - 1) / local * local;
  check(api()->clEnqueueNDRangeKernel(s.queue, kernel.get(), 1, nullptr, &global,
                                      device.gpu ? &local : nullptr, 0, nullptr, nullptr),
        "clEnqueueNDRangeKernel");
}

}  // namespace

DeviceTree build_device_tree(const Device& device, DeviceState& s, cl_program program,
                             const Mesh& mesh, const TreeKeys& keys) {
  const std::size_t faces = mesh.triangles.size(), n = keys.with_area;
  const std::size_t slots = 2 * n - 1, inner = std::max<std::size_t>(n, 2) - 1;
  // The build's buffers, then the points' (made once the build's scratch is released); the
  // mesh stays until the points are made.
  const std::vector<std::size_t> build = {
      bytes_of(mesh.vertices), bytes_of(mesh.triangles), faces * 4, n * 4,  // mesh, order, codes
      n * sizeof(kern::SdfTriangle), slots * sizeof(kern::SdfBvhNode),
      slots * 4, inner * 16, inner * 4};  // slot_of, inner nodes, made_in
  const std::vector<std::size_t> cast = {
      bytes_of(mesh.vertices), bytes_of(mesh.triangles), faces * 4,
      n * sizeof(kern::SdfTriangle), slots * sizeof(kern::SdfBvhNode),
      3 * faces * 12, faces * 4,  // origins, axes, tangents; own_face
      faces * 8};  // the cast's results
  check_fits(device, build);
  check_fits(device, cast);
  DeviceTree tree;
  for (const auto* sizes : {&build, &cast}) {
    std::uint64_t total = 0;
    for (std::size_t b : *sizes) total += b;
    tree.peak_bytes = std::max(tree.peak_bytes, total);
  }

  using Clock = std::chrono::steady_clock;
  const Clock::time_point start = Clock::now();
  Buffer vertices(s, bytes_of(mesh.vertices), mesh.vertices.data());
  Buffer triangles(s, bytes_of(mesh.triangles), mesh.triangles.data());
  tree.order = std::make_unique<Buffer>(s, faces * 4, keys.order.data());
  tree.triangles = std::make_unique<Buffer>(s, n * sizeof(kern::SdfTriangle), nullptr);
  tree.nodes = std::make_unique<Buffer>(s, slots * sizeof(kern::SdfBvhNode), nullptr);
  {
    Buffer codes(s, n * 4, keys.codes.data());
    check(api()->clFinish(s.queue), "clFinish (upload)");
    tree.upload_seconds = std::chrono::duration<double>(Clock::now() - start).count();
    Buffer slot_of(s, slots * 4, nullptr), inner_nodes(s, inner * 16, nullptr),
        made_in(s, inner * 4, nullptr);
    const cl_int count = static_cast<cl_int>(n);
    Kernel records(program, "sdf_lbvh_triangles");
    records.arg(0, vertices.get());
    records.arg(1, triangles.get());
    records.arg(2, tree.order->get());
    records.arg(3, static_cast<cl_uint>(n));
    records.arg(4, tree.triangles->get());
    launch_items(device, s, records, n);
    Kernel karras(program, "sdf_lbvh_inner");
    karras.arg(0, codes.get());
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
    leaves.arg(5, keys.margin);
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
    // Released here, freed by the driver once the kernels that read them have run.
  }
  tree.origins = std::make_unique<Buffer>(s, faces * 12, nullptr);
  tree.axes = std::make_unique<Buffer>(s, faces * 12, nullptr);
  tree.tangents = std::make_unique<Buffer>(s, faces * 12, nullptr);
  tree.own_face = std::make_unique<Buffer>(s, faces * 4, nullptr);
  Kernel points(program, "sdf_face_points");
  points.arg(0, vertices.get());
  points.arg(1, triangles.get());
  points.arg(2, static_cast<cl_uint>(faces));
  points.arg(3, tree.origins->get());
  points.arg(4, tree.axes->get());
  points.arg(5, tree.tangents->get());
  points.arg(6, tree.own_face->get());
  launch_items(device, s, points, faces);
  check(api()->clFinish(s.queue), "clFinish (device tree)");
  tree.build_seconds =
      std::chrono::duration<double>(Clock::now() - start).count() - tree.upload_seconds;
  return tree;
}

}  // namespace sdf::cl
