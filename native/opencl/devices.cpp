// SPDX-License-Identifier: GPL-3.0-or-later
#include "devices.h"

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <stdexcept>
#include <string>

namespace sdf::cl {

namespace {

std::string platform_string(const Api& cl, cl_platform_id p, cl_platform_info what) {
  std::size_t size = 0;
  if (cl.clGetPlatformInfo(p, what, 0, nullptr, &size) != CL_SUCCESS || size == 0) return "";
  std::string s(size, '\0');
  cl.clGetPlatformInfo(p, what, size, s.data(), nullptr);
  s.resize(std::strlen(s.c_str()));
  return s;
}

std::string device_string(const Api& cl, cl_device_id d, cl_device_info what) {
  std::size_t size = 0;
  if (cl.clGetDeviceInfo(d, what, 0, nullptr, &size) != CL_SUCCESS || size == 0) return "";
  std::string s(size, '\0');
  cl.clGetDeviceInfo(d, what, size, s.data(), nullptr);
  s.resize(std::strlen(s.c_str()));
  return s;
}

template <class T>
T device_value(const Api& cl, cl_device_id d, cl_device_info what) {
  T value{};
  cl.clGetDeviceInfo(d, what, sizeof(T), &value, nullptr);
  return value;
}

// SDF_OPENCL_MAX_MEMORY's value into *bytes: a plain count of bytes, or false. strtoull alone
// read "1e9" as 1 byte, "2G" as 2, "abc" as 0 and "-5" as no cap at all.
bool read_memory_cap(const char* text, std::uint64_t* bytes) {
  const std::string value(text);
  if (value.empty() || !std::all_of(value.begin(), value.end(),
                                    [](unsigned char c) { return std::isdigit(c) != 0; }))
    return false;
  errno = 0;
  *bytes = std::strtoull(value.c_str(), nullptr, 10);
  return errno != ERANGE;
}

struct Found {
  std::vector<Device> devices;
  std::string why;
};

// Set once a GPU was found; read in a forked process, which must not enumerate again.
std::atomic<bool> found_a_gpu{false};

Found enumerate() {
  Found found;
  // SDF_OPENCL_MAX_MEMORY (bytes) caps what the engine may use on every device: to leave room
  // for other programs, and to test the out-of-memory refusal on a small mesh. A value that
  // is no count of bytes makes OpenCL unavailable, saying why ('auto' then runs on the CPU).
  std::uint64_t cap = UINT64_MAX;
  if (const char* text = std::getenv("SDF_OPENCL_MAX_MEMORY");
      text && *text && !read_memory_cap(text, &cap)) {
    found.why = std::string("SDF_OPENCL_MAX_MEMORY='") + text +
                "' is not a number of bytes (digits only, e.g. 2000000000)";
    return found;
  }
  const Api* cl = api(&found.why);
  if (!cl) return found;
  cl_uint platform_count = 0;
  cl_int err = cl->clGetPlatformIDs(0, nullptr, &platform_count);
  if (err != CL_SUCCESS || platform_count == 0) {
    found.why = "no OpenCL platform is installed (clGetPlatformIDs: " + error_name(err) + ")";
    return found;
  }
  std::vector<cl_platform_id> platforms(platform_count);
  cl->clGetPlatformIDs(platform_count, platforms.data(), nullptr);
  for (cl_platform_id p : platforms) {
    cl_uint count = 0;
    if (cl->clGetDeviceIDs(p, CL_DEVICE_TYPE_ALL, 0, nullptr, &count) != CL_SUCCESS) continue;
    std::vector<cl_device_id> ids(count);
    cl->clGetDeviceIDs(p, CL_DEVICE_TYPE_ALL, count, ids.data(), nullptr);
    for (cl_device_id id : ids) {
      if (!device_value<cl_bool>(*cl, id, CL_DEVICE_AVAILABLE) ||
          !device_value<cl_bool>(*cl, id, CL_DEVICE_COMPILER_AVAILABLE))
        continue;
      Device d;
      d.platform = p;
      d.id = id;
      d.index = static_cast<int>(found.devices.size());
      d.name = device_string(*cl, id, CL_DEVICE_NAME);
      d.vendor = device_string(*cl, id, CL_DEVICE_VENDOR);
      d.driver_version = device_string(*cl, id, CL_DRIVER_VERSION);
      d.device_version = device_string(*cl, id, CL_DEVICE_VERSION);
      d.platform_name = platform_string(*cl, p, CL_PLATFORM_NAME);
      d.platform_version = platform_string(*cl, p, CL_PLATFORM_VERSION);
      d.gpu = (device_value<cl_device_type>(*cl, id, CL_DEVICE_TYPE) & CL_DEVICE_TYPE_GPU) != 0;
      d.global_memory = device_value<cl_ulong>(*cl, id, CL_DEVICE_GLOBAL_MEM_SIZE);
      d.max_allocation = device_value<cl_ulong>(*cl, id, CL_DEVICE_MAX_MEM_ALLOC_SIZE);
      d.compute_units = device_value<cl_uint>(*cl, id, CL_DEVICE_MAX_COMPUTE_UNITS);
      d.max_group = device_value<std::size_t>(*cl, id, CL_DEVICE_MAX_WORK_GROUP_SIZE);
      d.fp64 = device_value<cl_device_fp_config>(*cl, id, CL_DEVICE_DOUBLE_FP_CONFIG) != 0;
      d.clock_mhz = device_value<cl_uint>(*cl, id, CL_DEVICE_MAX_CLOCK_FREQUENCY);
      d.global_memory = std::min<std::uint64_t>(d.global_memory, cap);
      d.max_allocation = std::min<std::uint64_t>(d.max_allocation, cap);
      found.devices.push_back(d);
    }
  }
  if (found.devices.empty())
    found.why = "OpenCL platforms are installed but offer no usable device";
  for (const Device& d : found.devices) found_a_gpu = found_a_gpu || d.gpu;
  return found;
}

const Found& found() {
  static const Found f = enumerate();
  return f;
}

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

std::string listing() {
  std::string s;
  for (const Device& d : devices())
    s += (s.empty() ? "" : ", ") + std::string("opencl:") + std::to_string(d.index) + " (" +
         d.name + ")";
  return s.empty() ? "none (" + unavailable_reason() + ")" : s;
}

}  // namespace

double Device::score() const { return (gpu ? 1e12 : 0.0) + double(compute_units) * clock_mhz; }

const std::vector<Device>& devices() {
  static const std::vector<Device> none;
  return forked_after_load() ? none : found().devices;
}

std::string unavailable_reason() { return forked_after_load() ? kForkedReason : found().why; }

bool gpu_lost_to_fork() { return forked_after_load() && found_a_gpu; }

std::vector<const Device*> select_devices(const std::string& engine) {
  const std::vector<Device>& all = devices();
  const std::string prefix = "opencl";
  if (engine.compare(0, prefix.size(), prefix) != 0)
    throw std::invalid_argument("not an OpenCL engine: '" + engine + "'");
  if (all.empty()) throw std::invalid_argument("OpenCL is not available: " + unavailable_reason());
  std::vector<const Device*> chosen;
  if (engine == "opencl") {
    chosen.push_back(
        &*std::max_element(all.begin(), all.end(),
                           [](const Device& a, const Device& b) { return a.score() < b.score(); }));
    return chosen;
  }
  if (engine.size() < prefix.size() + 2 || engine[prefix.size()] != ':')
    throw std::invalid_argument("unknown engine '" + engine +
                                "'; OpenCL devices here: " + listing());
  const std::string what = engine.substr(prefix.size() + 1);
  if (what == "all") {
    for (const Device& d : all)
      if (d.gpu) chosen.push_back(&d);
    if (chosen.empty())
      for (const Device& d : all) chosen.push_back(&d);
    return chosen;
  }
  if (std::all_of(what.begin(), what.end(), [](unsigned char c) { return std::isdigit(c); })) {
    const std::size_t n = std::stoul(what);
    if (n >= all.size())
      throw std::invalid_argument("no OpenCL device " + what + "; devices here: " + listing());
    chosen.push_back(&all[n]);
    return chosen;
  }
  for (const Device& d : all)
    if (lower(d.name).find(lower(what)) != std::string::npos) {
      chosen.push_back(&d);
      return chosen;
    }
  throw std::invalid_argument("no OpenCL device matches '" + what +
                              "'; devices here: " + listing());
}

}  // namespace sdf::cl
