// SPDX-License-Identifier: GPL-3.0-or-later
#include "cache_folder.h"

#include <initializer_list>

namespace sdf::cl {

namespace {

// base joined with parts, one separator between each (none doubled where base ends in one).
std::string join(std::string base, std::initializer_list<const char*> parts, char separator) {
  for (const char* part : parts) {
    if (!base.empty() && base.back() != '/' && base.back() != separator) base += separator;
    base += part;
  }
  return base;
}

// The value of a variable that is set and not empty, else null.
const char* value(const EnvLookup& env, const char* name) {
  const char* text = env(name);
  return text && *text ? text : nullptr;
}

}  // namespace

CacheConvention host_cache_convention() {
#if defined(_WIN32)
  return CacheConvention::kWindows;
#elif defined(__APPLE__)
  return CacheConvention::kMacOS;
#else
  return CacheConvention::kXdg;
#endif
}

std::string cache_folder(CacheConvention convention, const EnvLookup& env,
                         const std::string& temp) {
  const char separator = convention == CacheConvention::kWindows ? '\\' : '/';
  if (const char* dir = value(env, "SDF_CACHE_DIR")) return join(dir, {"opencl"}, separator);
  switch (convention) {
    case CacheConvention::kWindows:
      if (const char* local = value(env, "LOCALAPPDATA"))
        return join(local, {"shape_diameter", "opencl"}, separator);
      break;
    case CacheConvention::kMacOS:
      if (const char* home = value(env, "HOME"))
        return join(home, {"Library", "Caches", "shape_diameter", "opencl"}, separator);
      break;
    case CacheConvention::kXdg:
      if (const char* xdg = value(env, "XDG_CACHE_HOME"))
        return join(xdg, {"shape_diameter", "opencl"}, separator);
      if (const char* home = value(env, "HOME"))
        return join(home, {".cache", "shape_diameter", "opencl"}, separator);
      break;
  }
  return join(temp, {"shape_diameter", "opencl"}, separator);
}

}  // namespace sdf::cl
