// SPDX-License-Identifier: GPL-3.0-or-later
// Benchmark tool, never part of the product: our OpenCL cast against tinybvh's GPU kernel on
// the same SDF rays, in one process on one OpenCL device.
//   tinybvh_compare --tinybvh DIR [--device ENGINE] [--rays N] [--rounds N] MESH.off[:K] ...
// MESH.off:K is the mesh subdivided 1-to-4 K times (as bench/meshes.py makes armadillo-x16).
// Per mesh: the tree our GPU path makes on the device and our cast kernel launched as the
// product launches it; tinybvh's BVH_GPU (built on the host by tiny_bvh.h from DIR) and its
// batch_ailalaine kernel (traverse.cl from DIR, tinyocl's build options) on the very rays our
// kernel casts; and our kernel compiled with one promise relaxed at a time. Kernel times are
// the device's profiling clock, the best of the rounds, the kernels taking turns in each.
// Prints a Markdown table of the times, one of the variants, and the hit comparison.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

#include "cl_bench.h"
#include "off_mesh.h"
#include "our_cast.h"
#include "prepare/sampling.h"
#include "prepare/unit_scale.h"
#include "tinybvh_cast.h"

namespace {

struct Args {
  std::string tinybvh, engine = "opencl";
  int rays = 30, rounds = 5;
  std::vector<std::string> meshes;
};

Args parse_args(int argc, char** argv) {
  Args a;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw std::invalid_argument(arg + " needs a value");
      return argv[++i];
    };
    if (arg == "--tinybvh")
      a.tinybvh = value();
    else if (arg == "--device")
      a.engine = value();
    else if (arg == "--rays")
      a.rays = std::stoi(value());
    else if (arg == "--rounds")
      a.rounds = std::stoi(value());
    else
      a.meshes.push_back(arg);
  }
  if (a.tinybvh.empty() || a.meshes.empty() || a.rays < 1 || a.rounds < 1)
    throw std::invalid_argument(
        "usage: tinybvh_compare --tinybvh DIR [--device ENGINE] [--rays N] [--rounds N] "
        "MESH.off[:SUBDIVISIONS] ...");
  return a;
}

// The mesh as compute() casts it: centred (make_mesh), scaled by a power of two when far from
// unit size (unit_scale.h). `name` gets the subdivision's face factor, e.g. armadillo-x16.
sdf::Mesh load_mesh(const std::string& spec, std::string& name) {
  const std::size_t colon = spec.rfind(':');
  const std::string path = colon == std::string::npos ? spec : spec.substr(0, colon);
  const int times = colon == std::string::npos ? 0 : std::stoi(spec.substr(colon + 1));
  bench::OffMesh off = bench::read_off_mesh(path);
  for (int k = 0; k < times; ++k) off = bench::subdivide(off);
  const std::size_t slash = path.find_last_of('/');
  name = path.substr(slash == std::string::npos ? 0 : slash + 1);
  name = name.substr(0, name.rfind('.'));
  if (times > 0) name += "-x" + std::to_string(1 << (2 * times));
  sdf::Mesh mesh = bench::core_mesh(off);
  const int exponent = sdf::unit_scale_exponent(mesh.max_extent);
  if (exponent != 0) sdf::scale_mesh(mesh, exponent, 0);
  return mesh;
}

// The rays of the faces cast, in cast order, made on the host by the core's own sampling
// (sample_points) and ray set (cone_rays): origins and directions, 3 floats a ray.
void host_rays(const sdf::Mesh& mesh, const std::vector<std::uint32_t>& order,
               std::size_t with_area, const sdf::Cone& cone, std::vector<float>& origins,
               std::vector<float>& directions) {
  const sdf::SamplePoints points = sdf::sample_points(mesh, sdf::PointKind::Faces);
  const std::size_t rays = static_cast<std::size_t>(cone.rays);
  origins.resize(3 * with_area * rays);
  directions.resize(3 * with_area * rays);
  std::vector<glm::vec3> d(rays);
  std::vector<float> angles(rays);
  for (std::size_t i = 0; i < with_area; ++i) {
    const std::uint32_t p = order[i];
    sdf::cone_rays(cone, points.axes[p], points.tangents[p], p, d.data(), angles.data());
    for (std::size_t r = 0; r < rays; ++r) {
      const std::size_t k = 3 * (i * rays + r);
      for (int c = 0; c < 3; ++c) {
        origins[k + c] = points.origins[p][c];
        directions[k + c] = d[r][c];
      }
    }
  }
}

// Rays whose origin or direction differ in any bit between two sets.
std::size_t rays_differing(const std::vector<float>& o1, const std::vector<float>& d1,
                           const std::vector<float>& o2, const std::vector<float>& d2) {
  std::size_t differ = 0;
  for (std::size_t i = 0; i < o1.size() / 3; ++i)
    differ += std::memcmp(&o1[3 * i], &o2[3 * i], 12) != 0 ||
              std::memcmp(&d1[3 * i], &d2[3 * i], 12) != 0;
  return differ;
}

// How our nearest hits compare with tinybvh's on the same rays. tinybvh's distances are from
// the origin moved tmin along the ray, so tmin is added back. `tolerance`: see the caller.
struct HitAgreement {
  std::size_t rays = 0, same = 0, same_distance = 0, both_miss = 0;
  std::size_t ours_only = 0, theirs_only = 0;  // rays that one side hits and the other misses
  double worst_same = 0.0;  // the largest distance difference on the same triangle
};

HitAgreement compare_hits(const std::vector<float>& our_t, const std::vector<int>& our_id,
                          const std::vector<float>& their_t, const std::vector<int>& their_id,
                          float tmin, float tolerance) {
  HitAgreement h;
  h.rays = our_t.size();
  for (std::size_t i = 0; i < h.rays; ++i) {
    const bool our_miss = our_t[i] == INFINITY, their_miss = their_t[i] >= 1e30f;
    if (our_miss || their_miss) {
      h.both_miss += our_miss && their_miss;
      h.ours_only += their_miss && !our_miss;
      h.theirs_only += our_miss && !their_miss;
      continue;
    }
    const double diff = std::fabs(double(our_t[i]) - (double(their_t[i]) + tmin));
    if (diff > tolerance) continue;
    ++h.same_distance;
    if (our_id[i] == their_id[i]) {
      ++h.same;
      h.worst_same = std::max(h.worst_same, diff);
    }
  }
  return h;
}

struct VariantResult {
  std::string name, missing;
  double ms = 0.0;
  std::size_t changed = 0;  // faces whose value differs in any bit from the default's
};

struct MeshResult {
  std::string name;
  std::size_t faces = 0, rays = 0, rays_differing = 0;
  double ours_ms = 1e300, tinybvh_ms = 1e300, tree_s = 0.0, tinybvh_build_s = 0.0;
  HitAgreement hits;
  float tolerance = 0.0f;
  std::vector<VariantResult> variants;
};

MeshResult run_mesh(const sdf::cl::Device& device, sdf::cl::DeviceState& s, cl_command_queue queue,
                    const Args& args, const std::string& spec) {
  MeshResult res;
  const sdf::Mesh mesh = load_mesh(spec, res.name);
  res.faces = mesh.triangles.size();
  const sdf::Cone cone = sdf::make_cone(args.rays, 120.0, sdf::Sampling::Fibonacci, 0);
  const float tmin = sdf::minimum_closeness(mesh);
  std::fprintf(stderr, "%s: %zu faces; building our tree and compiling our kernels\n",
               res.name.c_str(), res.faces);
  bench::OurCast ours(device, s, queue, mesh, cone, tmin);
  res.tree_s = ours.tree_seconds;
  std::vector<float> origins, directions, dev_origins, dev_directions, our_t, their_t;
  std::vector<int> our_id, their_id;
  host_rays(mesh, ours.order(), ours.with_area(), cone, origins, directions);
  ours.ray_hits(dev_origins, dev_directions, our_t, our_id);
  res.rays = our_t.size();
  res.rays_differing = rays_differing(origins, directions, dev_origins, dev_directions);

  // tinybvh's rays: the same, their origins moved tmin along the ray, so that its t > 0 is
  // our t > tmin (and the face a ray starts on lies behind it, as our own-face skip has it).
  std::vector<float> moved(origins.size());
  for (std::size_t i = 0; i < moved.size(); ++i) moved[i] = origins[i] + tmin * directions[i];
  std::vector<float> corners(9 * mesh.triangles.size());
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f)
    for (int c = 0; c < 3; ++c)
      for (int k = 0; k < 3; ++k)
        corners[9 * f + 3 * c + k] = mesh.vertices[mesh.triangles[f][c]][k];
  std::fprintf(stderr, "%s: building tinybvh's BVH_GPU and compiling its kernel\n",
               res.name.c_str());
  bench::TinybvhCast theirs(device, s, queue, args.tinybvh, corners, moved, directions);
  res.tinybvh_build_s = theirs.build_seconds;

  // Each kernel once before the clock (first launches pay for loading), then the rounds.
  std::vector<float> raw_default, raw;
  ours.cast_ms(0, &raw_default);
  theirs.cast_ms();
  const auto& variants = ours.variants();
  res.variants.resize(variants.size());
  for (std::size_t v = 0; v < variants.size(); ++v) {
    VariantResult& out = res.variants[v];
    out.name = variants[v].name;
    out.missing = variants[v].missing;
    out.ms = 1e300;
    if (!out.missing.empty()) continue;
    ours.cast_ms(v, &raw);
    for (std::size_t i = 0; i < raw.size(); ++i)
      out.changed += std::memcmp(&raw[i], &raw_default[i], sizeof(float)) != 0;
  }
  for (int round = 0; round < args.rounds; ++round) {
    res.ours_ms = std::min(res.ours_ms, ours.cast_ms(0));
    res.tinybvh_ms = std::min(res.tinybvh_ms, theirs.cast_ms());
    for (std::size_t v = 1; v < variants.size(); ++v)
      if (res.variants[v].missing.empty())
        res.variants[v].ms = std::min(res.variants[v].ms, ours.cast_ms(v));
  }
  res.variants[0].ms = res.ours_ms;
  theirs.hits(their_t, their_id);
  // Half the shortest distance either side keeps: a few tens of float32 roundings of the
  // mesh's size (tmin is 2e-5 of it), far more than the two intersection formulas' rounding
  // differences, far less than any distance the SDF tells apart.
  res.tolerance = tmin / 2;
  res.hits = compare_hits(our_t, our_id, their_t, their_id, tmin, res.tolerance);
  return res;
}

double percent(std::size_t part, std::size_t whole) {
  return whole ? 100.0 * static_cast<double>(part) / static_cast<double>(whole) : 0.0;
}

void print_tables(const std::vector<MeshResult>& results) {
  std::printf(
      "\n| mesh | faces | rays | ours ms | tinybvh ms | ours / tinybvh | "
      "Grays/s ours | Grays/s tinybvh | same hit | same distance | both miss |\n"
      "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  for (const MeshResult& r : results)
    std::printf(
        "| %s | %zu | %zu | %.2f | %.2f | %.3f | %.3f | %.3f | %.4f%% | %.4f%% | "
        "%.4f%% |\n",
        r.name.c_str(), r.faces, r.rays, r.ours_ms, r.tinybvh_ms, r.ours_ms / r.tinybvh_ms,
        r.rays / r.ours_ms * 1e-6, r.rays / r.tinybvh_ms * 1e-6, percent(r.hits.same, r.hits.rays),
        percent(r.hits.same_distance, r.hits.rays), percent(r.hits.both_miss, r.hits.rays));
  std::printf(
      "\nOur kernel with one promise relaxed at a time (values: faces whose value "
      "changes in any bit against the default's):\n\n"
      "| mesh | variant | ms | / default | values changed |\n|---|---|---:|---:|---:|\n");
  for (const MeshResult& r : results)
    for (const VariantResult& v : r.variants) {
      if (!v.missing.empty()) {
        std::printf("| %s | %s | n/a: %s | | |\n", r.name.c_str(), v.name.c_str(),
                    v.missing.substr(0, 120).c_str());
        continue;
      }
      std::printf("| %s | %s | %.2f | %.3f | %.4f%% |\n", r.name.c_str(), v.name.c_str(), v.ms,
                  v.ms / r.ours_ms, percent(v.changed, r.faces));
    }
  std::printf(
      "\nChecks: rays our kernel makes that differ in any bit from the host's (the rays "
      "given to tinybvh); same hit: equal triangle and distances within the tolerance; "
      "the largest distance difference on the same triangle.\n\n"
      "| mesh | rays differing | tolerance | largest difference | hit by ours only | "
      "by tinybvh only | our tree s (device) | tinybvh build s (host) |\n"
      "|---|---:|---:|---:|---:|---:|---:|---:|\n");
  for (const MeshResult& r : results)
    std::printf("| %s | %zu | %.3g | %.3g | %zu | %zu | %.3f | %.3f |\n", r.name.c_str(),
                r.rays_differing, r.tolerance, r.hits.worst_same, r.hits.ours_only,
                r.hits.theirs_only, r.tree_s, r.tinybvh_build_s);
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const Args args = parse_args(argc, argv);
    const sdf::cl::Device& device = *sdf::cl::select_devices(args.engine).front();
    sdf::cl::DeviceState& s = sdf::cl::state_of(device);
    cl_command_queue queue = bench::profiling_queue(device, s.context);
    std::printf(
        "device: %s (%s, driver %s); %d rays a face, 120-degree cone, Fibonacci; best "
        "of %d rounds\n",
        device.name.c_str(), device.platform_name.c_str(), device.driver_version.c_str(), args.rays,
        args.rounds);
    std::vector<MeshResult> results;
    for (const std::string& spec : args.meshes) {
      results.push_back(run_mesh(device, s, queue, args, spec));
      print_tables({results.back()});
      std::fflush(stdout);
    }
    if (results.size() > 1) print_tables(results);
    sdf::cl::api()->clReleaseCommandQueue(queue);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "tinybvh_compare: %s\n", e.what());
    return 1;
  }
  return 0;
}
