// SPDX-License-Identifier: GPL-3.0-or-later
#include "pipeline/sdf.h"

#include <atomic>
#include <future>
#include <memory>
#include <stdexcept>
#include <system_error>
#include <tuple>

#include "accel/bvh.h"
#include "accel/bvh4.h"
#include "accel/bvh8.h"
#include "accel/bvh_margin.h"
#include "accel/scene.h"
#include "cast/cpu_engine.h"
#include "prepare/orientation.h"
#include "prepare/unit_scale.h"
#include "util/stopwatch.h"
#ifdef SDF_HAVE_OPENCL
#include "opencl/device_tree.h"
#include "opencl/opencl_engine.h"
#endif

namespace sdf {

namespace {

void report(const ProgressFn& progress, double fraction) {
  if (progress && !progress(fraction)) throw Cancelled();
}

const char* accel_name(Accel a) { return a == Accel::Bvh ? "bvh" : "octree"; }

// BvhQuality::Fast's threshold: 256 to 16384 measured within 2% of each other end to end on
// the H100 (1024: 178 ms; 64: 199 ms, little faster to build than SAH everywhere).
constexpr std::size_t kFastMortonBelow = 1024;

// What a run builds and where it casts, settled before anything is built.
struct Plan {
#ifdef SDF_HAVE_OPENCL
  std::vector<const cl::Device*> devices;
#endif
  BvhWidths widths;  // the BVH casters read (accel 'bvh')
  bool fast_build = false;
  // Triangles per leaf of the host's binary tree: 1 where only GPUs casting a ray per work
  // item read it (H100, 1.21M faces, cast with leaves of 1 / 4: 'fast' tree 37.0 / 45.4 ms,
  // SAH 33.6 / 35.3); BvhConfig's default for the CPU's wide trees, whose leaves are packets.
  int max_leaf_size = BvhConfig{}.max_leaf_size;
  // The BVH made on the device, the cast making the faces' points (opencl/device_tree.h); the
  // host only orients the mesh, beside the cast.
  bool tree_on_device = false;
};

Plan make_plan(const Options& options, [[maybe_unused]] std::size_t faces) {
  Plan plan;
  plan.fast_build = options.bvh_quality == BvhQuality::Fast;
  if (options.engine == "cpu") {
    plan.widths = cpu_bvh_width();  // 8-wide with AVX2, 4-wide with SSE, else binary
    return plan;
  }
#ifdef SDF_HAVE_OPENCL
  plan.devices = cl::select_devices(options.engine);
  plan.widths = cl::wanted_bvhs(plan.devices);
  if (options.bvh_quality == BvhQuality::Auto) {
    plan.fast_build = options.rays <= 64;
    for (const cl::Device* d : plan.devices) plan.fast_build = plan.fast_build && d->gpu;
  }
  // Where the fast tree is wanted on GPUs that cast the binary tree a ray per work item: the
  // device's tree (the faces' Morton sort, Karras's tree, boxes bottom up) takes a few
  // milliseconds there, and the host is left with the orientation.
  bool per_ray_gpus = true, make_trees = true;
  for (const cl::Device* d : plan.devices) {
    per_ray_gpus = per_ray_gpus && d->gpu && cl::cast_kernel_for(*d) == cl::CastKernel::BvhPerRay;
    make_trees = make_trees && cl::makes_trees(*d);
  }
  if (per_ray_gpus) plan.max_leaf_size = 1;
  plan.tree_on_device = options.accel == Accel::Bvh && options.points == PointKind::Faces &&
                        faces <= cl::kDeviceTreeMaxFaces &&
                        cl::tree_on_device(plan.fast_build && per_ray_gpus && make_trees);
#endif
  return plan;
}

// The binary BVH, built on a thread of its own while the calling thread orients the mesh and
// samples its points, when the run may use every core (each stage runs on all of them;
// together they keep the cores busier than one after the other: on the H100 machine's 16
// cores, 1.21M faces, 182 -> 172 ms end to end). A tree depends on positions alone:
// reversing a face swaps two of its corners, which leaves its box (build_bvh makes a zero
// corner +0) and its zero-area test unchanged (nothing in the core is contracted into fused
// multiply-adds), so the tree built from the mesh before orientation is the tree built after
// it, and rewrite_triangles() then makes its records those of the oriented mesh: the same
// bits as building afterwards. Orientation changes the computation's mesh in place, so the
// build reads a copy of it unless orientation is 'as_is'.
class BackgroundBvh {
 public:
  // beside: build on a thread of its own; false: in finish(), after orientation (a caller
  // that set a thread count gets no more threads than it asked for).
  BackgroundBvh(const Mesh& mesh, const Options& options, const Plan& plan, bool beside) {
    BvhConfig config;
    config.threads = options.threads;
    config.morton_below = plan.fast_build ? kFastMortonBelow : 0;
    config.max_leaf_size = plan.max_leaf_size;
    config_ = config;
    if (!beside) {
      deferred_ = true;
      return;
    }
    if (options.orientation != Orientation::AsIs)
      copy_ = std::make_unique<Mesh>(copy_mesh(mesh, options.threads));
    const Mesh* source = copy_ ? copy_.get() : &mesh;
    try {
      build_ = std::async(std::launch::async, [source, config] {
        Stopwatch clock;
        Bvh bvh = build_bvh(*source, config);
        return std::make_pair(std::move(bvh), clock.lap());
      });
    } catch (const std::system_error&) {
      deferred_ = true;  // no thread to be had: built in finish() instead
      copy_.reset();
    }
  }

  // The tree with the records of `oriented`, and the seconds its build took.
  std::pair<Bvh, double> finish(const Mesh& oriented, bool turned, unsigned threads) {
    if (deferred_) {
      Stopwatch clock;
      Bvh bvh = build_bvh(oriented, config_);
      return {std::move(bvh), clock.lap()};
    }
    std::pair<Bvh, double> built = build_.get();
    copy_.reset();
    if (turned) {
      Stopwatch clock;
      rewrite_triangles(built.first, oriented, threads);
      built.second += clock.lap();
    }
    return built;
  }

 private:
  std::unique_ptr<Mesh> copy_;
  std::future<std::pair<Bvh, double>> build_;  // waits in its destructor if never finished
  BvhConfig config_;
  bool deferred_ = false;
};

// Completes the scene once the mesh is oriented: the binary BVH (boxes grown so that no engine
// prunes a hit, see bvh_margin.h) and its collapses in plan.widths, the binary tree freed
// unless a caster reads it (the 4-wide tree reads its triangles); or the octree. Adds the
// build's own time to out.timings as 'build' (the background part ran beside 'prepare'), and
// the time this call took as 'build wait': what the build added to the wall time.
void finish_scene(const Mesh& mesh, const Options& options, const Plan& plan,
                  std::unique_ptr<BackgroundBvh>& background, bool turned, Scene& s, Output& out) {
  Stopwatch clock, wait;
  double seconds = 0.0;
  if (options.accel == Accel::Bvh) {
    std::tie(s.bvh, seconds) = background->finish(mesh, turned, options.threads);
    background.reset();
    clock.lap();  // the wait for the background build is not the build's time
    grow_boxes_to_cover_hits(s.bvh, options.threads);
    if (plan.widths.four) s.bvh4 = collapse_to_bvh4(s.bvh);
    if (plan.widths.eight) s.bvh8 = collapse_to_bvh8(s.bvh);
    if (plan.widths.eight && !plan.widths.binary && !plan.widths.four) s.bvh = Bvh();
    s.widths = plan.widths;
  } else {
    s.octree = build_octree(mesh, options.octree);
    s.has_octree = true;
  }
  out.timings.emplace_back("build", seconds + clock.lap());
  out.timings.emplace_back("build wait", wait.lap());
}

// Casting and reducing are fused per point: the lengths never leave the cache (CPU) or the
// registers (OpenCL).
void cast_on_cpu(const Options& options, const Scene& scene, const Mesh& mesh,
                 const SamplePoints& points, const std::vector<std::uint32_t>& order,
                 const Cone& cone, Output& out, const ProgressFn& progress) {
  std::string structure = accel_name(options.accel);
  if (scene.eight()) {
    structure += ", 8-wide";
  } else if (scene.four()) {
    structure += ", 4-wide";
  } else if (scene.binary()) {
    structure += ", binary";
  }
  Stopwatch clock;
  cast_cpu(scene, points, order, cone, minimum_closeness(mesh), options.threads, out.raw.data(),
           out.valid_rays.data(), progress, 0.05, 0.99);
  out.timings.emplace_back("cast", clock.lap());
  const unsigned threads = resolve_threads(options.threads);
  out.engine = "cpu (" + std::to_string(threads) + (threads == 1 ? " thread, " : " threads, ") +
               structure + ")";
}

#ifdef SDF_HAVE_OPENCL
void cast_on_opencl(const Options& options, const Plan& plan, const cl::CastInput& input,
                    const Mesh& mesh, const Cone& cone, Output& out, const ProgressFn& progress,
                    const std::function<void()>& beside_cast) {
  Stopwatch clock;
  const cl::CastTimings t =
      cl::cast_opencl(plan.devices, input, cone, minimum_closeness(mesh), options.threads,
                      out.raw.data(), out.valid_rays.data(), progress, 0.05, 0.99, beside_cast);
  const double total = clock.lap();
  // Compile (or cache load) and set-up are what the device stages and the wait for the
  // structure leave of the total.
  out.timings.emplace_back(
      "setup", std::max(0.0, total - t.upload - t.wait - t.build - t.cast - t.download));
  out.timings.emplace_back("upload", t.upload);
  if (plan.tree_on_device)
    out.timings.emplace_back(t.rewound ? "rewind (device)" : "build (device)", t.build);
  out.timings.emplace_back("cast", t.cast);
  out.timings.emplace_back("download", t.download);
  out.device_bytes = t.device_bytes;
  out.engine.clear();
  for (const cl::Device* d : plan.devices)
    out.engine += (out.engine.empty() ? "" : " + ") + std::string("opencl:") +
                  std::to_string(d->index) + " " + d->name;
  out.engine += std::string(" (") + accel_name(options.accel) + ")";
}

// Thrown from beside the cast when the orientation reverses faces: the cast read the mesh as
// it was wound.
struct ReverseFacesFirst {};
// Thrown from beside the cast when faces have reversed twins: the caller casts without them.
struct TwinsFound {};

// Casts `mesh` while deciding beside the cast (only reading the mesh) its 'auto' orientation
// and whether faces have reversed twins (orientations 'as_is' and 'flip' were applied before).
// Faces to reverse: the devices stop at their next launch (launches are kept short while the
// orientation is decided), the faces are reversed, and the mesh is cast again on the devices'
// trees of the first cast, rewound (a face's box does not depend on its winding: only the
// faces go up again and the triangles' records are remade); the twins are looked for beside
// that cast. Twins: the devices stop at their next launch and out.twins says which (the
// search takes less than a first launch: launches need not be short for it). Otherwise the
// cast stands: it is the cast of the oriented mesh.
void cast_speculatively(const Options& options, const Plan& plan, cl::CastInput input, Mesh& mesh,
                        const Cone& cone, Output& out, const ProgressFn& progress,
                        const std::function<void()>& beside_cast) {
  StageTimings orientation_steps;
  double orientation_seconds = 0.0, twins_seconds = 0.0;
  const bool orienting = options.orientation == Orientation::Auto;
  std::atomic<bool> deciding{orienting};
  input.short_launches = orienting ? &deciding : nullptr;
  // Twins are told in the caller's winding: through the faces the orientation reversed.
  auto find_twins = [&] {
    if (!options.find_twins) return;
    Stopwatch clock;
    const std::uint8_t* reversed =
        out.orientation.reversed.empty() ? nullptr : out.orientation.reversed.data();
    out.twins = reversed_twins(mesh, options.threads, reversed);
    twins_seconds = clock.lap();
    if (!out.twins.empty()) throw TwinsFound{};
  };
  auto decide_beside = [&] {
    if (orienting) {
      Stopwatch clock;
      out.orientation =
          decide_orientation(mesh, Orientation::Auto, options.threads, &orientation_steps);
      orientation_seconds = clock.lap();
      if (out.orientation.flipped_faces > 0) throw ReverseFacesFirst{};
      deciding = false;
    }
    find_twins();
    if (beside_cast) beside_cast();
  };
  bool recorded = false;
  auto record = [&] {
    if (recorded) return;
    recorded = true;
    if (orienting) {
      out.timings.emplace_back("orientation (beside cast)", orientation_seconds);
      for (const auto& [name, seconds] : orientation_steps) out.timings.emplace_back(name, seconds);
    }
  };
  auto record_twins = [&] {
    if (options.find_twins) out.timings.emplace_back("twins (beside cast)", twins_seconds);
  };
  cl::KeptTrees trees;  // freed on the way out, whichever way that is
  input.trees = &trees;
  Stopwatch first;
  try {
    try {
      cast_on_opencl(options, plan, input, mesh, cone, out, progress, decide_beside);
      record();
      record_twins();
      return;
    } catch (const ReverseFacesFirst&) {
    }
    // What the first cast took until it stopped (its stages are not recorded), then the faces
    // reversed and the stages of the cast that counts.
    out.timings.emplace_back("cast (discarded)", first.lap());
    record();
    apply_orientation(mesh, out.orientation, options.threads);
    out.timings.emplace_back("orientation: reverse faces", first.lap());
    input.short_launches = nullptr;
    input.rewind_trees = true;
    cast_on_opencl(options, plan, input, mesh, cone, out, progress, [&] {
      find_twins();
      if (beside_cast) beside_cast();
    });
    record_twins();
  } catch (const TwinsFound&) {
    out.timings.emplace_back("cast (discarded)", first.lap());
    record();
    record_twins();
  }
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
  // A mesh far from unit size is computed scaled by a power of two (unit_scale.h).
  const int exponent = unit_scale_exponent(mesh.max_extent);
  const float near_cutoff = minimum_closeness(mesh);  // in the caller's units
  if (exponent != 0) scale_mesh(mesh, exponent, options.threads);
  Output out;
  out.near_cutoff = near_cutoff;
  Stopwatch clock;
  // The first OpenCL run of a process loads the drivers and lists their devices (50-130 ms
  // on the development machine's PoCL).
  const Plan plan = make_plan(options, mesh.triangles.size());
  if (!cpu) out.timings.emplace_back("devices", clock.lap());
  // With a tree made on the device, twins are looked for beside the cast (cast_speculatively);
  // otherwise first, on the mesh as the caller wound it.
  if (options.find_twins && !plan.tree_on_device) {
    out.twins = reversed_twins(mesh, options.threads);
    out.timings.emplace_back("twins", clock.lap());
    if (!out.twins.empty()) return out;
  }
  StageTimings steps;  // of 'prepare'
  StageClock step(&steps);
  report(progress, 0.0);
  // The BVH builds beside orientation and sampling; the octree, which stores its triangles as
  // they are wound, after them; a tree made on the device, there.
  std::unique_ptr<BackgroundBvh> background;
  if (options.accel == Accel::Bvh && !plan.tree_on_device) {
    background = std::make_unique<BackgroundBvh>(mesh, options, plan, options.threads == 0);
    step.lap("prepare: start of the build");  // the copy of the mesh it reads
  }
  // `mesh` is the computation's own copy, wound outward; the caller's mesh is never changed.
  // With a tree made on the device, 'auto' orientation is decided while the devices cast the
  // mesh as it is wound (the common case: nothing to reverse); should faces need reversing,
  // the cast stops and runs again on the oriented mesh (cast_speculatively). Twins are looked
  // for there too.
  const bool speculate =
      plan.tree_on_device && (options.orientation == Orientation::Auto || options.find_twins);
  StageTimings orientation_steps;
  if (!(speculate && options.orientation == Orientation::Auto)) {
    out.orientation = orient(mesh, options.orientation, options.threads, &orientation_steps);
    step.lap("prepare: orientation");
    for (const auto& [name, seconds] : orientation_steps)
      steps.emplace_back("prepare: " + name, seconds);
  }
  SamplePoints points;
  std::vector<std::uint32_t> order;
  if (!plan.tree_on_device) {
    points = sample_points(mesh, options.points, options.threads);
    step.lap("prepare: points");
    order = spatial_order(points, options.threads);
    step.lap("prepare: order");
  }
  const std::size_t count = plan.tree_on_device ? mesh.triangles.size() : points.size();
  out.raw.resize(count);
  out.valid_rays.resize(count);
  out.timings.emplace_back("prepare", clock.lap());
  out.timings.insert(out.timings.end(), steps.begin(), steps.end());
  report(progress, 0.02);  // a cancel here unwinds through the background build's wait

  Scene built;
  const bool turned = out.orientation.flipped_faces > 0;
  auto build_scene = [&]() -> const Scene& {
    finish_scene(mesh, options, plan, background, turned, built, out);
    return built;
  };

  // The hook's own time: a stage of its own after the CPU engine's cast; on OpenCL within the
  // cast's (part of no other stage's time).
  double beside_seconds = 0.0;
  std::function<void()> timed_beside_cast;
  if (beside_cast)
    timed_beside_cast = [&] {
      Stopwatch beside;
      // The device's cast makes its points itself; the hook gets the host's, made here.
      if (plan.tree_on_device) points = sample_points(mesh, options.points, options.threads);
      beside_cast(exponent != 0 ? scaled_points(points, -exponent) : points);
      beside_seconds = beside.lap();
    };
  if (cpu) {
    build_scene();
    report(progress, 0.05);
    cast_on_cpu(options, built, mesh, points, order, cone, out, progress);
    if (timed_beside_cast) timed_beside_cast();
  } else {
#ifdef SDF_HAVE_OPENCL
    cl::CastInput input;
    if (plan.tree_on_device) {
      input.mesh = &mesh;
    } else {
      // The scene is finished from a device thread once the points are uploaded: their upload
      // overlaps the build.
      input.scene = build_scene;
      input.points = &points;
      input.order = order.data();
    }
    input.size = count;
    if (speculate) {
      cast_speculatively(options, plan, input, mesh, cone, out, progress, timed_beside_cast);
      if (!out.twins.empty()) {  // the cast stopped: no values
        out.raw.clear();
        out.valid_rays.clear();
        return out;
      }
    } else {
      cast_on_opencl(options, plan, input, mesh, cone, out, progress, timed_beside_cast);
    }
#endif
  }
  if (beside_cast) out.timings.emplace_back("beside cast", beside_seconds);
  clock.lap();

  out.fill = fill_missing(mesh, options.points, out.raw.data(), out.valid_rays.data());
  if (exponent != 0) scale_lengths(out.raw.data(), out.raw.size(), -exponent);
  out.timings.emplace_back("fill", clock.lap());
  if (options.keep_mesh) {
    if (exponent != 0) scale_mesh(mesh, -exponent, options.threads);  // exact: a power of two
    out.mesh = std::move(mesh);
  }
  report(progress, 1.0);
  return out;
}

}  // namespace sdf
