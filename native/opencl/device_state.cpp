// SPDX-License-Identifier: GPL-3.0-or-later
#include "device_state.h"

#include <algorithm>
#include <memory>
#include <stdexcept>
#include <vector>

#include "program_cache.h"
#include "util/test_overrides.h"

namespace sdf::cl {

DeviceState& state_of(const Device& device) {
  static std::mutex registry_mutex;
  static std::map<int, std::unique_ptr<DeviceState>> registry;
  static std::vector<std::unique_ptr<DeviceState>> set_aside;
  std::lock_guard<std::mutex> lock(registry_mutex);
  std::unique_ptr<DeviceState>& slot = registry[device.index];
  if (slot && slot->broken && slot->mutex.try_lock()) {  // nobody is computing on it now
    slot->mutex.unlock();
    set_aside.push_back(std::move(slot));
  }
  if (!slot) {
    auto s = std::make_unique<DeviceState>();
    const Api& cl = *api();
    cl_int err = CL_SUCCESS;
    const cl_context_properties props[] = {
        CL_CONTEXT_PLATFORM, reinterpret_cast<cl_context_properties>(device.platform), 0};
    s->context = cl.clCreateContext(props, 1, &device.id, nullptr, nullptr, &err);
    check(err, "clCreateContext");
    s->queue = cl.clCreateCommandQueue(s->context, device.id, 0, &err);
    check(err, "clCreateCommandQueue");
    s->stage_uploads = device.gpu;
    if (const std::size_t bytes = test_overrides().opencl_staging_chunk; bytes > 0) {
      s->stage_uploads = true;
      s->staging.set_chunk_bytes(bytes);
    }
    slot = std::move(s);
  }
  return *slot;
}

void write_buffer(cl_context context, cl_command_queue queue, Staging* staging, unsigned threads,
                  cl_mem destination, const void* data, std::size_t bytes) {
  if (bytes == 0) return;
  if (staging && staging->worth(bytes) &&
      staging->write(context, queue, destination, data, bytes, threads))
    return;
  check(api()->clEnqueueWriteBuffer(queue, destination, CL_FALSE, 0, bytes, data, 0, nullptr,
                                    nullptr),
        "clEnqueueWriteBuffer");
}

void upload_new(DeviceState& s, cl_command_queue queue, Staging* staging, unsigned threads,
                cl_mem& mem, const void* data, std::size_t bytes) {
  cl_int err = CL_SUCCESS;
  mem = api()->clCreateBuffer(s.context, CL_MEM_READ_ONLY, std::max<std::size_t>(bytes, 4), nullptr,
                              &err);
  if (err != CL_SUCCESS) mem = nullptr;
  check(err, "clCreateBuffer");
  write_buffer(s.context, queue, staging, threads, mem, data, bytes);
}

cl_command_queue side_queue(const Device& device, DeviceState& s) {
  if (!s.side_queue) {
    cl_int err = CL_SUCCESS;
    s.side_queue = api()->clCreateCommandQueue(s.context, device.id, 0, &err);
    check(err, "clCreateCommandQueue (side)");
  }
  return s.side_queue;
}

void read_buffer(DeviceState& s, cl_mem source, void* data, std::size_t bytes) {
  if (bytes == 0) return;
  if (s.stage_uploads && s.staging.worth(bytes) &&
      s.staging.read(s.context, s.queue, source, data, bytes, s.copy_threads))
    return;
  check(api()->clEnqueueReadBuffer(s.queue, source, CL_TRUE, 0, bytes, data, 0, nullptr, nullptr),
        "clEnqueueReadBuffer");
}

std::string build_options(const Device& device, int rays) {
  std::string options = "-cl-std=CL1.2 -DSDF_MAX_RAYS=" + std::to_string(std::max(rays, 1));
  cl_device_fp_config fp = 0;
  api()->clGetDeviceInfo(device.id, CL_DEVICE_SINGLE_FP_CONFIG, sizeof fp, &fp, nullptr);
  if (fp & CL_FP_CORRECTLY_ROUNDED_DIVIDE_SQRT)
    options += " -cl-fp32-correctly-rounded-divide-sqrt";
  // Benchmark override: more options for the device's compiler, e.g.
  // "-cl-nv-maxrregcount=40" or "-cl-nv-verbose" (the options are part of the program cache's
  // key).
  if (const std::string& extra = test_overrides().opencl_extra_options; !extra.empty())
    options += " " + extra;
  return options;
}

cl_program program_for(const Device& device, DeviceState& s, const std::string& options) {
  auto it = s.programs.find(options);
  if (it != s.programs.end()) return it->second;
  cl_program program = build_program(device, s.context, options);
  s.programs[options] = program;
  return program;
}

// Below 10 MiB in bytes: rounded to MiB, a need just over a small cap read "needs 1 MiB, the
// device has 1 MiB".
std::string mib(std::uint64_t bytes) {
  if (bytes < (std::uint64_t{10} << 20)) return std::to_string(bytes) + " bytes";
  return std::to_string((bytes + (1 << 20) - 1) >> 20) + " MiB";
}

void check_fits(const Device& device, const std::vector<std::size_t>& buffers, bool at_least,
                const std::string& advice) {
  std::uint64_t total = 0, largest = 0;
  for (std::size_t b : buffers) {
    total += b;
    largest = std::max<std::uint64_t>(largest, b);
  }
  if (largest > device.max_allocation || total > device.global_memory)
    throw Error("the mesh does not fit OpenCL device " + device.name + ": it needs " +
                    (at_least ? "at least " : "") + mib(total) + " (largest buffer " +
                    mib(largest) + "), the device has " + mib(device.global_memory) +
                    " (largest buffer " + mib(device.max_allocation) + "); use engine='cpu'" +
                    (advice.empty() ? "" : " or " + advice),
                CL_MEM_OBJECT_ALLOCATION_FAILURE);
}

}  // namespace sdf::cl
