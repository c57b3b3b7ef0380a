// SPDX-License-Identifier: GPL-3.0-or-later
#include "tinybvh_cast.h"

#include <chrono>
#include <cstring>

#define TINYBVH_IMPLEMENTATION
#include "tiny_bvh.h"

#include "cl_bench.h"

namespace bench {

namespace {

// The ray record batch_ailalaine reads (traverse.cl's struct Ray): 16-byte fields.
struct RayRecord {
  float o[4], d[4], rd[4], hit[4];
};
static_assert(sizeof(RayRecord) == 64, "traverse.cl's Ray is 64 bytes");
static_assert(sizeof(tinybvh::BVH_GPU::BVHNode) == 64, "traverse.cl's BVHNode is 64 bytes");

// The options tinybvh's own OpenCL wrapper (tinyocl) builds its kernels with, as its README
// gives them: NVIDIA's with its vendor define and optimisation level, others without.
std::string tinyocl_options(const sdf::cl::Device& device, const std::string& folder) {
  std::string options = "-I " + folder +
                        " -cl-std=CL2.0 -cl-strict-aliasing -cl-fast-relaxed-math"
                        " -cl-single-precision-constant";
  if (device.vendor.find("NVIDIA") != std::string::npos) options += " -cl-nv-opt-level=9";
  return options;
}

std::string tinyocl_defines(const sdf::cl::Device& device) {
  return device.vendor.find("NVIDIA") != std::string::npos ? "#define ISNVIDIA\n" : "";
}

}  // namespace

struct TinybvhCast::Impl {
  tinybvh::BVH_GPU bvh;
  std::vector<tinybvh::bvhvec4> corners;  // the triangle soup the builder reads
  cl_command_queue queue = nullptr;
  cl_program program = nullptr;
  std::unique_ptr<sdf::cl::Kernel> kernel;
  std::unique_ptr<sdf::cl::Buffer> nodes, indices, vertices, rays;
  std::size_t count = 0, global = 0, local = 0;
  ~Impl() {
    kernel.reset();
    if (program) sdf::cl::api()->clReleaseProgram(program);
  }
};

TinybvhCast::TinybvhCast(const sdf::cl::Device& device, sdf::cl::DeviceState& s,
                         cl_command_queue queue, const std::string& folder,
                         const std::vector<float>& triangles, const std::vector<float>& origins,
                         const std::vector<float>& directions)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.queue = queue;
  const std::size_t tris = triangles.size() / 9;
  m.corners.resize(3 * tris);
  for (std::size_t i = 0; i < 3 * tris; ++i)
    m.corners[i] =
        tinybvh::bvhvec4(triangles[3 * i], triangles[3 * i + 1], triangles[3 * i + 2], 0);
  const auto start = std::chrono::steady_clock::now();
  m.bvh.Build(m.corners.data(), static_cast<std::uint32_t>(tris));
  build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  nodes = m.bvh.usedNodes;

  options = tinyocl_options(device, folder);
  m.program = program_from_source(device, s.context,
                                  tinyocl_defines(device) + "#include \"traverse.cl\"\n", options);
  m.kernel = std::make_unique<sdf::cl::Kernel>(m.program, "batch_ailalaine");

  // One work item per ray, in groups of 64 on GPUs (the launch must cover whole groups: the
  // last ray is repeated to fill the last one); the driver's choice elsewhere.
  m.count = origins.size() / 3;
  m.local = device.gpu ? 64 : 0;
  m.global = m.local ? (m.count + m.local - 1) / m.local * m.local : m.count;
  std::vector<RayRecord> records(m.global);
  for (std::size_t i = 0; i < m.global; ++i) {
    const std::size_t r = std::min(i, m.count - 1);
    const tinybvh::bvhvec3 d(directions[3 * r], directions[3 * r + 1], directions[3 * r + 2]);
    const tinybvh::bvhvec3 rd = tinybvh::tinybvh_rcp(d);
    records[i] = RayRecord{{origins[3 * r], origins[3 * r + 1], origins[3 * r + 2], 0},
                           {d.x, d.y, d.z, 0},
                           {rd.x, rd.y, rd.z, 0},
                           {1e30f, 0, 0, 0}};
  }
  m.nodes = std::make_unique<sdf::cl::Buffer>(s, nodes * sizeof(tinybvh::BVH_GPU::BVHNode),
                                              m.bvh.bvhNode);
  m.indices = std::make_unique<sdf::cl::Buffer>(s, m.bvh.bvh.idxCount * sizeof(std::uint32_t),
                                                m.bvh.bvh.primIdx);
  m.vertices = std::make_unique<sdf::cl::Buffer>(s, m.corners.size() * sizeof(tinybvh::bvhvec4),
                                                 m.corners.data());
  m.rays = std::make_unique<sdf::cl::Buffer>(s, records.size() * sizeof(RayRecord), records.data());
  sdf::cl::check(sdf::cl::api()->clFinish(s.queue), "clFinish (tinybvh upload)");
  m.kernel->arg(0, m.nodes->get());
  m.kernel->arg(1, m.indices->get());
  m.kernel->arg(2, m.vertices->get());
  m.kernel->arg(3, m.rays->get());
}

TinybvhCast::~TinybvhCast() = default;

double TinybvhCast::cast_ms() {
  Impl& m = *impl_;
  cl_event event = nullptr;
  sdf::cl::check(
      sdf::cl::api()->clEnqueueNDRangeKernel(m.queue, m.kernel->get(), 1, nullptr, &m.global,
                                             m.local ? &m.local : nullptr, 0, nullptr, &event),
      "clEnqueueNDRangeKernel (tinybvh)");
  return event_ms(event);
}

void TinybvhCast::hits(std::vector<float>& t, std::vector<int>& id) {
  Impl& m = *impl_;
  std::vector<RayRecord> records(m.count);
  sdf::cl::check(sdf::cl::api()->clEnqueueReadBuffer(m.queue, m.rays->get(), CL_TRUE, 0,
                                                     m.count * sizeof(RayRecord), records.data(), 0,
                                                     nullptr, nullptr),
                 "clEnqueueReadBuffer (tinybvh hits)");
  t.resize(m.count);
  id.resize(m.count);
  for (std::size_t i = 0; i < m.count; ++i) {
    t[i] = records[i].hit[0];
    std::memcpy(&id[i], &records[i].hit[3], sizeof(int));
  }
}

}  // namespace bench
