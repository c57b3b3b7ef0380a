// SPDX-License-Identifier: GPL-3.0-or-later
#include "opencl_projected.h"

#include <cstdint>
#include <cstring>
#include <memory>
#include <mutex>
#include <utility>
#include <vector>

#include "device_state.h"
#include "smoothing_launch.h"
#include "util/parallel.h"
#include "util/uninitialized_vector.h"

namespace sdf::cl {

namespace {

// Points per work item of the points and bin kernels (sdf_point_octree_kernels.cl): enough
// that an item's run of points in one bin saves atomics, few enough to fill the device (on
// the H100 at 1.5M points 32 was faster than 64 and 128).
constexpr cl_uint kSpan = 32;
// Slots of a work group's table of bins in local memory: a group of 64 items over 2048
// neighbouring points meets few bins. On CPUs (groups of one item) one slot.
constexpr cl_uint kGroupBins = 64;

// The frames' buffers on one device state: origins and axes, 3 floats a point. Released with
// the prepared frames, unless the device failed since (its driver objects may be dead).
struct FramesOnDevice {
  DeviceState* state = nullptr;
  cl_mem origins = nullptr, axes = nullptr;
  FramesOnDevice() = default;
  FramesOnDevice(const FramesOnDevice&) = delete;
  FramesOnDevice& operator=(const FramesOnDevice&) = delete;
  ~FramesOnDevice() {
    if (!state || state->broken || forked_after_load()) return;
    for (cl_mem mem : {origins, axes})
      if (mem) api()->clReleaseMemObject(mem);
  }
};

// A bin as the kernels leave it: count, the fixed-point sum in two halves, the minimum
// value's bits (initially 0, 0, 0, all ones).
struct ProjectedBin {
  std::uint32_t count, sum_low, sum_high, min_bits;
  std::uint64_t sum() const { return std::uint64_t{sum_high} << 32 | sum_low; }
  float min() const { return float_of(min_bits); }
  static float float_of(std::uint32_t bits) {
    float x;
    std::memcpy(&x, &bits, sizeof x);
    return x;
  }
};
constexpr ProjectedBin kEmptyBin{0, 0, 0, 0xffffffffu};

// The inverse of the kernels' sdf_ordered_bits.
float from_ordered_bits(std::uint32_t b) {
  return ProjectedBin::float_of((b & 0x80000000u) ? (b & 0x7fffffffu) : ~b);
}

// A small non-blocking write: `data` must stay unchanged until a later blocking read (the
// level's bins: 16 bytes each, a few thousand at most with the default min_points).
void write_small(DeviceState& s, const Buffer& buffer, const void* data, std::size_t bytes) {
  check(api()->clEnqueueWriteBuffer(s.queue, buffer.get(), CL_FALSE, 0, bytes, data, 0, nullptr,
                                    nullptr),
        "clEnqueueWriteBuffer");
}

// A buffer that grows to the largest size asked of it.
class GrowingBuffer {
 public:
  const Buffer& at_least(DeviceState& s, std::size_t bytes) {
    if (!buffer_ || bytes > bytes_) {
      buffer_ = std::make_unique<Buffer>(s, bytes, nullptr);
      bytes_ = bytes;
    }
    return *buffer_;
  }

 private:
  std::unique_ptr<Buffer> buffer_;
  std::size_t bytes_ = 0;
};

// Everything after the frames are on the device, under the state's lock: per iteration, the
// points kernel (and the members' box and root sums read back), one bin kernel per level (its
// bins read back and made into nodes here), the nodes uploaded and the gather; the result
// read back once. n > 0 and range.lo < range.hi.
void smooth_on_device(const Device& device, DeviceState& s, cl_mem origins, cl_mem axes,
                      std::size_t n, const float* values, const ValueRange& range,
                      const ProjectedOptions& options, float* out, const ProgressFn& progress,
                      StageTimings* timings) {
  Stopwatch clock;
  cl_program program = smoothing_program(device, s);
  const std::size_t value_bytes = n * sizeof(float);
  auto current = std::make_unique<Buffer>(s, value_bytes, values);
  auto next = std::make_unique<Buffer>(s, value_bytes, nullptr);
  Buffer points(s, n * 4 * sizeof(float), nullptr);
  Buffer bin_of(s, n * sizeof(cl_int), nullptr);
  Buffer box(s, 6 * sizeof(std::uint32_t), nullptr);
  Buffer root(s, sizeof(ProjectedBin), nullptr);
  GrowingBuffer bins, slots;
  add_time(timings, "device: upload", clock.lap());

  const int shift = point_fixed_shift(range.hi, n);  // later iterations stay within range
  const cl_uint count = static_cast<cl_uint>(n);
  const std::size_t local = device.gpu ? 64 : 1;
  const std::size_t global = (n + local * kSpan - 1) / (local * kSpan) * local;
  Kernel project(program, "sdf_projected_points");
  Kernel split(program, "sdf_projected_bin");
  Kernel gather(program, "sdf_smooth_projected");
  // The host arrays that transfers read or write without blocking, then the guard that waits
  // for the queue before they go if an exception unwinds (declared after them: it runs first).
  const std::uint32_t box_start[6] = {~0u, ~0u, ~0u, 0u, 0u, 0u};
  std::uint32_t box_bits[6];
  ProjectedBin root_bin;
  std::vector<ProjectedBin> level_bins;
  std::vector<cl_int> slot_of_bin, next_slot_of_bin;       // the level above's bins: slot or -1
  std::vector<std::uint32_t> slot_nodes, next_slot_nodes;  // a level's branching nodes
  std::vector<PointOctreeNode> nodes;
  const FinishOnUnwind finish_on_unwind(s.queue);
  for (int it = 0; it < options.iterations; ++it) {
    // The points, their box and the root's sums.
    root_bin = kEmptyBin;
    write_small(s, box, box_start, sizeof box_start);
    write_small(s, root, &root_bin, sizeof root_bin);
    cl_uint a = 0;
    project.arg(a++, count);
    project.arg(a++, kSpan);
    project.arg(a++, origins);
    project.arg(a++, axes);
    project.arg(a++, current->get());
    project.arg(a++, static_cast<cl_int>(shift));
    project.arg(a++, points.get());
    project.arg(a++, bin_of.get());
    project.arg(a++, box.get());
    project.arg(a++, root.get());
    launch(s, project, 1, &global, &local);
    check(api()->clEnqueueReadBuffer(s.queue, box.get(), CL_FALSE, 0, sizeof box_bits, box_bits, 0,
                                     nullptr, nullptr),
          "clEnqueueReadBuffer");
    read(s, root, sizeof root_bin, &root_bin);
    add_time(timings, "device: points", clock.lap());
    if (root_bin.count == 0) {  // no point has an axis (then on the first iteration)
      std::copy(values, values + n, out);
      return;
    }

    // The octree, level by level, breadth first as the host builder makes it.
    const PointCube cube(glm::vec3(from_ordered_bits(box_bits[0]), from_ordered_bits(box_bits[1]),
                                   from_ordered_bits(box_bits[2])),
                         glm::vec3(from_ordered_bits(box_bits[3]), from_ordered_bits(box_bits[4]),
                                   from_ordered_bits(box_bits[5])),
                         options.max_depth);
    const double branch_above = options.min_points * static_cast<double>(root_bin.count);
    nodes = {make_point_node(cube.center, 0.5f * cube.side, root_bin.count, root_bin.sum(), shift)};
    slot_nodes.clear();
    slot_of_bin.assign(1, -1);
    if (point_node_branches(nodes[0], 0, root_bin.min(), options, branch_above)) {
      slot_of_bin[0] = 0;
      slot_nodes.push_back(0);
    }
    a = 0;
    split.arg(a++, count);
    split.arg(a++, kSpan);
    split.arg(a++, points.get());
    a = 4;
    split.arg(a++, static_cast<cl_int>(options.max_depth));
    split.arg(a++, cube.corner.x);
    split.arg(a++, cube.corner.y);
    split.arg(a++, cube.corner.z);
    split.arg(a++, cube.scale);
    split.arg(a++, static_cast<cl_uint>(cube.cells));
    split.arg(a++, static_cast<cl_int>(shift));
    split.arg(12, bin_of.get());
    const cl_uint table = device.gpu ? kGroupBins : 1;
    split.local_arg(14, table * sizeof(cl_int));
    split.local_arg(15, table * 4 * sizeof(cl_uint));
    split.arg(16, table);
    for (int level = 0; !slot_nodes.empty(); ++level) {
      level_bins.assign(8 * slot_nodes.size(), kEmptyBin);
      const Buffer& slot_buffer = slots.at_least(s, bytes_of(slot_of_bin));
      const Buffer& bin_buffer = bins.at_least(s, bytes_of(level_bins));
      write_small(s, slot_buffer, slot_of_bin.data(), bytes_of(slot_of_bin));
      write_small(s, bin_buffer, level_bins.data(), bytes_of(level_bins));
      split.arg(3, static_cast<cl_int>(level));
      split.arg(11, slot_buffer.get());
      split.arg(13, bin_buffer.get());
      launch(s, split, 1, &global, &local);
      read(s, bin_buffer, bytes_of(level_bins), level_bins.data());
      next_slot_of_bin.assign(level_bins.size(), -1);
      next_slot_nodes.clear();
      for (std::size_t slot = 0; slot < slot_nodes.size(); ++slot) {
        const std::uint32_t parent = slot_nodes[slot];
        const std::uint32_t first = static_cast<std::uint32_t>(nodes.size());
        for (unsigned octant = 0; octant < 8; ++octant) {
          const ProjectedBin& b = level_bins[8 * slot + octant];
          if (b.count == 0) continue;
          const PointOctreeNode p = nodes[parent];  // a copy: push_back may move the array
          nodes.push_back(make_point_node(point_child_center(p, octant), 0.5f * p.half_side,
                                          b.count, b.sum(), shift));
          if (point_node_branches(nodes.back(), level + 1, b.min(), options, branch_above)) {
            next_slot_of_bin[8 * slot + octant] = static_cast<cl_int>(next_slot_nodes.size());
            next_slot_nodes.push_back(static_cast<std::uint32_t>(nodes.size() - 1));
          }
        }
        nodes[parent].first_child = static_cast<std::int32_t>(first);
        nodes[parent].child_count = static_cast<std::uint32_t>(nodes.size()) - first;
      }
      slot_nodes.swap(next_slot_nodes);
      slot_of_bin.swap(next_slot_of_bin);
    }
    add_time(timings, "device: octree", clock.lap());

    // Each point's gathered mean, into `next` (the nodes' upload does not block).
    Buffer node_buffer(s, bytes_of(nodes), nodes.data());
    gather.arg(2, node_buffer.get());
    gather.arg(3, points.get());
    gather.arg(4, static_cast<float>(options.radius));
    gather.arg(5, range.lo);
    gather.arg(6, range.hi);
    gather.arg(7, next->get());
    launch_chunks(device, s, gather, n, std::size_t{1} << 18);
    check(api()->clFinish(s.queue), "clFinish (gather)");
    add_time(timings, "device: gather", clock.lap());
    std::swap(current, next);
    if (progress && !progress(static_cast<double>(it + 1) / options.iterations)) throw Cancelled();
  }
  read_buffer(s, current->get(), out, value_bytes);
  add_time(timings, "device: download", clock.lap());
}

// Uploads both frames' arrays into new buffers of `frames` on `queue` (not waiting).
void upload_frames(DeviceState& s, cl_command_queue queue, Staging* staging, unsigned threads,
                   const glm::vec3* origins, const glm::vec3* axes, std::size_t n,
                   FramesOnDevice& frames) {
  static_assert(sizeof(glm::vec3) == 3 * sizeof(float), "vec3 is 3 packed floats (vload3)");
  frames.state = &s;
  upload_new(s, queue, staging, threads, frames.origins, origins, n * sizeof(glm::vec3));
  upload_new(s, queue, staging, threads, frames.axes, axes, n * sizeof(glm::vec3));
}

std::size_t working_bytes(std::size_t n) {  // besides the frames: values x2, points, bins
  return n * (2 * sizeof(float) + 4 * sizeof(float) + sizeof(cl_int));
}

// Checks the input (std::invalid_argument) and reports progress 0; returns false, having
// copied the values to `out`, where smoothing would leave them as they are.
bool worth_smoothing(const float* values, std::size_t n, const ProjectedOptions& options,
                     float* out, const ProgressFn& progress, ValueRange* range) {
  *range = checked_projected_input(values, n, options);
  if (n == 0 || range->lo == range->hi || options.iterations == 0) {
    std::copy(values, values + n, out);
    return false;
  }
  if (progress && !progress(0.0)) throw Cancelled();
  return true;
}

}  // namespace

PreparedProjected prepare_projected(const Device& device, const SamplePoints& points,
                                    unsigned threads) {
  PreparedProjected prepared;
  const std::size_t n = points.size();
  prepared.count = n;
  if (2 * n * sizeof(glm::vec3) > device.global_memory / 4) return prepared;  // room to cast
  DeviceState& s = state_of(device);
  auto frames = std::make_shared<FramesOnDevice>();
  std::lock_guard<std::mutex> lock(s.side_mutex);
  cl_command_queue queue = side_queue(device, s);
  // A failed call must not leave a write still reading the caller's arrays.
  const FinishOnUnwind finish_on_unwind(queue);
  Stopwatch clock;
  upload_frames(s, queue, s.stage_uploads ? &s.side_staging : nullptr, threads,
                points.origins.data(), points.axes.data(), n, *frames);
  check(api()->clFinish(queue), "clFinish (side)");
  prepared.timings.emplace_back("upload", clock.lap());
  prepared.on_device = std::move(frames);
  return prepared;
}

void smooth_projected_opencl(const Device& device, const PreparedProjected& prepared,
                             const float* values, const ProjectedOptions& options, float* out,
                             const ProgressFn& progress, StageTimings* timings) {
  Stopwatch clock;
  const std::size_t n = prepared.count;
  ValueRange range;
  if (!worth_smoothing(values, n, options, out, progress, &range)) return;
  add_time(timings, "checks", clock.lap());
  check_fits(device, {working_bytes(n)});
  DeviceState& s = state_of(device);
  std::lock_guard<std::mutex> lock(s.mutex);
  const FinishOnUnwind finish_on_unwind(s.queue);
  // Checked under the lock: made for this state, which no failed run has replaced since.
  const auto* frames = static_cast<const FramesOnDevice*>(prepared.on_device.get());
  if (!frames || frames->state != &s || s.broken)
    throw Error(
        "the points' frames are not on this device (not uploaded, or the device "
        "failed since)",
        CL_INVALID_MEM_OBJECT);
  s.copy_threads = options.threads;
  smooth_on_device(device, s, frames->origins, frames->axes, n, values, range, options, out,
                   progress, timings);
}

void smooth_projected_opencl(const Device& device, const Mesh& mesh, PointKind kind,
                             const float* values, const ProjectedOptions& options, float* out,
                             const ProgressFn& progress, StageTimings* timings) {
  Stopwatch clock;
  const std::size_t n = kind == PointKind::Faces ? mesh.triangles.size() : mesh.vertices.size();
  ValueRange range;
  if (!worth_smoothing(values, n, options, out, progress, &range)) return;
  add_time(timings, "checks", clock.lap());
  // Faces: centroids and inward normals only (sample_points' other arrays are the cast's).
  UninitializedVector<glm::vec3> origins, axes;
  SamplePoints vertex_points;
  const glm::vec3 *origin_data, *axis_data;
  if (kind == PointKind::Faces) {
    origins.resize(n);
    axes.resize(n);
    parallel_for(n, std::size_t{1} << 14, options.threads, [&](std::size_t begin, std::size_t end) {
      for (std::size_t i = begin; i < end; ++i) face_point(mesh, i, &origins[i], &axes[i]);
    });
    origin_data = origins.data();
    axis_data = axes.data();
  } else {
    vertex_points = sample_points(mesh, kind, options.threads);
    origin_data = vertex_points.origins.data();
    axis_data = vertex_points.axes.data();
  }
  add_time(timings, "frames", clock.lap());
  check_fits(device, {working_bytes(n), 2 * n * sizeof(glm::vec3)});
  DeviceState& s = state_of(device);
  std::lock_guard<std::mutex> lock(s.mutex);
  const FinishOnUnwind finish_on_unwind(s.queue);
  s.copy_threads = options.threads;
  FramesOnDevice frames;  // non-blocking uploads: the arrays live past the blocking reads
  upload_frames(s, s.queue, s.stage_uploads ? &s.staging : nullptr, options.threads, origin_data,
                axis_data, n, frames);
  smooth_on_device(device, s, frames.origins, frames.axes, n, values, range, options, out, progress,
                   timings);
}

}  // namespace sdf::cl
