// SPDX-License-Identifier: GPL-3.0-or-later
#include "sdf.h"

#include <stdexcept>

#include "bvh.h"
#include "bvh4.h"
#include "bvh8.h"
#include "bvh_margin.h"
#include "cpu_engine.h"
#include "stopwatch.h"
#ifdef SDF_HAVE_OPENCL
#include "opencl/opencl_engine.h"
#endif

namespace sdf {

namespace {

void report(const ProgressFn& progress, double fraction) {
  if (progress && !progress(fraction)) throw Cancelled();
}

const char* accel_name(Accel a) { return a == Accel::Bvh ? "bvh" : "octree"; }

// The acceleration structure options.accel asks for: the binary BVH (boxes grown so that no
// engine prunes a hit, see bvh_margin.h) and its collapses in `widths`, or the octree. The
// 4-wide tree points at the binary tree's triangles, so a Structures never moves; the 8-wide
// one copies them, and the binary tree is then freed unless a caster reads it.
struct Structures {
  Bvh bvh;
  Bvh4 wide4;
  Bvh8 wide8;
  Octree tree;
};

// BvhQuality::Fast's threshold: 256 to 16384 measured within 2% of each other end to end on
// the H100 (1024: 178 ms; 64: 199 ms, little faster to build than SAH everywhere).
constexpr std::size_t kFastMortonBelow = 1024;

void build_structures(const Mesh& mesh, const Options& options, BvhWidths widths,
                      bool fast_build, Structures& s) {
  if (options.accel == Accel::Bvh) {
    BvhConfig config;
    config.threads = options.threads;
    config.morton_below = fast_build ? kFastMortonBelow : 0;
    s.bvh = build_bvh(mesh, config);
    grow_boxes_to_cover_hits(s.bvh, options.threads);
    if (widths.four) s.wide4 = collapse_to_bvh4(s.bvh);
    if (widths.eight) s.wide8 = collapse_to_bvh8(s.bvh);
    if (widths.eight && !widths.binary && !widths.four) s.bvh = Bvh();
  } else {
    s.tree = build_octree(mesh, options.octree);
  }
}

// Casting and reducing are fused per point: the lengths never leave the cache (CPU) or the
// registers (OpenCL).
void cast_on_cpu(const Mesh& mesh, const Options& options, const SamplePoints& points,
                 const std::vector<std::uint32_t>& order, const Cone& cone, Output& out,
                 Stopwatch& clock, const ProgressFn& progress) {
  // The 8-wide tree needs AVX2 (chosen at run time); without it the 4-wide SSE tree.
  Structures built;
  BvhWidths widths;
  widths.eight = bvh8_supported();
  widths.four = !widths.eight;
  build_structures(mesh, options, widths, options.bvh_quality == BvhQuality::Fast, built);
  CpuScene scene;
  if (options.accel == Accel::Bvh) {
    if (widths.eight) {
      scene.bvh8 = &built.wide8;
    } else {
      scene.bvh4 = &built.wide4;
    }
  } else {
    scene.octree = &built.tree;
  }
  out.timings.emplace_back("build", clock.lap());
  report(progress, 0.05);
  cast_cpu(scene, points, order, cone, minimum_closeness(mesh), options.threads, out.raw.data(),
           out.valid_rays.data(), progress, 0.05, 0.99);
  out.timings.emplace_back("cast", clock.lap());
  out.engine = "cpu (" + std::to_string(resolve_threads(options.threads)) + " threads, " +
               accel_name(options.accel) + ")";
}

#ifdef SDF_HAVE_OPENCL
void cast_on_opencl(const Mesh& mesh, const Options& options, const SamplePoints& points,
                    const std::vector<std::uint32_t>& order, const Cone& cone, Output& out,
                    Stopwatch& clock, const ProgressFn& progress, const BesideCast& beside_cast) {
  const std::vector<const cl::Device*> devices = cl::select_devices(options.engine);
  const BvhWidths wanted = cl::wanted_bvhs(devices);
  bool fast_build = options.bvh_quality == BvhQuality::Fast;
  if (options.bvh_quality == BvhQuality::Auto) {
    fast_build = options.rays <= 64;
    for (const cl::Device* d : devices) fast_build = fast_build && d->gpu;
  }
  Structures built;
  build_structures(mesh, options, wanted, fast_build, built);
  cl::Scene scene;
  if (options.accel == Accel::Bvh) {
    scene.bvh = wanted.binary ? &built.bvh : nullptr;
    scene.bvh4 = wanted.four ? &built.wide4 : nullptr;
    scene.bvh8 = wanted.eight ? &built.wide8 : nullptr;
  } else {
    scene.octree = &built.tree;
  }
  out.timings.emplace_back("build", clock.lap());
  report(progress, 0.05);
  const cl::CastTimings t = cl::cast_opencl(
      devices, scene, points, order, cone, minimum_closeness(mesh), options.threads,
      out.raw.data(), out.valid_rays.data(), progress, 0.05, 0.99, beside_cast);
  const double total = clock.lap();
  // Compile (or cache load) and set-up are what the three device stages leave of the total.
  out.timings.emplace_back("setup", std::max(0.0, total - t.upload - t.cast - t.download));
  out.timings.emplace_back("upload", t.upload);
  out.timings.emplace_back("cast", t.cast);
  out.timings.emplace_back("download", t.download);
  out.device_bytes = t.device_bytes;
  out.engine.clear();
  for (const cl::Device* d : devices)
    out.engine += (out.engine.empty() ? "" : " + ") + std::string("opencl:") +
                  std::to_string(d->index) + " " + d->name;
  out.engine += std::string(" (") + accel_name(options.accel) + ")";
}
#endif

}  // namespace

bool opencl_built() {
#ifdef SDF_HAVE_OPENCL
  return true;
#else
  return false;
#endif
}

Output compute(Mesh mesh, const Options& options, const ProgressFn& progress,
               const BesideCast& beside_cast) {
  const Cone cone = make_cone(options.rays, options.cone_angle, options.sampling, options.seed);
  const bool cpu = options.engine == "cpu";
  if (!cpu && options.engine.compare(0, 6, "opencl") != 0)
    throw std::invalid_argument("unknown engine '" + options.engine + "'");
#ifndef SDF_HAVE_OPENCL
  if (!cpu) throw std::invalid_argument("this build of shape_diameter has no OpenCL engine");
#endif
  Output out;
  Stopwatch clock;
  report(progress, 0.0);
  // `mesh` is the computation's own copy, wound outward; the caller's mesh is never changed.
  out.orientation = orient(mesh, options.orientation, options.threads);
  const SamplePoints points = sample_points(mesh, options.points, options.threads);
  const std::vector<std::uint32_t> order = spatial_order(points, options.threads);
  out.raw.resize(points.size());
  out.valid_rays.resize(points.size());
  out.timings.emplace_back("prepare", clock.lap());

  // The hook's own time: a stage of its own after the CPU engine's cast; on OpenCL within the
  // cast's (part of no other stage's time).
  double beside_seconds = 0.0;
  BesideCast timed_beside_cast;
  if (beside_cast)
    timed_beside_cast = [&] {
      Stopwatch beside;
      beside_cast();
      beside_seconds = beside.lap();
    };
  if (cpu) {
    cast_on_cpu(mesh, options, points, order, cone, out, clock, progress);
    if (timed_beside_cast) {
      timed_beside_cast();
      clock.lap();
    }
  } else {
#ifdef SDF_HAVE_OPENCL
    cast_on_opencl(mesh, options, points, order, cone, out, clock, progress, timed_beside_cast);
#endif
  }
  if (beside_cast) out.timings.emplace_back("beside cast", beside_seconds);

  out.fill = fill_missing(mesh, options.points, out.raw.data(), out.valid_rays.data());
  out.timings.emplace_back("fill", clock.lap());
  report(progress, 1.0);
  return out;
}

}  // namespace sdf
