// SPDX-License-Identifier: GPL-3.0-or-later
// Internal to the OpenCL engine: the per-device context, queue and program cache, and small
// RAII wrappers for kernels and buffers, shared by the casting (opencl_engine.cpp) and the
// smoothing (opencl_smoothing.cpp) host code.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <map>
#include <mutex>
#include <string>
#include <vector>

#include "devices.h"
#include "staging.h"

namespace sdf::cl {

// A context, a queue and the programs built so far for one device, kept for the life of the
// process: a second compute() in the same process neither recompiles nor reloads.
struct DeviceState {
  cl_context context = nullptr;
  cl_command_queue queue = nullptr;
  std::map<std::string, cl_program> programs;
  // Large uploads to a GPU go through it (write_buffer); CPU devices read host memory.
  bool stage_uploads = false;
  Staging staging;
  unsigned copy_threads = 0;  // host threads its copies may use: the computation's `threads`
  std::mutex mutex;           // one computation at a time per device; guards all of the above
  // A second queue, for uploads made while a computation holds `mutex` and its queue
  // (opencl_smoothing.h: upload_prepared_texture); made on first use, guarded by side_mutex.
  cl_command_queue side_queue = nullptr;
  Staging side_staging;  // for the side queue's uploads
  std::mutex side_mutex;
  // Set when an OpenCL call failed while computing (a lost device, a driver reset): the next
  // computation gets a fresh context and queue instead of this one.
  std::atomic<bool> broken{false};
};

// The device's state; a fresh one when the last computation on it failed. A broken state is
// never released (its driver objects may be dead): it is set aside.
DeviceState& state_of(const Device& device);

// -cl-fp32-correctly-rounded-divide-sqrt where the device offers it: with it, division and
// square root round as on the host (OpenCL otherwise allows 2.5 and 3 ulp).
std::string build_options(const Device& device, int rays);

cl_program program_for(const Device& device, DeviceState& s, const std::string& options);

class Kernel {
 public:
  Kernel(cl_program program, const char* name) {
    cl_int err = CL_SUCCESS;
    kernel_ = api()->clCreateKernel(program, name, &err);
    check(err, "clCreateKernel");
  }
  ~Kernel() {
    if (!forked_after_load()) api()->clReleaseKernel(kernel_);
  }
  Kernel(const Kernel&) = delete;
  Kernel& operator=(const Kernel&) = delete;
  template <class T>
  void arg(cl_uint index, const T& value) {
    check(api()->clSetKernelArg(kernel_, index, sizeof(T), &value), "clSetKernelArg");
  }
  // The largest work group this kernel can run with on `device` (registers limit it).
  std::size_t max_group(cl_device_id device) const {
    std::size_t size = 0;
    check(api()->clGetKernelWorkGroupInfo(kernel_, device, CL_KERNEL_WORK_GROUP_SIZE, sizeof size,
                                          &size, nullptr),
          "clGetKernelWorkGroupInfo");
    return size;
  }
  // A __local array of `bytes` for argument `index`.
  void local_arg(cl_uint index, std::size_t bytes) {
    check(api()->clSetKernelArg(kernel_, index, bytes, nullptr), "clSetKernelArg");
  }
  cl_kernel get() const { return kernel_; }

 private:
  cl_kernel kernel_ = nullptr;
};

// Queues the upload of `bytes` from `data` into `destination` on `queue`, through `staging`
// (null: none) with `threads` copying where that is faster (then `data` may change once this
// returns); otherwise non-blocking, so `data` must stay unchanged until the queue has run it
// (a later blocking read or clFinish).
void write_buffer(cl_context context, cl_command_queue queue, Staging* staging, unsigned threads,
                  cl_mem destination, const void* data, std::size_t bytes);

// The same on the state's queue, through its staging where uploads are staged.
inline void write_buffer(DeviceState& s, cl_mem destination, const void* data, std::size_t bytes) {
  write_buffer(s.context, s.queue, s.stage_uploads ? &s.staging : nullptr, s.copy_threads,
               destination, data, bytes);
}

// A new read-only buffer, set into `mem` before anything can fail after its creation (its
// owner releases it also when the write fails), holding `bytes` of `data` written as
// write_buffer writes them on `queue` through `staging` (not waiting).
void upload_new(DeviceState& s, cl_command_queue queue, Staging* staging, unsigned threads,
                cl_mem& mem, const void* data, std::size_t bytes);

// The state's side queue, made on first use. Call it holding s.side_mutex.
cl_command_queue side_queue(const Device& device, DeviceState& s);

// Reads `bytes` of `source` into `data` on the state's queue, waiting for them: through its
// staging where uploads are staged and it is worth it (the copy out on s.copy_threads).
void read_buffer(DeviceState& s, cl_mem source, void* data, std::size_t bytes);

class Buffer {
 public:
  Buffer(DeviceState& s, std::size_t bytes, const void* data) {
    cl_int err = CL_SUCCESS;
    // Zero-sized buffers are invalid in OpenCL; an empty array still gets one word.
    const std::size_t size = std::max<std::size_t>(bytes, 4);
    mem_ = api()->clCreateBuffer(s.context, CL_MEM_READ_WRITE, size, nullptr, &err);
    check(err, "clCreateBuffer");
    if (data && bytes) write_buffer(s, mem_, data, bytes);
  }
  ~Buffer() {
    if (!forked_after_load()) api()->clReleaseMemObject(mem_);
  }
  Buffer(const Buffer&) = delete;
  Buffer& operator=(const Buffer&) = delete;
  cl_mem get() const { return mem_; }

 private:
  cl_mem mem_ = nullptr;
};

template <class T, class Allocator>
std::size_t bytes_of(const std::vector<T, Allocator>& v) {
  return v.size() * sizeof(T);
}

std::string mib(std::uint64_t bytes);

// Refuses, before allocating anything, a scene that cannot fit the device: throws Error
// (CL_MEM_OBJECT_ALLOCATION_FAILURE; engine='auto' then runs on the CPU). at_least: `buffers`
// are only the first of a run's (the message says "at least"). advice: what else would help,
// after "use engine='cpu'".
void check_fits(const Device& device, const std::vector<std::size_t>& buffers,
                bool at_least = false, const std::string& advice = "");

}  // namespace sdf::cl
