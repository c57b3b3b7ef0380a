// SPDX-License-Identifier: GPL-3.0-or-later
#include "cl_api.h"

#if defined(_WIN32)
#define NOMINMAX
#define WIN32_LEAN_AND_MEAN
#include <windows.h>
#else
#include <dlfcn.h>
#include <pthread.h>
#endif

#include <atomic>
#include <cstdlib>
#include <mutex>

namespace sdf::cl {

const char* const kForkedReason =
    "OpenCL cannot be used in a process forked from one that had used it (its driver's threads "
    "do not survive a fork); start worker processes with multiprocessing's 'spawn' or "
    "'forkserver' method, or fork before the first use of OpenCL";

namespace {

std::atomic<bool> forked{false};

[[maybe_unused]] void mark_forked() { forked.store(true, std::memory_order_relaxed); }

struct Loaded {
  Api api;
  bool ok = false;
  std::string why;
};

// The OpenCL loader where each system puts it: the ICD loader on Linux (and other Unix), the
// system framework on macOS, OpenCL.dll (installed with the GPU driver) on Windows.
#if defined(_WIN32)
const char* const kLibraryNames[] = {"OpenCL.dll"};
void* open_library(const char* name) { return reinterpret_cast<void*>(LoadLibraryA(name)); }
void* find_symbol(void* library, const char* name) {
  return reinterpret_cast<void*>(GetProcAddress(static_cast<HMODULE>(library), name));
}
std::string open_error() { return "Windows error " + std::to_string(GetLastError()); }
#else
#if defined(__APPLE__)
const char* const kLibraryNames[] = {"/System/Library/Frameworks/OpenCL.framework/OpenCL"};
#else
const char* const kLibraryNames[] = {"libOpenCL.so.1", "libOpenCL.so"};
#endif
void* open_library(const char* name) { return dlopen(name, RTLD_NOW | RTLD_LOCAL); }
void* find_symbol(void* library, const char* name) { return dlsym(library, name); }
std::string open_error() {
  const char* err = dlerror();
  return err ? err : "unknown";
}
#endif

Loaded load() {
  Loaded loaded;
  // SDF_OPENCL_LIBRARY: a user setting for an OpenCL loader outside the library path
  // (docs/python.md); tests set a path that does not exist to act out "no OpenCL".
  void* handle = nullptr;
  if (const char* forced = std::getenv("SDF_OPENCL_LIBRARY")) {
    handle = open_library(forced);
  } else {
    for (const char* name : kLibraryNames) {
      if ((handle = open_library(name))) break;
    }
  }
  if (!handle) {
    loaded.why = "no OpenCL library could be loaded (" + open_error() + ")";
    return loaded;
  }
#define SDF_CL_RESOLVE(name)                                                         \
  loaded.api.name = reinterpret_cast<decltype(&::name)>(find_symbol(handle, #name)); \
  if (!loaded.api.name) {                                                            \
    loaded.why = "the OpenCL library lacks " #name;                                  \
    return loaded;                                                                   \
  }
  SDF_CL_FUNCTIONS(SDF_CL_RESOLVE)
#undef SDF_CL_RESOLVE
#if !defined(_WIN32)  // (Windows has no fork)
  pthread_atfork(nullptr, nullptr, mark_forked);
#endif
  loaded.ok = true;
  return loaded;
}

}  // namespace

bool forked_after_load() { return forked.load(std::memory_order_relaxed); }

const Api* api(std::string* why) {
  static const Loaded loaded = load();
  if (why) *why = loaded.why;
  return loaded.ok ? &loaded.api : nullptr;
}

std::string error_name(cl_int code) {
  switch (code) {
#define SDF_CL_CASE(c) \
  case c: return #c;
    SDF_CL_CASE(CL_SUCCESS)
    SDF_CL_CASE(CL_DEVICE_NOT_FOUND)
    SDF_CL_CASE(CL_DEVICE_NOT_AVAILABLE)
    SDF_CL_CASE(CL_COMPILER_NOT_AVAILABLE)
    SDF_CL_CASE(CL_MEM_OBJECT_ALLOCATION_FAILURE)
    SDF_CL_CASE(CL_OUT_OF_RESOURCES)
    SDF_CL_CASE(CL_OUT_OF_HOST_MEMORY)
    SDF_CL_CASE(CL_PROFILING_INFO_NOT_AVAILABLE)
    SDF_CL_CASE(CL_MEM_COPY_OVERLAP)
    SDF_CL_CASE(CL_IMAGE_FORMAT_MISMATCH)
    SDF_CL_CASE(CL_IMAGE_FORMAT_NOT_SUPPORTED)
    SDF_CL_CASE(CL_BUILD_PROGRAM_FAILURE)
    SDF_CL_CASE(CL_MAP_FAILURE)
    SDF_CL_CASE(CL_MISALIGNED_SUB_BUFFER_OFFSET)
    SDF_CL_CASE(CL_EXEC_STATUS_ERROR_FOR_EVENTS_IN_WAIT_LIST)
    SDF_CL_CASE(CL_COMPILE_PROGRAM_FAILURE)
    SDF_CL_CASE(CL_LINKER_NOT_AVAILABLE)
    SDF_CL_CASE(CL_LINK_PROGRAM_FAILURE)
    SDF_CL_CASE(CL_DEVICE_PARTITION_FAILED)
    SDF_CL_CASE(CL_KERNEL_ARG_INFO_NOT_AVAILABLE)
    SDF_CL_CASE(CL_INVALID_VALUE)
    SDF_CL_CASE(CL_INVALID_DEVICE_TYPE)
    SDF_CL_CASE(CL_INVALID_PLATFORM)
    SDF_CL_CASE(CL_INVALID_DEVICE)
    SDF_CL_CASE(CL_INVALID_CONTEXT)
    SDF_CL_CASE(CL_INVALID_QUEUE_PROPERTIES)
    SDF_CL_CASE(CL_INVALID_COMMAND_QUEUE)
    SDF_CL_CASE(CL_INVALID_HOST_PTR)
    SDF_CL_CASE(CL_INVALID_MEM_OBJECT)
    SDF_CL_CASE(CL_INVALID_IMAGE_FORMAT_DESCRIPTOR)
    SDF_CL_CASE(CL_INVALID_IMAGE_SIZE)
    SDF_CL_CASE(CL_INVALID_SAMPLER)
    SDF_CL_CASE(CL_INVALID_BINARY)
    SDF_CL_CASE(CL_INVALID_BUILD_OPTIONS)
    SDF_CL_CASE(CL_INVALID_PROGRAM)
    SDF_CL_CASE(CL_INVALID_PROGRAM_EXECUTABLE)
    SDF_CL_CASE(CL_INVALID_KERNEL_NAME)
    SDF_CL_CASE(CL_INVALID_KERNEL_DEFINITION)
    SDF_CL_CASE(CL_INVALID_KERNEL)
    SDF_CL_CASE(CL_INVALID_ARG_INDEX)
    SDF_CL_CASE(CL_INVALID_ARG_VALUE)
    SDF_CL_CASE(CL_INVALID_ARG_SIZE)
    SDF_CL_CASE(CL_INVALID_KERNEL_ARGS)
    SDF_CL_CASE(CL_INVALID_WORK_DIMENSION)
    SDF_CL_CASE(CL_INVALID_WORK_GROUP_SIZE)
    SDF_CL_CASE(CL_INVALID_WORK_ITEM_SIZE)
    SDF_CL_CASE(CL_INVALID_GLOBAL_OFFSET)
    SDF_CL_CASE(CL_INVALID_EVENT_WAIT_LIST)
    SDF_CL_CASE(CL_INVALID_EVENT)
    SDF_CL_CASE(CL_INVALID_OPERATION)
    SDF_CL_CASE(CL_INVALID_GL_OBJECT)
    SDF_CL_CASE(CL_INVALID_BUFFER_SIZE)
    SDF_CL_CASE(CL_INVALID_MIP_LEVEL)
    SDF_CL_CASE(CL_INVALID_GLOBAL_WORK_SIZE)
    SDF_CL_CASE(CL_INVALID_PROPERTY)
    SDF_CL_CASE(CL_INVALID_IMAGE_DESCRIPTOR)
    SDF_CL_CASE(CL_INVALID_COMPILER_OPTIONS)
    SDF_CL_CASE(CL_INVALID_LINKER_OPTIONS)
    SDF_CL_CASE(CL_INVALID_DEVICE_PARTITION_COUNT)
#undef SDF_CL_CASE
    case -1001: return "CL_PLATFORM_NOT_FOUND_KHR";
    default: return "CL error " + std::to_string(code);
  }
}

void check(cl_int code, const char* call) {
  if (code != CL_SUCCESS)
    throw Error(std::string("OpenCL ") + call + " failed: " + error_name(code), code);
}

}  // namespace sdf::cl
