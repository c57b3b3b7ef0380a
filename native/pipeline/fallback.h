// SPDX-License-Identifier: GPL-3.0-or-later
// engine='auto''s promise: an OpenCL device that fails (cl::Error: a driver error, a device
// too small for the work) does not fail the call; the stage runs again on the CPU.
#pragma once

#include <string>

#ifdef SDF_HAVE_OPENCL
#include "opencl/cl_api.h"
#endif

namespace sdf {

// stage(engine); where `allowed` and engine is a device, a cl::Error runs stage("cpu"), sets
// `failure` to the error's first line and leaves `engine` at "cpu" for the stages after it.
// Any other exception (a cancel above all) propagates.
template <class Stage>
auto with_fallback(std::string& engine, bool allowed, std::string& failure, const Stage& stage) {
#ifdef SDF_HAVE_OPENCL
  try {
    return stage(engine);
  } catch (const cl::Error& error) {
    if (!allowed || engine == "cpu") throw;
    const std::string why = error.what();
    failure = why.substr(0, why.find('\n'));
    engine = "cpu";
  }
#else
  (void)allowed, (void)failure;
#endif
  return stage(engine);
}

}  // namespace sdf
