// SPDX-License-Identifier: GPL-3.0-or-later
// Internal to the OpenCL smoothing (opencl_smoothing.cpp, opencl_projected.cpp): the program
// their kernels live in, launches, blocking reads, and a guard that waits for a queue when an
// exception unwinds.
#pragma once

#include <algorithm>
#include <cstddef>
#include <exception>

#include "device_state.h"

namespace sdf::cl {

// The smoothing kernels do not depend on SDF_MAX_RAYS: any program already built for the
// device has them, so a compute() followed by smoothing builds (or loads) nothing more. With
// none yet, the program for the default 30 rays (what a later compute() will most likely
// need).
inline cl_program smoothing_program(const Device& device, DeviceState& s) {
  if (!s.programs.empty()) return s.programs.begin()->second;
  return program_for(device, s, build_options(device, 30));
}

inline void launch(DeviceState& s, const Kernel& kernel, cl_uint dims, const std::size_t* global,
                   const std::size_t* local) {
  check(api()->clEnqueueNDRangeKernel(s.queue, kernel.get(), dims, nullptr, global, local, 0,
                                      nullptr, nullptr),
        "clEnqueueNDRangeKernel");
}

inline void read(DeviceState& s, const Buffer& buffer, std::size_t bytes, void* out) {
  check(api()->clEnqueueReadBuffer(s.queue, buffer.get(), CL_TRUE, 0, bytes, out, 0, nullptr,
                                   nullptr),
        "clEnqueueReadBuffer");
}

// Launches `kernel` over [0, count) items, one work item each, in launches of at most
// `chunk` items (short ones: display watchdogs), with arguments 0 and 1 set to each launch's
// first item and size. Work-group size as for casting: 64 on GPUs, 1 on CPUs (PoCL
// vectorises a group as a loop, which divergent loops defeat).
inline void launch_chunks(const Device& device, DeviceState& s, Kernel& kernel, std::size_t count,
                          std::size_t chunk) {
  const std::size_t local = device.gpu ? 64 : 1;
  for (std::size_t first = 0; first < count; first += chunk) {
    const std::size_t n = std::min(chunk, count - first);
    kernel.arg(0, static_cast<cl_uint>(first));
    kernel.arg(1, static_cast<cl_uint>(n));
    const std::size_t global = (n + local - 1) / local * local;
    launch(s, kernel, 1, &global, &local);
  }
}

// 2-D global size rounded up to the local size (8 x 8 on GPUs; the driver's choice on CPUs).
inline void image_launch(const Device& device, DeviceState& s, const Kernel& kernel, int width,
                         int height) {
  if (device.gpu) {
    const std::size_t local[2] = {8, 8};
    const std::size_t global[2] = {(static_cast<std::size_t>(width) + 7) / 8 * 8,
                                   (static_cast<std::size_t>(height) + 7) / 8 * 8};
    launch(s, kernel, 2, global, local);
  } else {
    const std::size_t global[2] = {static_cast<std::size_t>(width),
                                   static_cast<std::size_t>(height)};
    launch(s, kernel, 2, global, nullptr);
  }
}

// Waits for the queue when an exception leaves the scope it guards: transfers queued there
// without blocking still read or write host memory that the unwinding is about to free.
class FinishOnUnwind {
 public:
  explicit FinishOnUnwind(cl_command_queue queue)
      : queue_(queue), exceptions_(std::uncaught_exceptions()) {}
  ~FinishOnUnwind() {
    if (std::uncaught_exceptions() > exceptions_ && !forked_after_load())
      api()->clFinish(queue_);  // errors ignored
  }
  FinishOnUnwind(const FinishOnUnwind&) = delete;
  FinishOnUnwind& operator=(const FinishOnUnwind&) = delete;

 private:
  cl_command_queue queue_;
  int exceptions_;
};

}  // namespace sdf::cl
