// SPDX-License-Identifier: GPL-3.0-or-later
// The OpenCL entry points the engine uses, loaded at run time with dlopen. Linking libOpenCL
// would make the module fail to import where no ICD loader is installed (common on Blender
// users' machines); loading it late turns "no OpenCL" into an engine that is not listed.
#pragma once

#define CL_TARGET_OPENCL_VERSION 120
#include <CL/cl.h>

#include <stdexcept>
#include <string>

namespace sdf::cl {

#define SDF_CL_FUNCTIONS(X)    \
  X(clGetPlatformIDs)          \
  X(clGetPlatformInfo)         \
  X(clGetDeviceIDs)            \
  X(clGetDeviceInfo)           \
  X(clCreateContext)           \
  X(clReleaseContext)          \
  X(clCreateCommandQueue)      \
  X(clReleaseCommandQueue)     \
  X(clCreateProgramWithSource) \
  X(clCreateProgramWithBinary) \
  X(clBuildProgram)            \
  X(clGetProgramBuildInfo)     \
  X(clGetProgramInfo)          \
  X(clReleaseProgram)          \
  X(clCreateKernel)            \
  X(clReleaseKernel)           \
  X(clGetKernelWorkGroupInfo)  \
  X(clSetKernelArg)            \
  X(clCreateBuffer)            \
  X(clReleaseMemObject)        \
  X(clEnqueueWriteBuffer)      \
  X(clEnqueueMapBuffer)        \
  X(clEnqueueUnmapMemObject)   \
  X(clWaitForEvents)           \
  X(clGetEventProfilingInfo)   \
  X(clReleaseEvent)            \
  X(clEnqueueReadBuffer)       \
  X(clEnqueueNDRangeKernel)    \
  X(clFinish)

struct Api {
#define SDF_CL_MEMBER(name) decltype(&::name) name = nullptr;
  SDF_CL_FUNCTIONS(SDF_CL_MEMBER)
#undef SDF_CL_MEMBER
};

// The loaded API, or nullptr when no OpenCL library can be loaded; `why` says what failed.
// Loads once; later calls return the same answer. Thread-safe.
const Api* api(std::string* why = nullptr);

// True in a process forked from one that had loaded OpenCL: the driver's threads did not come
// along while its locks and handles did, and any call can hang for ever (fork-started Pool
// workers did). Such a process lists no device and releases nothing.
bool forked_after_load();

// What a forked process is told instead of its parent's devices.
extern const char* const kForkedReason;

// "CL_OUT_OF_RESOURCES" for -5, and so on; "CL error N" for codes it does not know.
std::string error_name(cl_int code);

// Throws sdf::cl::Error naming the call and the error code unless code == CL_SUCCESS.
void check(cl_int code, const char* call);

struct Error : std::runtime_error {
  Error(const std::string& message, cl_int code) : std::runtime_error(message), code(code) {}
  cl_int code;
};

}  // namespace sdf::cl
