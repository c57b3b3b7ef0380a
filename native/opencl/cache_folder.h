// SPDX-License-Identifier: GPL-3.0-or-later
// Where the compiled OpenCL programs are kept, by each system's convention for per-user
// caches. A pure function of the convention and the environment's values, so that every
// platform's answer is tested on any one.
#pragma once

#include <functional>
#include <string>

namespace sdf::cl {

enum class CacheConvention {
  kXdg,      // Linux and other Unix: $XDG_CACHE_HOME, else ~/.cache
  kMacOS,    // ~/Library/Caches
  kWindows,  // %LOCALAPPDATA% (the local, not roaming, profile: caches do not roam)
};

// The convention of the system this was compiled for.
CacheConvention host_cache_convention();

// An environment variable's value, or null when it is unset.
using EnvLookup = std::function<const char*(const char* name)>;

// The program cache folder: $SDF_CACHE_DIR/opencl where set (every system), else
// <the convention's cache folder>/shape_diameter/opencl, else <temp>/shape_diameter/opencl
// when the variables the convention reads are unset or empty. Parts are joined with the
// convention's separator ('\\' on Windows, '/' elsewhere).
std::string cache_folder(CacheConvention convention, const EnvLookup& env, const std::string& temp);

}  // namespace sdf::cl
