// SPDX-License-Identifier: GPL-3.0-or-later
// Builds the kernel program for a device, keeping compiled binaries on disk so a second run
// does not compile again. Key: device name, driver version, platform version, build options
// and a hash of the source. A cache file that is unreadable, truncated, corrupt or refused by
// the driver is rebuilt from source and rewritten, never trusted.
#pragma once

#include <cstdint>
#include <string>

#include "devices.h"

namespace sdf::cl {

// The folder compiled programs are kept in, by this system's convention (cache_folder.h):
// $SDF_CACHE_DIR/opencl, else .../shape_diameter/opencl in $XDG_CACHE_HOME or ~/.cache
// (Linux), ~/Library/Caches (macOS), %LOCALAPPDATA% (Windows).
std::string cache_directory();

struct ProgramStats {
  std::uint64_t compiled = 0;    // programs built from source
  std::uint64_t from_cache = 0;  // programs loaded from a cache file
};
ProgramStats program_stats();

// A built program for `device` in `context`. Throws Error with the build log on failure.
// `source` defaults to the embedded kernels; tests pass their own.
cl_program build_program(const Device& device, cl_context context, const std::string& options,
                         const char* source = nullptr);

}  // namespace sdf::cl
