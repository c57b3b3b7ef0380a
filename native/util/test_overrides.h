// SPDX-License-Identifier: GPL-3.0-or-later
// Hooks that only tests and benchmarks set: they force a choice the product makes for itself
// (a kernel, where the tree is built, the CPU's SIMD width) or act out what a machine cannot
// be asked to do on cue (a lost device), so every path runs on the machines the tests have.
// Nothing in the product sets them; users have no way to, and need none. Tests and benchmarks
// set them through the Python module shape_diameter._testing (docs/testing.md), C++ tests
// directly.
//
// Thread safety: the fields are plain values, read without a lock by the computation's
// threads. Set them only while no computation runs in the process (between calls), from one
// thread; a computation sees the values it started with only if nobody writes during it.
#pragma once

#include <cstddef>
#include <string>

namespace sdf {

// The OpenCL cast kernel for accel='bvh' (opencl_engine.cpp, cast_kernel_for).
enum class KernelChoice {
  Engine,        // the engine's own choice per device (the default)
  BvhPerPoint,   // binary BVH, one work item per point
  Bvh4PerPoint,  // 4-wide BVH, one work item per point
  Bvh8PerPoint,  // 8-wide BVH, one work item per point
  BvhPerRay,     // binary BVH, one work item per ray
};

// Where the OpenCL engine's BVH is built (pipeline/sdf.cpp's plan).
enum class TreeChoice {
  Engine,  // the plan's own choice (the device for GPUs that cast per ray; the default)
  Host,    // always on the host
  Device,  // on the device, any device (PoCL included), when the cast could use it
};

struct TestOverrides {
  // bvh8_supported() answers false: the CPU engine casts the 4-wide SSE tree and CPU OpenCL
  // devices the 4-wide kernel, as on a CPU without AVX2. Read on every call.
  bool cpu_without_avx2 = false;
  // The BVH builder cuts no long thin triangles into pieces (accel/bvh_split.cpp), for the
  // benchmark comparing builds with and without. Read at each build.
  bool no_sliver_cutting = false;
  // The OpenCL cast kernel, on every device. Read at each computation.
  KernelChoice opencl_kernel = KernelChoice::Engine;
  // Where the OpenCL engine's BVH is built. Read at each computation.
  TreeChoice opencl_tree = TreeChoice::Engine;
  // More options for the OpenCL compiler, appended to the engine's (e.g. "-cl-nv-verbose" or
  // "-DSDF_LBVH_LEAF_SIZE=4"); part of the program cache's key. Read at each program build.
  std::string opencl_extra_options;
  // Bytes per staging chunk instead of 16 MiB, and uploads staged on every device, not only
  // on GPUs (opencl/staging.h): tiny chunks run the chunked paths on small meshes. 0: the
  // engine's own. Read when a device is first used in the process.
  std::size_t opencl_staging_chunk = 0;
  // Acts out a device lost (CL_DEVICE_NOT_AVAILABLE) after this many cast launches in a
  // computation, as a driver reset or an unplugged eGPU would. -1: never. Read at each cast.
  long opencl_lose_device_after = -1;
};

// The process's one set of overrides (one per copy of the core: each Python extension module
// links its own, and shape_diameter._testing sets them in both).
TestOverrides& test_overrides();

}  // namespace sdf
