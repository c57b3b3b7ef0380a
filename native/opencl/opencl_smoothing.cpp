// SPDX-License-Identifier: GPL-3.0-or-later
#include "opencl_smoothing.h"

#include <algorithm>
#include <cstdint>
#include <exception>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "device_state.h"
#include "smoothing_launch.h"
#include "util/stopwatch.h"

namespace sdf::cl {

namespace {

// Steps 3 and 4 on the device: dilates island/value and blurs value, swapping each pair so
// that island and value hold the results (the blurred image in value).
void filter_on_device(const Device& device, DeviceState& s, cl_program program,
                      const TextureFilter& f, std::unique_ptr<Buffer>& island,
                      std::unique_ptr<Buffer>& value, std::vector<std::unique_ptr<Buffer>>& keep) {
  const std::size_t image = static_cast<std::size_t>(f.width) * f.height * sizeof(float);
  auto island_b = std::make_unique<Buffer>(s, image, nullptr);
  auto value_b = std::make_unique<Buffer>(s, image, nullptr);
  if (f.margin > 0) {
    Kernel dilate(program, "sdf_texture_dilate");
    dilate.arg(0, static_cast<cl_int>(f.width));
    dilate.arg(1, static_cast<cl_int>(f.height));
    for (int ring = 0; ring < f.margin; ++ring) {
      dilate.arg(2, island->get());
      dilate.arg(3, value->get());
      dilate.arg(4, island_b->get());
      dilate.arg(5, value_b->get());
      image_launch(device, s, dilate, f.width, f.height);
      std::swap(island, island_b);
      std::swap(value, value_b);
    }
  }
  keep.push_back(std::move(island_b));  // alive until the queue has run
  if (f.taps < 1) {
    keep.push_back(std::move(value_b));
    return;
  }
  auto row_value = std::make_unique<Buffer>(s, image, nullptr);
  auto row_weight = std::make_unique<Buffer>(s, image, nullptr);
  auto taps = std::make_unique<Buffer>(s, bytes_of(f.kernel), f.kernel.data());
  Kernel rows(program, "sdf_texture_blur_rows");
  cl_uint a = 0;
  rows.arg(a++, static_cast<cl_int>(f.width));
  rows.arg(a++, static_cast<cl_int>(f.height));
  rows.arg(a++, island->get());
  rows.arg(a++, value->get());
  rows.arg(a++, taps->get());
  rows.arg(a++, static_cast<cl_int>(f.taps));
  rows.arg(a++, f.inv_range);
  rows.arg(a++, row_value->get());
  rows.arg(a++, row_weight->get());
  image_launch(device, s, rows, f.width, f.height);
  Kernel columns(program, "sdf_texture_blur_columns");
  a = 0;
  columns.arg(a++, static_cast<cl_int>(f.width));
  columns.arg(a++, static_cast<cl_int>(f.height));
  columns.arg(a++, island->get());
  columns.arg(a++, row_value->get());
  columns.arg(a++, row_weight->get());
  columns.arg(a++, taps->get());
  columns.arg(a++, static_cast<cl_int>(f.taps));
  columns.arg(a++, f.inv_range);
  columns.arg(a++, f.lo);
  columns.arg(a++, f.hi);
  columns.arg(a++, value_b->get());
  image_launch(device, s, columns, f.width, f.height);
  std::swap(value, value_b);
  for (auto* b : {&value_b, &row_value, &row_weight, &taps}) keep.push_back(std::move(*b));
}

// Drawing and reading back compute texel coverage in double: a device without it would cover
// other texels than the CPU, so there the CPU threads do it all. (smooth_texture also keeps
// faces spanning more than kMostTexelsPerDeviceFace texels off a device: each is one work
// item, in double, which consumer GPUs run at 1/32 to 1/64 of float speed.)

// A prepared texture's UVs and face islands on a device (for vertex values also its
// triangles, corner groups and merged vertices), uploaded on its side queue while it cast. Released
// with the prepared texture, unless the device failed since (its driver objects may be dead: set
// aside like its state).
struct TextureUploads {
  DeviceState* state = nullptr;
  cl_mem uvs = nullptr, face_island = nullptr;
  cl_mem triangles = nullptr, group_first = nullptr, corners = nullptr, merged = nullptr;
  TextureUploads() = default;
  TextureUploads(const TextureUploads&) = delete;
  TextureUploads& operator=(const TextureUploads&) = delete;
  ~TextureUploads() {
    if (!state || state->broken || forked_after_load()) return;
    for (cl_mem mem : {uvs, face_island, triangles, group_first, corners, merged})
      if (mem) api()->clReleaseMemObject(mem);
  }
};

// Steps 2 to 5 on `device` (TextureDeviceFn); the UVs and face islands from `prepared`'s
// uploads where it has some that this device's state can read, else uploaded here.
TextureDeviceFn texture_on_device(const Device& device, const PreparedTexture* prepared) {
  return [&device, prepared](const TextureJob& job, bool images, float* out,
                             std::vector<std::int32_t>& island, std::vector<float>& blurred,
                             StageTimings& timings) {
    DeviceState& s = state_of(device);
    constexpr std::size_t kFaceChunk = std::size_t{1} << 20;  // faces per launch
    Stopwatch clock;
    const TextureFilter& f = job.filter;
    const bool faces = job.kind == PointKind::Faces;
    const std::size_t m = job.mesh->triangles.size();
    const std::size_t n = faces ? m : job.mesh->vertices.size();
    const std::size_t texels = static_cast<std::size_t>(f.width) * f.height;
    const std::size_t image = texels * sizeof(float);
    // uvs, values, face islands, read-back values; owner, island, value and their dilation
    // copies; the blur's two sums and taps; vertex values: triangles, corner samples, groups,
    // merged vertices.
    std::vector<std::size_t> sizes = {6 * m * sizeof(float),
                                      n * sizeof(float),
                                      m * sizeof(std::int32_t),
                                      n * sizeof(float),
                                      image,
                                      image,
                                      image,
                                      image,
                                      image};
    if (f.taps >= 1) sizes.insert(sizes.end(), {image, image, bytes_of(f.kernel)});
    if (!faces)
      sizes.insert(sizes.end(), {bytes_of(job.mesh->triangles), 3 * m * sizeof(float),
                                 bytes_of(job.groups->first), bytes_of(job.groups->corners),
                                 bytes_of(job.islands->merged)});
    check_fits(device, sizes, false, "a smaller texture_size");
    std::lock_guard<std::mutex> lock(s.mutex);
    const FinishOnUnwind finish_on_unwind(s.queue);
    cl_program program = smoothing_program(device, s);
    // Checked under the lock: made for this state, which no failed run has replaced since.
    const auto* uploads =
        prepared ? static_cast<const TextureUploads*>(prepared->on_device.get()) : nullptr;
    if (uploads && (uploads->state != &s || s.broken)) uploads = nullptr;
    s.copy_threads = job.threads;
    // Non-blocking uploads: the host arrays stay unchanged until the blocking reads below.
    std::unique_ptr<Buffer> own_uvs, own_islands;
    if (!uploads) {
      own_uvs = std::make_unique<Buffer>(s, 6 * m * sizeof(float), job.uvs);
      own_islands = std::make_unique<Buffer>(s, m * sizeof(std::int32_t), job.face_island);
    }
    const cl_mem uv_buffer = uploads ? uploads->uvs : own_uvs->get();
    const cl_mem face_island = uploads ? uploads->face_island : own_islands->get();
    Buffer value_buffer(s, n * sizeof(float), job.values);
    Buffer read_values(s, n * sizeof(float), nullptr);
    std::unique_ptr<Buffer> samples, own_triangles, own_first, own_corners, own_merged;
    cl_mem triangles = nullptr, group_first = nullptr, corners = nullptr, merged = nullptr;
    if (!faces) {
      samples = std::make_unique<Buffer>(s, 3 * m * sizeof(float), nullptr);
      if (uploads && uploads->group_first) {
        triangles = uploads->triangles;
        group_first = uploads->group_first;
        corners = uploads->corners;
        merged = uploads->merged;
      } else {
        own_triangles =
            std::make_unique<Buffer>(s, bytes_of(job.mesh->triangles), job.mesh->triangles.data());
        own_first =
            std::make_unique<Buffer>(s, bytes_of(job.groups->first), job.groups->first.data());
        own_corners =
            std::make_unique<Buffer>(s, bytes_of(job.groups->corners), job.groups->corners.data());
        if (!job.islands->merged.empty())
          own_merged = std::make_unique<Buffer>(s, bytes_of(job.islands->merged),
                                                job.islands->merged.data());
        triangles = own_triangles->get();
        group_first = own_first->get();
        corners = own_corners->get();
        merged = own_merged ? own_merged->get() : nullptr;
      }
    }
    Buffer owner(s, texels * sizeof(std::uint32_t), nullptr);
    auto island_a = std::make_unique<Buffer>(s, image, nullptr);
    auto value_a = std::make_unique<Buffer>(s, image, nullptr);
    check(api()->clFinish(s.queue), "clFinish (upload)");
    timings.emplace_back("device: upload", clock.lap());

    Kernel clear(program, "sdf_texture_clear");
    clear.arg(0, static_cast<cl_uint>(texels));
    clear.arg(1, owner.get());
    clear.arg(2, island_a->get());
    clear.arg(3, value_a->get());
    const std::size_t local = device.gpu ? 64 : 1;
    const std::size_t global = (texels + local - 1) / local * local;
    launch(s, clear, 1, &global, &local);
    const cl_uint faces_count = static_cast<cl_uint>(m);
    Kernel rank(program, "sdf_texture_rank");
    rank.arg(2, faces_count);
    rank.arg(3, static_cast<cl_int>(f.width));
    rank.arg(4, static_cast<cl_int>(f.height));
    rank.arg(5, uv_buffer);
    rank.arg(6, owner.get());
    launch_chunks(device, s, rank, m, kFaceChunk);
    Kernel draw(program, "sdf_texture_draw");
    cl_uint a = 2;
    draw.arg(a++, faces_count);
    draw.arg(a++, static_cast<cl_int>(f.width));
    draw.arg(a++, static_cast<cl_int>(f.height));
    draw.arg(a++, uv_buffer);
    draw.arg(a++, value_buffer.get());
    draw.arg(a++, triangles);  // null: face values
    draw.arg(a++, f.lo);
    draw.arg(a++, f.hi);
    draw.arg(a++, face_island);
    draw.arg(a++, owner.get());
    draw.arg(a++, island_a->get());
    draw.arg(a++, value_a->get());
    launch_chunks(device, s, draw, m, kFaceChunk);
    std::vector<std::unique_ptr<Buffer>> keep;
    filter_on_device(device, s, program, f, island_a, value_a, keep);
    if (faces) {
      Kernel read_faces(program, "sdf_texture_read_faces");
      a = 2;
      read_faces.arg(a++, static_cast<cl_int>(f.width));
      read_faces.arg(a++, static_cast<cl_int>(f.height));
      read_faces.arg(a++, uv_buffer);
      read_faces.arg(a++, face_island);
      read_faces.arg(a++, island_a->get());
      read_faces.arg(a++, value_a->get());
      read_faces.arg(a++, f.lo);
      read_faces.arg(a++, f.hi);
      read_faces.arg(a++, value_buffer.get());
      read_faces.arg(a++, read_values.get());
      launch_chunks(device, s, read_faces, m, kFaceChunk);
    } else {
      Kernel sample(program, "sdf_texture_sample_corners");
      a = 2;
      sample.arg(a++, static_cast<cl_int>(f.width));
      sample.arg(a++, static_cast<cl_int>(f.height));
      sample.arg(a++, uv_buffer);
      sample.arg(a++, face_island);
      sample.arg(a++, island_a->get());
      sample.arg(a++, value_a->get());
      sample.arg(a++, samples->get());
      launch_chunks(device, s, sample, m, kFaceChunk);
      Kernel read_vertices(program, "sdf_texture_read_vertices");
      a = 2;
      read_vertices.arg(a++, merged);  // null: each vertex its own group
      read_vertices.arg(a++, group_first);
      read_vertices.arg(a++, corners);
      read_vertices.arg(a++, samples->get());
      read_vertices.arg(a++, f.lo);
      read_vertices.arg(a++, f.hi);
      read_vertices.arg(a++, value_buffer.get());
      read_vertices.arg(a++, read_values.get());
      launch_chunks(device, s, read_vertices, n, kFaceChunk);
    }
    check(api()->clFinish(s.queue), "clFinish (texture)");
    timings.emplace_back("device: kernels", clock.lap());
    // The downloads queued, one wait (the queue runs in order).
    if (images) {
      island.resize(texels);
      blurred.resize(texels);
      check(api()->clEnqueueReadBuffer(s.queue, island_a->get(), CL_FALSE, 0, image, island.data(),
                                       0, nullptr, nullptr),
            "clEnqueueReadBuffer");
      check(api()->clEnqueueReadBuffer(s.queue, value_a->get(), CL_FALSE, 0, image, blurred.data(),
                                       0, nullptr, nullptr),
            "clEnqueueReadBuffer");
    }
    if (n > 0) read_buffer(s, read_values.get(), out, n * sizeof(float));
    check(api()->clFinish(s.queue), "clFinish (download)");
    timings.emplace_back("device: download", clock.lap());
  };
}

}  // namespace

TextureSmoothing smooth_texture_opencl(const Device& device, const Mesh& mesh, PointKind kind,
                                       const float* values, const float* uvs,
                                       const TextureOptions& options, bool keep_image,
                                       const ProgressFn& progress, float* into) {
  return smooth_texture(mesh, kind, values, uvs, options, keep_image, progress, 0.0, 1.0,
                        device.fp64 ? texture_on_device(device, nullptr) : nullptr, into);
}

TextureSmoothing smooth_texture_opencl(const Device& device, const PreparedTexture& prepared,
                                       PointKind kind, const float* values,
                                       const TextureOptions& options, bool keep_image,
                                       const ProgressFn& progress, float* into) {
  return smooth_texture(prepared, kind, values, options, keep_image, progress, 0.0, 1.0,
                        device.fp64 ? texture_on_device(device, &prepared) : nullptr, into);
}

bool upload_prepared_texture(const Device& device, PreparedTexture& prepared, unsigned threads) {
  if (!device.fp64 || prepared.largest_face_texels > kMostTexelsPerDeviceFace) return false;
  const std::size_t m = prepared.mesh.triangles.size();
  const std::size_t uv_bytes = 6 * m * sizeof(float), island_bytes = m * sizeof(std::int32_t);
  const CornerGroups& groups = prepared.groups;
  const std::vector<std::uint32_t>& merged = prepared.islands.merged;
  const bool vertex_values = !groups.first.empty();
  const std::size_t group_bytes = vertex_values
                                      ? bytes_of(prepared.mesh.triangles) + bytes_of(groups.first) +
                                            bytes_of(groups.corners) + bytes_of(merged)
                                      : 0;
  // Counted as the buffers are made (upload_new: at least 4 bytes each).
  if (std::max<std::size_t>(uv_bytes, 4) + std::max<std::size_t>(island_bytes, 4) + group_bytes >
      device.global_memory / 4)
    return false;  // leave room to cast
  DeviceState& s = state_of(device);
  auto uploads = std::make_shared<TextureUploads>();
  uploads->state = &s;
  std::lock_guard<std::mutex> lock(s.side_mutex);
  cl_command_queue queue = side_queue(device, s);
  // A failed call must not leave a write still reading the caller's arrays.
  const FinishOnUnwind finish_on_unwind(queue);
  Stopwatch clock;
  Staging* staging = s.stage_uploads ? &s.side_staging : nullptr;
  // Into buffers that `uploads` releases (also after a failed write).
  auto upload = [&](cl_mem& mem, const void* data, std::size_t bytes) {
    upload_new(s, queue, staging, threads, mem, data, bytes);
  };
  upload(uploads->uvs, prepared.uvs, uv_bytes);
  upload(uploads->face_island, prepared.islands.face_island.data(), island_bytes);
  if (vertex_values) {
    upload(uploads->triangles, prepared.mesh.triangles.data(), bytes_of(prepared.mesh.triangles));
    upload(uploads->group_first, groups.first.data(), bytes_of(groups.first));
    upload(uploads->corners, groups.corners.data(), bytes_of(groups.corners));
    if (!merged.empty()) upload(uploads->merged, merged.data(), bytes_of(merged));
  }
  // Done before the smoothing's queue reads them (and before `prepared` may change).
  check(api()->clFinish(queue), "clFinish (side)");
  prepared.timings.emplace_back("upload", clock.lap());
  prepared.on_device = std::move(uploads);
  return true;
}

}  // namespace sdf::cl
