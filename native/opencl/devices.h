// SPDX-License-Identifier: GPL-3.0-or-later
// The OpenCL devices this machine offers, and how a user's engine string picks among them.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "cl_api.h"

namespace sdf::cl {

struct Device {
  cl_platform_id platform = nullptr;
  cl_device_id id = nullptr;
  int index = 0;  // position in devices(): "opencl:<index>"
  std::string name, platform_name, vendor, driver_version, device_version, platform_version;
  bool gpu = false;
  bool fp64 = false;  // double precision (cl_khr_fp64): texture smoothing's drawing needs it
  std::uint64_t global_memory = 0, max_allocation = 0;
  std::uint32_t compute_units = 0, clock_mhz = 0;
  std::size_t max_group = 0;  // work items a work group may hold (CL_DEVICE_MAX_WORK_GROUP_SIZE)
  // A rough throughput score to pick "the best" device: GPUs first, then units x clock.
  double score() const;
};

// Every device of every platform, in a stable order (platform, then device). Empty when
// OpenCL is not available; unavailable_reason() then says why.
const std::vector<Device>& devices();
std::string unavailable_reason();

// Whether this process was forked from one that had found an OpenCL GPU, which it cannot use.
bool gpu_lost_to_fork();

// Resolves an engine string to devices: "opencl" (the best device), "opencl:N" (the N-th of
// devices()), "opencl:all" (every GPU, or every device when there is no GPU), or
// "opencl:<text>" (the devices whose name contains <text>, case-insensitive; the first one).
// Throws std::invalid_argument naming the devices there are when nothing matches.
std::vector<const Device*> select_devices(const std::string& engine);

}  // namespace sdf::cl
