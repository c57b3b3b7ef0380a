// SPDX-License-Identifier: GPL-3.0-or-later
#include "our_cast.h"

#include <algorithm>
#include <cstring>

#include "cl_bench.h"
#include "common/sdf_layout.h"
#include "opencl/kernel_source.h"
#include "opencl/program_cache.h"

namespace bench {

namespace {

using sdf::cl::Buffer;
using sdf::cl::Kernel;

// Ray r of the point at place i of the cast order, made as sdf_cast_bvh_per_ray_faces makes
// it (the same functions, the same program options), and its nearest hit of either facing by
// the product's traversal: what the benchmark compares with the reference's hits.
const char* const kRayHitsKernel = R"CL(
__kernel void bench_face_ray_hits(__global const float4* restrict nodes,
                                  __global const float4* restrict tris,
                                  __global const float* restrict vertices,
                                  __global const uint* restrict faces,
                                  __global const uint* restrict order,
                                  __global const float4* restrict local_rays,
                                  SdfCastParams params, __global float4* restrict rays_out,
                                  __global float2* restrict hits_out) {
  uint gid = get_global_id(0);
  uint i = gid / (uint)params.rays;
  int r = (int)(gid % (uint)params.rays);
  if (i >= params.count) return;
  uint p = order[params.first + i];
  SdfRayStart start = sdf_start_of_face(p, vertices, faces);
  float3 b1, b2;
  float angle;
  sdf_frame(params.sampling, start.axis, start.tangent, &b1, &b2);
  float3 d = sdf_cast_direction(params, local_rays, r, p, start.axis, b1, b2, &angle);
  SdfHit hit = sdf_bvh_closest_hit_units(nodes, tris, SDF_LBVH_ROOT, start.origin, d,
                                         params.tmin, start.own);
  rays_out[2 * gid] = (float4)(start.origin, 0.0f);
  rays_out[2 * gid + 1] = (float4)(d, 0.0f);
  hits_out[gid] = (float2)(hit.t, as_float(hit.id));
}
)CL";

// `text` with every `from` replaced by `to`; sets `missing` when there is none.
std::string replaced(const std::string& text, const std::string& from, const std::string& to,
                     std::string& missing) {
  std::string out = text;
  std::size_t at = 0, count = 0;
  while ((at = out.find(from, at)) != std::string::npos) {
    out.replace(at, from.size(), to);
    at += to.size();
    ++count;
  }
  if (count == 0) missing = "source line not found: " + from;
  return out;
}

const char* const kCorrectlyRounded = " -cl-fp32-correctly-rounded-divide-sqrt";

// The kernel as the product builds it, then each promise relaxed alone, then all together.
std::vector<CastVariant> make_variants(const std::string& options, const std::string& source) {
  std::vector<CastVariant> v;
  v.push_back({"default", options, source, ""});
  v.push_back({"-cl-mad-enable", options + " -cl-mad-enable", source, ""});
  CastVariant contract{"FP_CONTRACT ON", options, "", ""};
  contract.source = replaced(source, "#pragma OPENCL FP_CONTRACT OFF",
                             "#pragma OPENCL FP_CONTRACT ON", contract.missing);
  v.push_back(contract);
  CastVariant rounding{"no correctly rounded div/sqrt", options, source, ""};
  std::string missing_option;
  rounding.options = replaced(options, kCorrectlyRounded, "", missing_option);
  if (!missing_option.empty()) rounding.missing = "the device does not offer it";
  v.push_back(rounding);
  v.push_back({"-cl-fast-relaxed-math", options + " -cl-fast-relaxed-math", source, ""});
  CastVariant exact{"triangles not grown", options, "", ""};
  exact.source = replaced(source, "#define SDF_BARYCENTRIC_SLACK 1e-5f",
                          "#define SDF_BARYCENTRIC_SLACK 0.0f", exact.missing);
  v.push_back(exact);
  // Ties: the first triangle found at the nearest distance wins, and a subtree whose box
  // starts exactly there is no longer visited for a lower id.
  CastVariant ties{"no tie rule", options, "", ""};
  ties.source =
      replaced(source, "t > hit->t || (t == hit->t && id >= hit->id)", "t >= hit->t", ties.missing);
  ties.source = replaced(ties.source, "if (sdf_as_float(stack[sp].y) <= hit.t) break;",
                         "if (sdf_as_float(stack[sp].y) < hit.t) break;", ties.missing);
  v.push_back(ties);
  CastVariant all{"all relaxed", missing_option.empty() ? rounding.options : options, "", ""};
  all.options += " -cl-fast-relaxed-math";
  std::string ignored;
  all.source = replaced(contract.source, "#define SDF_BARYCENTRIC_SLACK 1e-5f",
                        "#define SDF_BARYCENTRIC_SLACK 0.0f", ignored);
  all.source =
      replaced(all.source, "t > hit->t || (t == hit->t && id >= hit->id)", "t >= hit->t", ignored);
  all.source = replaced(all.source, "if (sdf_as_float(stack[sp].y) <= hit.t) break;",
                        "if (sdf_as_float(stack[sp].y) < hit.t) break;", ignored);
  v.push_back(all);
  return v;
}

}  // namespace

struct OurCast::Impl {
  const sdf::cl::Device* device = nullptr;
  sdf::cl::DeviceState* s = nullptr;
  cl_command_queue queue = nullptr;
  sdf::cl::DeviceTree tree;
  std::unique_ptr<Buffer> local_rays, raw, valid;
  sdf::kern::SdfCastParams params{};
  std::vector<cl_program> owned_programs;
  std::vector<std::unique_ptr<Kernel>> kernels;  // per variant; null where it is missing
  cl_program hits_program = nullptr;
  ~Impl() {
    kernels.clear();
    for (cl_program p : owned_programs) sdf::cl::api()->clReleaseProgram(p);
    if (hits_program) sdf::cl::api()->clReleaseProgram(hits_program);
  }
};

OurCast::OurCast(const sdf::cl::Device& device, sdf::cl::DeviceState& s, cl_command_queue queue,
                 const sdf::Mesh& mesh, const sdf::Cone& cone, float tmin)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.device = &device;
  m.s = &s;
  m.queue = queue;
  const std::string options = sdf::cl::build_options(device, cone.rays);
  m.tree = sdf::cl::build_device_tree(device, s, options, mesh);
  tree_seconds = m.tree.build_seconds;
  order_.assign(m.tree.host_order.begin(), m.tree.host_order.end());
  with_area_ = m.tree.with_area;

  std::vector<float> table(4 * std::max<std::size_t>(cone.local.size(), 1), 0.0f);
  for (std::size_t i = 0; i < cone.local.size(); ++i) {
    table[4 * i] = cone.local[i].x;
    table[4 * i + 1] = cone.local[i].y;
    table[4 * i + 2] = cone.local[i].z;
    table[4 * i + 3] = cone.local_angle[i];
  }
  m.local_rays = std::make_unique<Buffer>(s, table.size() * sizeof(float), table.data());
  m.raw =
      std::make_unique<Buffer>(s, std::max<std::size_t>(with_area_, 1) * sizeof(float), nullptr);
  m.valid = std::make_unique<Buffer>(s, std::max<std::size_t>(with_area_, 1) * 4, nullptr);
  m.params.rays = cone.rays;
  m.params.sampling = static_cast<int>(cone.sampling);
  m.params.one_minus_cos_half = cone.one_minus_cos_half;
  m.params.sin_half = cone.sin_half;
  m.params.angle_floor = cone.angle_floor;
  m.params.seed = cone.seed;
  m.params.tmin = tmin;
  m.params.first = 0;
  m.params.count = static_cast<std::uint32_t>(with_area_);

  const std::string source = sdf::cl::kernel_source();
  variants_ = make_variants(options, source);
  for (std::size_t v = 0; v < variants_.size(); ++v) {
    CastVariant& variant = variants_[v];
    cl_program program = nullptr;
    if (v == 0) {
      program = sdf::cl::program_for(device, s, options);  // the product's own
    } else if (variant.missing.empty()) {
      try {
        program =
            sdf::cl::build_program(device, s.context, variant.options, variant.source.c_str());
        m.owned_programs.push_back(program);
      } catch (const sdf::cl::Error& e) {
        variant.missing = std::string("does not build: ") + e.what();
      }
    }
    m.kernels.push_back(program ? std::make_unique<Kernel>(program, "sdf_cast_bvh_per_ray_faces")
                                : nullptr);
  }
  m.hits_program =
      sdf::cl::build_program(device, s.context, options, (source + kRayHitsKernel).c_str());
}

OurCast::~OurCast() = default;

double OurCast::cast_ms(std::size_t v, std::vector<float>* raw) {
  Impl& m = *impl_;
  Kernel& kernel = *m.kernels.at(v);
  // The product's launch (opencl_engine.cpp): points_per_group points of `rays` items each,
  // about 128 items a group, fewer when registers limit the group size.
  const std::size_t rays = static_cast<std::size_t>(m.params.rays);
  const std::size_t points_per_group = std::min(std::max<std::size_t>(1, (128 + rays / 2) / rays),
                                                kernel.max_group(m.device->id) / rays);
  cl_uint a = 0;
  for (cl_mem mem : {m.tree.nodes->get(), m.tree.triangles->get(), m.tree.vertices->get(),
                     m.tree.faces->get(), m.tree.order->get(), m.local_rays->get()})
    kernel.arg(a++, mem);
  kernel.arg(a++, m.params);
  kernel.arg(a++, m.raw->get());
  kernel.arg(a++, m.valid->get());
  kernel.local_arg(a++, 2 * points_per_group * rays * sizeof(float));
  kernel.local_arg(a++, 2 * points_per_group * rays * sizeof(float));
  const std::size_t group = points_per_group * rays;
  const std::size_t global = (with_area_ + points_per_group - 1) / points_per_group * group;
  cl_event event = nullptr;
  sdf::cl::check(sdf::cl::api()->clEnqueueNDRangeKernel(m.queue, kernel.get(), 1, nullptr, &global,
                                                        &group, 0, nullptr, &event),
                 "clEnqueueNDRangeKernel (cast)");
  const double ms = event_ms(event);
  if (raw) {
    raw->resize(with_area_);
    sdf::cl::check(sdf::cl::api()->clEnqueueReadBuffer(m.queue, m.raw->get(), CL_TRUE, 0,
                                                       with_area_ * sizeof(float), raw->data(), 0,
                                                       nullptr, nullptr),
                   "clEnqueueReadBuffer (raw)");
  }
  return ms;
}

void OurCast::ray_hits(std::vector<float>& origins, std::vector<float>& directions,
                       std::vector<float>& t, std::vector<int>& id) {
  Impl& m = *impl_;
  const std::size_t count = with_area_ * static_cast<std::size_t>(m.params.rays);
  Buffer rays_out(*m.s, std::max<std::size_t>(count, 1) * 8 * sizeof(float), nullptr);
  Buffer hits_out(*m.s, std::max<std::size_t>(count, 1) * 2 * sizeof(float), nullptr);
  Kernel kernel(m.hits_program, "bench_face_ray_hits");
  cl_uint a = 0;
  for (cl_mem mem : {m.tree.nodes->get(), m.tree.triangles->get(), m.tree.vertices->get(),
                     m.tree.faces->get(), m.tree.order->get(), m.local_rays->get()})
    kernel.arg(a++, mem);
  kernel.arg(a++, m.params);
  kernel.arg(a++, rays_out.get());
  kernel.arg(a++, hits_out.get());
  const std::size_t global = (count + 63) / 64 * 64;
  sdf::cl::check(sdf::cl::api()->clEnqueueNDRangeKernel(m.queue, kernel.get(), 1, nullptr, &global,
                                                        nullptr, 0, nullptr, nullptr),
                 "clEnqueueNDRangeKernel (ray hits)");
  std::vector<float> rays(8 * count), hits(2 * count);
  sdf::cl::check(sdf::cl::api()->clEnqueueReadBuffer(m.queue, rays_out.get(), CL_TRUE, 0,
                                                     rays.size() * sizeof(float), rays.data(), 0,
                                                     nullptr, nullptr),
                 "clEnqueueReadBuffer (rays)");
  sdf::cl::check(sdf::cl::api()->clEnqueueReadBuffer(m.queue, hits_out.get(), CL_TRUE, 0,
                                                     hits.size() * sizeof(float), hits.data(), 0,
                                                     nullptr, nullptr),
                 "clEnqueueReadBuffer (hits)");
  origins.resize(3 * count);
  directions.resize(3 * count);
  t.resize(count);
  id.resize(count);
  for (std::size_t i = 0; i < count; ++i) {
    for (int k = 0; k < 3; ++k) {
      origins[3 * i + k] = rays[8 * i + k];
      directions[3 * i + k] = rays[8 * i + 4 + k];
    }
    t[i] = hits[2 * i];
    std::memcpy(&id[i], &hits[2 * i + 1], sizeof(int));
  }
}

}  // namespace bench
