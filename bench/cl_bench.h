// SPDX-License-Identifier: GPL-3.0-or-later
// OpenCL helpers of the GPU benchmarks, on the product's loaded API (native/opencl/cl_api.h):
// a queue that records kernel times, those times, and programs built from a source string
// outside the product's program cache. Benchmark code only.
#pragma once

#include <string>

#include "opencl/device_state.h"

namespace bench {

// A second queue on the device's context, with profiling, so kernel times come from the
// device's own clock (CL_PROFILING_COMMAND_START to END) and not from the host's.
inline cl_command_queue profiling_queue(const sdf::cl::Device& device, cl_context context) {
  cl_int err = CL_SUCCESS;
  cl_command_queue queue =
      sdf::cl::api()->clCreateCommandQueue(context, device.id, CL_QUEUE_PROFILING_ENABLE, &err);
  sdf::cl::check(err, "clCreateCommandQueue (profiling)");
  return queue;
}

// Milliseconds the command of `event` ran on the device; releases the event.
inline double event_ms(cl_event event) {
  const sdf::cl::Api& cl = *sdf::cl::api();
  sdf::cl::check(cl.clWaitForEvents(1, &event), "clWaitForEvents");
  cl_ulong start = 0, end = 0;
  sdf::cl::check(
      cl.clGetEventProfilingInfo(event, CL_PROFILING_COMMAND_START, sizeof start, &start, nullptr),
      "clGetEventProfilingInfo");
  sdf::cl::check(
      cl.clGetEventProfilingInfo(event, CL_PROFILING_COMMAND_END, sizeof end, &end, nullptr),
      "clGetEventProfilingInfo");
  cl.clReleaseEvent(event);
  return (end - start) * 1e-6;
}

// A program built from `source` with `options`; throws sdf::cl::Error with the build log.
inline cl_program program_from_source(const sdf::cl::Device& device, cl_context context,
                                      const std::string& source, const std::string& options) {
  const sdf::cl::Api& cl = *sdf::cl::api();
  const char* text = source.c_str();
  cl_int err = CL_SUCCESS;
  cl_program program = cl.clCreateProgramWithSource(context, 1, &text, nullptr, &err);
  sdf::cl::check(err, "clCreateProgramWithSource");
  err = cl.clBuildProgram(program, 1, &device.id, options.c_str(), nullptr, nullptr);
  if (err != CL_SUCCESS) {
    std::size_t size = 0;
    cl.clGetProgramBuildInfo(program, device.id, CL_PROGRAM_BUILD_LOG, 0, nullptr, &size);
    std::string log(size, '\0');
    if (size)
      cl.clGetProgramBuildInfo(program, device.id, CL_PROGRAM_BUILD_LOG, size, log.data(), nullptr);
    cl.clReleaseProgram(program);
    throw sdf::cl::Error("clBuildProgram (" + options + ") failed:\n" + log, err);
  }
  return program;
}

}  // namespace bench
