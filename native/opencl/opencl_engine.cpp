// SPDX-License-Identifier: GPL-3.0-or-later
#include "opencl_engine.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <exception>
#include <map>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>

#include "device_state.h"
#include "device_tree.h"
#include "launch_sizes.h"
#include "program_cache.h"
#include "util/test_overrides.h"

namespace sdf::cl {

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

// Shared by the device threads: the next range of points in Morton order to hand out.
struct WorkQueue {
  std::atomic<std::size_t> next{0};
  std::atomic<std::size_t> done{0};
  std::atomic<bool> stop{false};
  std::atomic<bool> nothing_to_hit{false};  // every triangle has zero area
  std::size_t meshes_uploaded = 0;  // devices whose mesh is up (CastInput::mesh), under done_mutex
  std::size_t total = 0;
  std::size_t devices = 1;  // casting together
  // Per device (its place in the list), points a second in its last launch; 0 before one.
  std::unique_ptr<std::atomic<double>[]> rates;
  // A device-made order (CastInput::mesh), from the first device to make it (all make the
  // same), for putting the results in face order.
  std::mutex order_mutex;
  UninitializedVector<std::uint32_t> device_order;
};

struct DeviceResult {
  CastTimings timings;
  std::exception_ptr failure;
};

}  // namespace

// Each device's tree, with the device state it was made on: another computation may find the
// device broken between the two casts and give it a fresh state (state_of), whose context the
// tree's buffers are not of.
struct KeptTrees::Slots {
  struct Kept {
    DeviceState* state = nullptr;
    DeviceTree tree;
  };
  std::mutex mutex;
  std::map<const Device*, Kept> trees;

  ~Slots() { clear(); }
  void put(const Device* device, DeviceState* state, DeviceTree&& tree) {
    std::lock_guard<std::mutex> lock(mutex);
    Kept& kept = trees[device];
    drop(kept);
    kept.state = state;
    kept.tree = std::move(tree);
  }
  void clear() {
    std::lock_guard<std::mutex> lock(mutex);
    for (auto& [device, kept] : trees) drop(kept);
    trees.clear();
  }
  // The device's kept tree, moved out, when it was made on `state` and that state still
  // works; false otherwise.
  bool take(const Device* device, DeviceState& state, DeviceTree& into) {
    std::lock_guard<std::mutex> lock(mutex);
    auto found = trees.find(device);
    if (found == trees.end()) return false;
    const bool usable = found->second.state == &state && !state.broken;
    if (usable) into = std::move(found->second.tree);
    drop(found->second);
    trees.erase(found);
    return usable;
  }

 private:
  // Frees a tree's buffers, unless its device failed since (its driver objects may be dead:
  // they are left alone, as the state is).
  static void drop(Kept& kept) {
    DeviceTree& t = kept.tree;
    if (kept.state && kept.state->broken)
      for (std::unique_ptr<Buffer>* b : {&t.vertices, &t.faces, &t.order, &t.nodes, &t.triangles})
        (void)b->release();
    t = DeviceTree{};
  }
};

KeptTrees::KeptTrees() : slots_(std::make_unique<Slots>()) {}
KeptTrees::~KeptTrees() = default;

// Which cast kernel a device runs for accel='bvh'. GPUs: the binary BVH, one work item per
// ray (13-15% faster than one per point on an H100; a 4-wide BVH was 8-10% slower there).
// CPU devices (PoCL): the CPU engine's 8-wide BVH, one work item per point, with float8 box
// tests, float4 triangle packets and two rays taking turns (sdf_bvh8_traverse.h): 0.83-0.93
// of the CPU engine's rays/s where a 4-wide BVH kernel reached 0.38-0.40 and the binary one
// per point 0.24-0.30 (bench/opencl_vs_cpu.py, interleaved runs, PoCL 3.1 on a 2-core
// AVX-512 EPYC, 52k-1.2M faces). The 4-wide kernel went for that: the 8-wide one is plain
// OpenCL C, which PoCL compiles for any CPU (SSE or NEON as well as AVX2), and a CPU-only
// machine casts with the CPU engine unless asked for OpenCL. A test override
// (util/test_overrides.h) forces any kernel, so tests run every kernel on whatever device they
// have and benchmarks compare them.
CastKernel cast_kernel_for(const Device& device) {
  switch (test_overrides().opencl_kernel) {
    case KernelChoice::BvhPerPoint: return CastKernel::BvhPerPoint;
    case KernelChoice::Bvh8PerPoint: return CastKernel::Bvh8PerPoint;
    case KernelChoice::BvhPerRay: return CastKernel::BvhPerRay;
    case KernelChoice::Engine: break;
  }
  if (device.gpu) return CastKernel::BvhPerRay;
  return CastKernel::Bvh8PerPoint;
}

BvhWidths wanted_bvhs(const std::vector<const Device*>& devices) {
  BvhWidths wanted;
  for (const Device* d : devices) {
    switch (cast_kernel_for(*d)) {
      case CastKernel::Bvh8PerPoint: wanted.eight = true; break;
      default: wanted.binary = true;
    }
  }
  return wanted;
}

namespace {

// Gets the scene once for every device thread: the first to ask runs the source (the others
// wait), and a failure reaches each of them.
class SharedScene {
 public:
  explicit SharedScene(const SceneSource& source) : source_(source) {}
  // Null when every triangle has zero area (nothing can be hit: an empty tree has no root).
  const Scene* get() {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!asked_) {
      asked_ = true;
      try {
        scene_ = &source_();
      } catch (...) {
        failure_ = std::current_exception();
      }
    }
    if (failure_) std::rethrow_exception(failure_);
    const bool empty =
        (scene_->binary() && scene_->bvh.empty()) || (scene_->eight() && scene_->bvh8.empty());
    return empty ? nullptr : scene_;
  }

 private:
  const SceneSource& source_;
  std::mutex mutex_;
  bool asked_ = false;
  const Scene* scene_ = nullptr;
  std::exception_ptr failure_;
};

void run_device(const Device& device, std::size_t slot, SharedScene& shared_scene,
                const CastInput& input, const Cone& cone, float min_closeness,
                unsigned host_threads, UninitializedVector<float>& raw_ordered,
                UninitializedVector<std::int32_t>& valid_ordered, WorkQueue& work,
                std::mutex& done_mutex, std::condition_variable& done_changed,
                DeviceResult& result) {
  const Api& cl = *api();
  DeviceState& s = state_of(device);
  std::lock_guard<std::mutex> device_lock(s.mutex);
  s.copy_threads = host_threads;
  const std::size_t n = input.size;
  const std::string options = build_options(device, cone.rays);
  const CastKernel choice = cast_kernel_for(device);
  // What the kernel reads: the tree, the points (the host's arrays, or a device tree's mesh,
  // which the kernel makes the faces' points from) and their order.
  cl_mem accel[3] = {nullptr, nullptr, nullptr}, order = nullptr;
  cl_mem points_in[4] = {nullptr, nullptr, nullptr, nullptr};
  const kern::SdfOctreeRoot* accel_root = nullptr;  // the octree's kernel takes it by value
  DeviceTree tree;                                  // CastInput::mesh: the device's own
  std::unique_ptr<Buffer> owned[8];                 // otherwise: the host's uploads
  std::unique_ptr<Kernel> kernel;
  cl_program program = nullptr;
  std::size_t points_per_group = 0;
  // One work item per ray: points_per_group points of `rays` items each, about 128 items a
  // group (H100, device tree, cast ms at 1.21M faces with 1 / 2 / 4 / 8 / 16 points a group:
  // 30 rays 42.9 / 40.2 / 39.6 / 42.8 / 42.8; 64 rays 99.9 / 89.2 / 95.5 with 1 / 2 / 4), fewer
  // when registers limit the group size; otherwise the binary tree's per-point kernel.
  auto binary_tree_kernel = [&](const std::string& suffix) {
    if (choice == CastKernel::BvhPerRay) {
      kernel = std::make_unique<Kernel>(program, ("sdf_cast_bvh_per_ray" + suffix).c_str());
      const std::size_t rays = static_cast<std::size_t>(cone.rays);
      points_per_group = std::min(std::max<std::size_t>(1, (128 + rays / 2) / rays),
                                  kernel->max_group(device.id) / rays);
    }
    if (points_per_group == 0)
      kernel = std::make_unique<Kernel>(program, ("sdf_cast_bvh" + suffix).c_str());
  };
  // The host's ray table (direction, angle) for deterministic samplings; random rays are
  // generated on the device and read none of it.
  std::vector<float> table(4 * std::max<std::size_t>(cone.local.size(), 1), 0.0f);
  for (std::size_t i = 0; i < cone.local.size(); ++i) {
    table[4 * i] = cone.local[i].x;
    table[4 * i + 1] = cone.local[i].y;
    table[4 * i + 2] = cone.local[i].z;
    table[4 * i + 3] = cone.local_angle[i];
  }
  Buffer local_rays(s, table.size() * sizeof(float), table.data());

  if (input.mesh) {
    // Order and tree made here, from the mesh alone (the kernel makes the faces' points), or
    // a kept tree of the mesh as an earlier cast had it wound, rewound.
    auto uploaded = [&] {
      {
        std::lock_guard<std::mutex> lock(done_mutex);
        ++work.meshes_uploaded;
      }
      done_changed.notify_all();
    };
    if (input.trees && input.rewind_trees && input.trees->slots().take(&device, s, tree)) {
      rewind_device_tree(device, s, options, tree, *input.mesh, uploaded);
      result.timings.rewound = true;
    } else {
      tree = build_device_tree(device, s, options, *input.mesh, uploaded);
    }
    program = program_for(device, s, options);  // built by now: a lookup
    result.timings.upload += tree.upload_seconds;
    result.timings.build = tree.build_seconds;
    result.timings.device_bytes = tree.peak_bytes;
    if (tree.with_area == 0) {
      work.nothing_to_hit = true;  // cast_opencl fills the results
      work.stop = true;
      return;
    }
    {
      // Every device must cast the faces in one order: the ranges handed out are positions
      // in it. Devices that round differently (no correctly rounded division) could sort
      // differently: then this run fails (engine 'auto' then runs on the CPU).
      std::lock_guard<std::mutex> lock(work.order_mutex);
      if (work.device_order.empty()) {
        // (Kept, the tree then reads its order back again if rewound: device_tree.cpp.)
        work.device_order = std::move(tree.host_order);
      } else if (!std::equal(work.device_order.begin(), work.device_order.end(),
                             tree.host_order.begin())) {
        // Not thrown: the device works, and a thrown Error would mark it broken.
        result.failure = std::make_exception_ptr(
            Error("OpenCL devices sorted the faces differently (their float rounding differs): "
                  "cast on one of them",
                  CL_INVALID_OPERATION));
        work.stop = true;
        return;
      }
    }
    points_in[0] = tree.vertices->get();
    points_in[1] = tree.faces->get();
    order = tree.order->get();
    accel[0] = tree.nodes->get();
    accel[1] = tree.triangles->get();
    binary_tree_kernel("_faces");
  } else {
    const SamplePoints& points = *input.points;
    // The points and their order first: they go to the device (and the program is compiled
    // or loaded) while the scene may still be building on the host.
    std::vector<std::size_t> sizes = {3 * n * sizeof(float),    3 * n * sizeof(float),
                                      n * sizeof(std::int32_t), n * sizeof(std::uint32_t),
                                      n * sizeof(float),        n * sizeof(std::int32_t),
                                      3 * n * sizeof(float)};
    check_fits(device, sizes, true);
    program = program_for(device, s, options);
    Clock::time_point upload_start = Clock::now();
    owned[0] = std::make_unique<Buffer>(s, sizes[0], points.origins.data());
    owned[1] = std::make_unique<Buffer>(s, sizes[1], points.axes.data());
    owned[2] = std::make_unique<Buffer>(s, sizes[2], points.own_face.data());
    owned[3] = std::make_unique<Buffer>(s, sizes[3], input.order);
    owned[4] = std::make_unique<Buffer>(s, sizes[6], points.tangents.data());
    points_in[0] = owned[0]->get();  // origins, axes, tangents, own_face
    points_in[1] = owned[1]->get();
    points_in[2] = owned[4]->get();
    points_in[3] = owned[2]->get();
    order = owned[3]->get();
    result.timings.upload += seconds_since(upload_start);

    const Clock::time_point wait_start = Clock::now();
    const Scene* scene_or_empty = shared_scene.get();
    result.timings.wait = seconds_since(wait_start);
    if (!scene_or_empty) {
      check(cl.clFinish(s.queue), "clFinish (upload)");
      work.stop = true;  // nothing to cast; cast_opencl fills the results
      return;
    }
    if (work.stop.load()) return;  // cancelled (or another device failed) during the build
    const Scene& scene = *scene_or_empty;
    upload_start = Clock::now();
    const std::size_t first_accel = sizes.size();
    // The 8-wide tree needs no depth check: its stack holds the deepest tree the builder
    // makes (sdf_bvh8_traverse.h).
    const bool wide8 = choice == CastKernel::Bvh8PerPoint && scene.eight();
    std::vector<const void*> data;
    if (wide8) {
      sizes.push_back(bytes_of(scene.bvh8.nodes));
      sizes.push_back(bytes_of(scene.bvh8.packets));
      data = {scene.bvh8.nodes.data(), scene.bvh8.packets.data()};
      kernel = std::make_unique<Kernel>(program, "sdf_cast_bvh8");
    } else if (scene.binary()) {
      sizes.push_back(bytes_of(scene.bvh.nodes));
      sizes.push_back(bytes_of(scene.bvh.triangles));
      data = {scene.bvh.nodes.data(), scene.bvh.triangles.data()};
      binary_tree_kernel("");
    } else {
      sizes.push_back(bytes_of(scene.octree.nodes));
      sizes.push_back(bytes_of(scene.octree.leaves));
      sizes.push_back(bytes_of(scene.octree.triangles));
      data = {scene.octree.nodes.data(), scene.octree.leaves.data(), scene.octree.triangles.data()};
      kernel = std::make_unique<Kernel>(program, "sdf_cast_octree");
    }
    check_fits(device, sizes);
    for (std::size_t b : sizes) result.timings.device_bytes += b;
    for (std::size_t i = 0; i < data.size(); ++i) {
      owned[5 + i] = std::make_unique<Buffer>(s, sizes[first_accel + i], data[i]);
      accel[i] = owned[5 + i]->get();
    }
    result.timings.upload += seconds_since(upload_start);
    if (scene.tree()) accel_root = &scene.octree.root;
  }
  // The results, made last: a device tree's build no longer holds its scratch by now.
  Buffer raw(s, n * sizeof(float), nullptr);
  Buffer valid(s, n * sizeof(std::int32_t), nullptr);
  const Clock::time_point upload_start = Clock::now();
  kern::SdfCastParams params{};
  params.rays = cone.rays;
  params.sampling = static_cast<int>(cone.sampling);
  params.one_minus_cos_half = cone.one_minus_cos_half;
  params.sin_half = cone.sin_half;
  params.angle_floor = cone.angle_floor;
  params.seed = cone.seed;
  params.tmin = min_closeness;
  cl_uint a = 0;
  for (cl_mem m : accel)
    if (m) kernel->arg(a++, m);
  if (accel_root) kernel->arg(a++, *accel_root);
  for (cl_mem m : points_in)
    if (m) kernel->arg(a++, m);
  kernel->arg(a++, order);
  kernel->arg(a++, local_rays.get());
  const cl_uint params_index = a++;
  kernel->arg(a++, raw.get());
  kernel->arg(a++, valid.get());
  if (points_per_group) {
    // Lengths and angles, each as cast and sorted per point (sdf_kernels.cl).
    kernel->local_arg(a++, 2 * points_per_group * cone.rays * sizeof(float));
    kernel->local_arg(a++, 2 * points_per_group * cone.rays * sizeof(float));
  }
  check(cl.clFinish(s.queue), "clFinish (upload)");
  result.timings.upload += seconds_since(upload_start);

  // Launches of about 100 ms on this device: short enough that a display driver's watchdog
  // never fires and progress and cancellation stay responsive, long enough to fill the device.
  constexpr double kTargetSeconds = 0.1;
  constexpr double kShortSeconds = 0.005;  // CastInput::short_launches
  // The first launch holds 2048 points per compute unit: enough to fill a GPU with one work
  // item per point (2048 resident per unit on NVIDIA's), `rays` times more with the per-ray
  // kernel, and still short (about 12 ms for 270k points on an H100); starting at 4096 points
  // left the GPU mostly idle, 11% of the cast time at 832k faces (H100).
  std::size_t chunk = first_launch_points(
      device.gpu ? std::max<std::size_t>(4096, device.compute_units * 2048u) : 4096, work.total,
      work.devices);
  const std::size_t floor = chunk / 4;
  // Work-group size. GPUs: 64, two warps or one wavefront (left to the driver, NVIDIA's picks a
  // divisor of the global size, down to 1 for a prime count). CPUs (PoCL): 1, because PoCL
  // runs a work group as a loop it tries to vectorise, and divergent traversal loops defeat
  // that: measured about 3x faster than its default on fandisk.
  // (Sizes 32 to 128 measured the same on an H100.)
  const std::size_t local = device.gpu ? 64 : 1;
  // Test override: act out a device lost after this many launches (a driver reset, an
  // unplugged eGPU), which real hardware cannot be asked to do on cue.
  const long lose_after = test_overrides().opencl_lose_device_after;
  long launches = 0;
  while (!work.stop.load()) {
    const std::size_t first = work.next.fetch_add(chunk);
    if (first >= work.total) break;
    const std::size_t count = std::min(chunk, work.total - first);
    params.first = static_cast<std::uint32_t>(first);
    params.count = static_cast<std::uint32_t>(count);
    kernel->arg(params_index, params);
    const Clock::time_point launch = Clock::now();
    std::size_t group = local;
    std::size_t global = (count + local - 1) / local * local;
    if (points_per_group) {
      group = points_per_group * cone.rays;
      global = (count + points_per_group - 1) / points_per_group * group;
    }
    check(cl.clEnqueueNDRangeKernel(s.queue, kernel->get(), 1, nullptr, &global, &group, 0, nullptr,
                                    nullptr),
          "clEnqueueNDRangeKernel");
    if (lose_after >= 0 && launches++ >= lose_after)
      throw Error(
          "OpenCL clFinish (cast) failed: CL_DEVICE_NOT_AVAILABLE (acted out by a "
          "test override)",
          CL_DEVICE_NOT_AVAILABLE);
    check(cl.clFinish(s.queue), "clFinish (cast)");
    const double took = seconds_since(launch);
    result.timings.cast += took;
    const Clock::time_point read = Clock::now();
    check(cl.clEnqueueReadBuffer(s.queue, raw.get(), CL_FALSE, first * sizeof(float),
                                 count * sizeof(float), raw_ordered.data() + first, 0, nullptr,
                                 nullptr),
          "clEnqueueReadBuffer");
    check(cl.clEnqueueReadBuffer(s.queue, valid.get(), CL_TRUE, first * sizeof(std::int32_t),
                                 count * sizeof(std::int32_t), valid_ordered.data() + first, 0,
                                 nullptr, nullptr),
          "clEnqueueReadBuffer");
    result.timings.download += seconds_since(read);
    {
      std::lock_guard<std::mutex> lock(done_mutex);
      work.done += count;
    }
    done_changed.notify_all();
    // The next launch toward the target time, shared out between devices (launch_sizes.h).
    const double target =
        input.short_launches && input.short_launches->load() ? kShortSeconds : kTargetSeconds;
    work.rates[slot] = count / std::max(took, 1e-6);
    double share = 1.0 / work.devices;
    if (work.devices <= 64) {
      double rates[64];
      for (std::size_t d = 0; d < work.devices; ++d) rates[d] = work.rates[d].load();
      share = launch_share(rates, work.devices, slot);
    }
    const std::size_t left = work.total - std::min(work.total, work.next.load());
    chunk = next_launch_points(chunk, took, target, floor, left, work.devices, share);
  }
  if (input.trees && tree.nodes) input.trees->slots().put(&device, &s, std::move(tree));
}

}  // namespace

bool tree_on_device(bool preferred) {
  switch (test_overrides().opencl_tree) {
    case TreeChoice::Device: return true;
    case TreeChoice::Host: return false;
    case TreeChoice::Engine: break;
  }
  return preferred;
}

CastTimings cast_opencl(const std::vector<const Device*>& devices, const CastInput& input,
                        const Cone& cone, float min_closeness, unsigned host_threads, float* raw,
                        std::int32_t* valid_rays, const ProgressFn& progress, double progress_from,
                        double progress_to, const std::function<void()>& beside_cast) {
  const std::size_t n = input.size;
  SharedScene shared_scene(input.scene);
  // The kernels write results in cast order (contiguous per launch); scattered back below.
  UninitializedVector<float> raw_ordered(n);
  UninitializedVector<std::int32_t> valid_ordered(n);
  WorkQueue work;
  work.total = n;
  work.devices = devices.size();
  work.rates = std::make_unique<std::atomic<double>[]>(devices.size());
  for (std::size_t i = 0; i < devices.size(); ++i) work.rates[i] = 0.0;
  std::mutex done_mutex;
  std::condition_variable done_changed;
  std::vector<DeviceResult> results(devices.size());
  std::vector<std::thread> threads;
  for (std::size_t i = 0; i < devices.size(); ++i) {
    threads.emplace_back([&, i] {
      try {
        run_device(*devices[i], i, shared_scene, input, cone, min_closeness, host_threads,
                   raw_ordered, valid_ordered, work, done_mutex, done_changed, results[i]);
      } catch (const Error&) {
        // An OpenCL call failed: the device may be lost, so the next run starts afresh.
        results[i].failure = std::current_exception();
        state_of(*devices[i]).broken = true;
        work.stop = true;
      } catch (...) {
        results[i].failure = std::current_exception();
        work.stop = true;
      }
      done_changed.notify_all();
    });
  }
  bool cancelled = false;
  std::exception_ptr caller_failure;
  if (beside_cast && input.mesh) {
    // The host's work beside the cast waits for the meshes' uploads: their copies into pinned
    // memory run on host threads too, and beside a 16-thread orientation took 3-4 times as
    // long (H100 host, 1.21M faces: 1.8 -> 6.6 ms), delaying the cast itself.
    // In steps: a device thread that fails sets `stop` without the mutex, so its notification
    // can come between a check and the wait.
    std::unique_lock<std::mutex> lock(done_mutex);
    while (work.meshes_uploaded < devices.size() && !work.stop.load())
      done_changed.wait_for(lock, std::chrono::milliseconds(5));
  }
  if (beside_cast) {
    try {
      beside_cast();
    } catch (...) {
      caller_failure = std::current_exception();  // rethrown once the devices have stopped
      work.stop = true;
    }
  }
  {
    // Progress at least once during the cast, also when the devices finished while the work
    // beside it ran (a small mesh on a GPU): the caller sees the cast end and may still
    // cancel there.
    std::unique_lock<std::mutex> lock(done_mutex);
    bool reported = false;
    while (!work.stop.load() && (work.done.load() < n || (progress && !reported))) {
      if (work.done.load() < n) done_changed.wait_for(lock, std::chrono::milliseconds(50));
      if (!progress) continue;
      reported = true;
      const double fraction = n ? static_cast<double>(work.done.load()) / n : 1.0;
      lock.unlock();
      bool keep_going = true;
      try {
        keep_going = progress(progress_from + (progress_to - progress_from) * fraction);
      } catch (...) {
        caller_failure = std::current_exception();
        keep_going = false;
      }
      lock.lock();
      if (!keep_going) {
        cancelled = true;
        work.stop = true;
      }
    }
  }
  for (std::thread& t : threads) t.join();
  // Trees are kept for a cast again only when the caller stopped this one (sdf.cpp: the
  // orientation reverses faces); otherwise freed here, within the cast's time, as before.
  if (input.trees && !caller_failure) input.trees->slots().clear();
  if (caller_failure) std::rethrow_exception(caller_failure);
  if (cancelled) throw Cancelled();
  CastTimings timings;
  for (const DeviceResult& r : results) {
    if (r.failure) std::rethrow_exception(r.failure);
    timings.upload = std::max(timings.upload, r.timings.upload);
    timings.wait = std::max(timings.wait, r.timings.wait);
    timings.build = std::max(timings.build, r.timings.build);
    timings.rewound = timings.rewound || r.timings.rewound;
    timings.cast = std::max(timings.cast, r.timings.cast);
    timings.download = std::max(timings.download, r.timings.download);
    timings.device_bytes = std::max(timings.device_bytes, r.timings.device_bytes);
  }
  if (work.nothing_to_hit || (!input.mesh && !shared_scene.get())) {
    // Every triangle has zero area: nothing was cast, nothing can be hit.
    std::fill(raw, raw + n, -1.0f);
    std::fill(valid_rays, valid_rays + n, 0);
    return timings;
  }
  const std::uint32_t* order = input.mesh ? work.device_order.data() : input.order;
  parallel_for(n, 1 << 16, host_threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      raw[order[i]] = raw_ordered[i];
      valid_rays[order[i]] = valid_ordered[i];
    }
  });
  return timings;
}

void build_source_for_test(int index, const std::string& source) {
  const Device& device = *select_devices("opencl:" + std::to_string(index)).front();
  DeviceState& s = state_of(device);
  std::lock_guard<std::mutex> lock(s.mutex);
  cl_program program = build_program(device, s.context, "-cl-std=CL1.2", source.c_str());
  api()->clReleaseProgram(program);
}

std::vector<std::uint32_t> probe_layout(int index) {
  const Device& device = *select_devices("opencl:" + std::to_string(index)).front();
  DeviceState& s = state_of(device);
  std::lock_guard<std::mutex> lock(s.mutex);
  cl_program program = program_for(device, s, build_options(device, 1));
  Kernel kernel(program, "sdf_layout_probe");
  std::vector<std::uint32_t> out(32, 0);
  Buffer buffer(s, bytes_of(out), out.data());
  kernel.arg(0, buffer.get());
  const std::size_t one = 1;
  check(api()->clEnqueueNDRangeKernel(s.queue, kernel.get(), 1, nullptr, &one, nullptr, 0, nullptr,
                                      nullptr),
        "clEnqueueNDRangeKernel");
  check(api()->clEnqueueReadBuffer(s.queue, buffer.get(), CL_TRUE, 0, bytes_of(out), out.data(), 0,
                                   nullptr, nullptr),
        "clEnqueueReadBuffer");
  out.resize(24);
  return out;
}

}  // namespace sdf::cl
