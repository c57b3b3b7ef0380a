// SPDX-License-Identifier: GPL-3.0-or-later
// Benchmark tool, never part of the product: casts one mesh (faces, 30 Fibonacci rays, 120°,
// orientation as given, the SAH tree) with the CPU engine, the OpenCL engine's per-ray kernel
// and CUDA builds of the same kernel (cast_kernels.cu), checks that every result has the CPU
// engine's bits, and times the GPU casts. Made for profiling: Nsight Compute sees the CUDA
// kernels. Usage:
//   cuda_cast MESH.bin all [VARIANT,VARIANT,...] [REPS]   everything, a table at the end
//   cuda_cast MESH.bin opencl                             one OpenCL cast (for ncu to try)
//   cuda_cast MESH.bin cuda VARIANT [REPS]               CUDA only (for ncu)
// MESH.bin: int64 vertex count, int64 face count, float64 vertices (n,3), int64 faces (m,3).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "bvh.h"
#include "bvh8.h"
#include "bvh_margin.h"
#include "cpu_engine.h"
#include "mesh.h"
#include "opencl/devices.h"
#include "opencl/opencl_engine.h"
#include "rays.h"
#include "sampling.h"

#include "cast_kernels.h"

namespace {

double now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

sdf::Mesh read_mesh(const char* path) {
  std::ifstream in(path, std::ios::binary);
  std::int64_t nv = 0, nf = 0;
  in.read(reinterpret_cast<char*>(&nv), 8);
  in.read(reinterpret_cast<char*>(&nf), 8);
  std::vector<double> v(3 * nv);
  std::vector<std::int64_t> f(3 * nf);
  in.read(reinterpret_cast<char*>(v.data()), v.size() * 8);
  in.read(reinterpret_cast<char*>(f.data()), f.size() * 8);
  if (!in) {
    std::fprintf(stderr, "cannot read %s\n", path);
    std::exit(2);
  }
  return sdf::make_mesh(v.data(), nv, f.data(), nf);
}

struct Values {
  std::vector<float> raw;
  std::vector<std::int32_t> valid;
};

// Mismatches against the reference (bits of raw, and valid counts).
std::size_t mismatches(const Values& ref, const Values& got) {
  std::size_t bad = 0;
  for (std::size_t i = 0; i < ref.raw.size(); ++i) {
    if (ref.valid[i] != got.valid[i] ||
        std::memcmp(&ref.raw[i], &got.raw[i], sizeof(float)) != 0)
      ++bad;
  }
  return bad;
}

std::vector<std::string> split(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ',')) out.push_back(item);
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: cuda_cast MESH.bin all|opencl|cuda [VARIANTS] [REPS]\n");
    return 2;
  }
  const std::string mode = argv[2];
  double t0 = now();
  const sdf::Mesh mesh = read_mesh(argv[1]);
  const sdf::SamplePoints points = sdf::sample_points(mesh, sdf::PointKind::Faces);
  const std::vector<std::uint32_t> order = sdf::spatial_order(points);
  const sdf::Cone cone = sdf::make_cone(30, 120.0, sdf::Sampling::Fibonacci, 0);
  const float tmin = sdf::minimum_closeness(mesh);
  sdf::Bvh bvh = sdf::build_bvh(mesh, sdf::BvhConfig());  // SAH everywhere ('high')
  sdf::grow_boxes_to_cover_hits(bvh);
  const std::size_t n = points.size();
  std::printf("mesh %s: %zu faces, %zu points, %zu nodes (%.1f MiB), %zu triangles (%.1f MiB), "
              "depth %d; prepared in %.2f s\n",
              argv[1], mesh.triangles.size(), n, bvh.nodes.size(),
              bvh.nodes.size() * 32 / 1048576.0, bvh.triangles.size(),
              bvh.triangles.size() * 48 / 1048576.0, sdf::bvh_depth(bvh), now() - t0);

  Values ref;
  if (mode == "all") {
    t0 = now();
    const sdf::Bvh8 wide8 = sdf::collapse_to_bvh8(bvh);
    sdf::CpuScene scene8;
    scene8.bvh8 = &wide8;
    ref.raw.resize(n);
    ref.valid.resize(n);
    sdf::cast_cpu(scene8, points, order, cone, tmin, 0, ref.raw.data(), ref.valid.data(),
                  nullptr, 0.0, 1.0);
    std::printf("cpu engine: %.3f s\n", now() - t0);
  }

  std::vector<std::string> table;
  if (mode == "all" || mode == "opencl") {
    setenv("SDF_OPENCL_KERNEL", "bvh_per_ray", 1);
    const std::vector<const sdf::cl::Device*> devices = sdf::cl::select_devices("opencl");
    sdf::cl::Scene scene;
    scene.bvh = &bvh;
    sdf::cl::CastInput input;
    input.scene = [&] { return scene; };
    input.points = &points;
    input.order = order.data();
    input.size = n;
    const int runs = mode == "all" ? 3 : 1;
    double best = 1e30;
    Values cl;
    cl.raw.resize(n);
    cl.valid.resize(n);
    for (int r = 0; r < runs; ++r) {
      const sdf::cl::CastTimings t =
          sdf::cl::cast_opencl(devices, input, cone, tmin, 0, cl.raw.data(),
                               cl.valid.data(), nullptr, 0.0, 1.0);
      best = std::min(best, t.cast);
    }
    char line[256];
    std::snprintf(line, sizeof line, "%-14s %8.2f ms  %6.0f Mrays/s  mismatches vs cpu: %s",
                  "opencl", best * 1e3, n * 30 / best / 1e6,
                  ref.raw.empty() ? "-" : std::to_string(mismatches(ref, cl)).c_str());
    std::printf("%s (%s)\n", line, devices[0]->name.c_str());
    table.push_back(line);
  }

  if (mode == "all" || mode == "cuda") {
    std::vector<float> origins(3 * n), axes(3 * n), tangents(3 * n), rays(4 * cone.rays);
    for (std::size_t i = 0; i < n; ++i)
      for (int k = 0; k < 3; ++k) {
        origins[3 * i + k] = points.origins[i][k];
        axes[3 * i + k] = points.axes[i][k];
        tangents[3 * i + k] = points.tangents[i][k];
      }
    for (int i = 0; i < cone.rays; ++i) {
      rays[4 * i] = cone.local[i].x;
      rays[4 * i + 1] = cone.local[i].y;
      rays[4 * i + 2] = cone.local[i].z;
      rays[4 * i + 3] = cone.local_angle[i];
    }
    CudaScene s;
    s.nodes = bvh.nodes.data();
    s.node_bytes = bvh.nodes.size() * sizeof(bvh.nodes[0]);
    s.tris = bvh.triangles.data();
    s.tri_bytes = bvh.triangles.size() * sizeof(bvh.triangles[0]);
    s.origins = origins.data();
    s.axes = axes.data();
    s.tangents = tangents.data();
    s.own_face = points.own_face.data();
    s.order = order.data();
    s.points = n;
    s.ray_table = rays.data();
    s.rays = cone.rays;
    s.sampling = static_cast<int>(cone.sampling);
    s.one_minus_cos_half = cone.one_minus_cos_half;
    s.sin_half = cone.sin_half;
    s.angle_floor = cone.angle_floor;
    s.seed = cone.seed;
    s.tmin = tmin;
    std::printf("CUDA variants:\n");
    cuda_print_attributes();
    std::vector<std::string> variants =
        argc > 3 ? split(argv[3]) : cuda_variant_names();
    const int reps = argc > 4 ? std::atoi(argv[4]) : (mode == "all" ? 5 : 1);
    // Two passes over the variants, alternating, so drift hits them alike.
    const int passes = mode == "all" ? 2 : 1;
    std::vector<float> best(variants.size(), 1e30f);
    std::vector<std::string> check(variants.size());
    std::vector<CudaResult> last(variants.size());
    for (int pass = 0; pass < passes; ++pass) {
      for (std::size_t v = 0; v < variants.size(); ++v) {
        CudaResult r = cuda_cast(s, variants[v], reps);
        best[v] = std::min(best[v], r.ms_median);
        Values got;
        got.raw.resize(n);
        got.valid.resize(n);
        for (std::size_t i = 0; i < n; ++i) {  // launch order back to point order
          got.raw[order[i]] = r.raw[i];
          got.valid[order[i]] = r.valid[i];
        }
        check[v] = ref.raw.empty() ? "-" : std::to_string(mismatches(ref, got));
        if (r.counters[4]) {
          const double rays_cast = static_cast<double>(r.counters[4]);
          std::printf("  %s: per ray %.2f inner visits, %.2f leaf visits, %.2f triangle tests, "
                      "%.2f pushes (%llu rays)\n",
                      variants[v].c_str(), r.counters[0] / rays_cast, r.counters[1] / rays_cast,
                      r.counters[2] / rays_cast, r.counters[3] / rays_cast, r.counters[4]);
        }
      }
    }
    for (std::size_t v = 0; v < variants.size(); ++v) {
      char line[256];
      std::snprintf(line, sizeof line,
                    "cuda %-9s %8.2f ms  %6.0f Mrays/s  mismatches vs cpu: %s",
                    variants[v].c_str(), best[v], n * 30 / (best[v] * 1e-3) / 1e6,
                    check[v].c_str());
      table.push_back(line);
    }
  }
  std::printf("\n== %s, %zu faces x 30 rays (best median of the passes)\n", argv[1], n);
  for (const std::string& line : table) std::printf("%s\n", line.c_str());
  return 0;
}
