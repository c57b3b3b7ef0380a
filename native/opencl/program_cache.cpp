// SPDX-License-Identifier: GPL-3.0-or-later
#include "program_cache.h"

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <vector>

#include "cache_folder.h"
#include "kernel_source.h"

namespace sdf::cl {

namespace {

std::atomic<std::uint64_t> g_compiled{0}, g_from_cache{0};

constexpr char kMagic[8] = {'S', 'D', 'F', 'C', 'L', 'B', 'N', '1'};

// FNV-1a, 64 bits: a cache key and a checksum, not a defence against tampering.
std::uint64_t fnv1a(const void* data, std::size_t size, std::uint64_t h = 1469598103934665603ull) {
  const unsigned char* p = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < size; ++i) h = (h ^ p[i]) * 1099511628211ull;
  return h;
}
std::uint64_t fnv1a(const std::string& s, std::uint64_t h) {
  return fnv1a(s.data(), s.size() + 1, h);
}

std::string build_log(const Api& cl, cl_program program, cl_device_id device) {
  std::size_t size = 0;
  cl.clGetProgramBuildInfo(program, device, CL_PROGRAM_BUILD_LOG, 0, nullptr, &size);
  std::string log(size, '\0');
  if (size)
    cl.clGetProgramBuildInfo(program, device, CL_PROGRAM_BUILD_LOG, size, log.data(), nullptr);
  log.resize(std::strlen(log.c_str()));
  return log;
}

// The binary from a cache file, or empty when the file is missing or fails any check.
std::vector<unsigned char> read_cached(const std::filesystem::path& path, std::uint64_t key) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return {};
  char magic[8];
  std::uint64_t file_key = 0, size = 0, checksum = 0;
  in.read(magic, 8);
  in.read(reinterpret_cast<char*>(&file_key), 8);
  in.read(reinterpret_cast<char*>(&size), 8);
  in.read(reinterpret_cast<char*>(&checksum), 8);
  if (!in || std::memcmp(magic, kMagic, 8) != 0 || file_key != key || size == 0 ||
      size > (std::uint64_t(1) << 30))
    return {};
  std::vector<unsigned char> binary(size);
  in.read(reinterpret_cast<char*>(binary.data()), static_cast<std::streamsize>(size));
  if (!in || fnv1a(binary.data(), binary.size()) != checksum) return {};
  return binary;
}

// Writes through a temporary file and a rename, so a reader never sees half a file. A cache
// that cannot be written (read-only home, full disk) is not an error: the next run compiles.
void write_cached(const std::filesystem::path& path, std::uint64_t key,
                  const std::vector<unsigned char>& binary) {
  std::error_code ec;
  std::filesystem::create_directories(path.parent_path(), ec);
  const std::filesystem::path tmp = path.string() + ".tmp" + std::to_string(std::rand());
  {
    std::ofstream out(tmp, std::ios::binary);
    if (!out) return;
    const std::uint64_t size = binary.size(), checksum = fnv1a(binary.data(), binary.size());
    out.write(kMagic, 8);
    out.write(reinterpret_cast<const char*>(&key), 8);
    out.write(reinterpret_cast<const char*>(&size), 8);
    out.write(reinterpret_cast<const char*>(&checksum), 8);
    out.write(reinterpret_cast<const char*>(binary.data()), static_cast<std::streamsize>(size));
    if (!out) {
      std::filesystem::remove(tmp, ec);
      return;
    }
  }
  std::filesystem::rename(tmp, path, ec);
  if (ec) std::filesystem::remove(tmp, ec);
}

cl_program build_from_binary(const Api& cl, const Device& device, cl_context context,
                             const std::vector<unsigned char>& binary, const std::string& options) {
  const unsigned char* data = binary.data();
  const std::size_t size = binary.size();
  cl_int status = CL_SUCCESS, err = CL_SUCCESS;
  cl_program program =
      cl.clCreateProgramWithBinary(context, 1, &device.id, &size, &data, &status, &err);
  if (err != CL_SUCCESS || status != CL_SUCCESS) {
    if (program) cl.clReleaseProgram(program);
    return nullptr;
  }
  if (cl.clBuildProgram(program, 1, &device.id, options.c_str(), nullptr, nullptr) != CL_SUCCESS) {
    cl.clReleaseProgram(program);
    return nullptr;
  }
  return program;
}

}  // namespace

std::string cache_directory() {
  return cache_folder(
      host_cache_convention(), [](const char* name) { return std::getenv(name); },
      std::filesystem::temp_directory_path().string());
}

ProgramStats program_stats() { return ProgramStats{g_compiled.load(), g_from_cache.load()}; }

cl_program build_program(const Device& device, cl_context context, const std::string& options,
                         const char* source) {
  const Api& cl = *api();
  if (!source) source = kernel_source();
  std::uint64_t key = fnv1a(source, std::strlen(source));
  key = fnv1a(options, key);
  key = fnv1a(device.name, key);
  key = fnv1a(device.driver_version, key);
  key = fnv1a(device.platform_version, key);
  char name[32];
  std::snprintf(name, sizeof name, "%016llx.bin", static_cast<unsigned long long>(key));
  const std::filesystem::path path = std::filesystem::path(cache_directory()) / name;

  const std::vector<unsigned char> cached = read_cached(path, key);
  if (!cached.empty()) {
    if (cl_program program = build_from_binary(cl, device, context, cached, options)) {
      ++g_from_cache;
      return program;
    }
  }

  cl_int err = CL_SUCCESS;
  cl_program program = cl.clCreateProgramWithSource(context, 1, &source, nullptr, &err);
  check(err, "clCreateProgramWithSource");
  err = cl.clBuildProgram(program, 1, &device.id, options.c_str(), nullptr, nullptr);
  if (err != CL_SUCCESS) {
    const std::string log = build_log(cl, program, device.id);
    cl.clReleaseProgram(program);
    throw Error("OpenCL clBuildProgram failed: " + error_name(err) + " on " + device.name +
                    "; build log:\n" + log,
                err);
  }
  ++g_compiled;
  std::size_t size = 0;
  if (cl.clGetProgramInfo(program, CL_PROGRAM_BINARY_SIZES, sizeof size, &size, nullptr) ==
          CL_SUCCESS &&
      size > 0) {
    std::vector<unsigned char> binary(size);
    unsigned char* ptr = binary.data();
    if (cl.clGetProgramInfo(program, CL_PROGRAM_BINARIES, sizeof ptr, &ptr, nullptr) == CL_SUCCESS)
      write_cached(path, key, binary);
  }
  return program;
}

}  // namespace sdf::cl
