// SPDX-License-Identifier: GPL-3.0-or-later
// Benchmark tool: the interface between main.cpp (the host side, built with the core library)
// and cast_kernels.cu (the CUDA kernels). Plain types only: the two sides compile the shared
// structs differently (GLM on the host, CUDA vectors on the device), with the same bytes.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

struct CudaScene {
  const void* nodes = nullptr;  // SdfBvhNode[]
  std::size_t node_bytes = 0;
  const void* tris = nullptr;  // SdfTriangle[]
  std::size_t tri_bytes = 0;
  const float* origins = nullptr;  // 3 per point
  const float* axes = nullptr;
  const float* tangents = nullptr;
  const std::int32_t* own_face = nullptr;
  const std::uint32_t* order = nullptr;
  std::size_t points = 0;
  const float* ray_table = nullptr;  // 4 per ray: local direction, angle
  int rays = 30, sampling = 0;
  float one_minus_cos_half = 0, sin_half = 0, angle_floor = 0, tmin = 0;
  std::uint32_t seed = 0;
};

struct CudaResult {
  std::vector<float> raw;           // in launch (Morton) order, like the OpenCL engine's
  std::vector<std::int32_t> valid;
  float ms_median = 0, ms_min = 0;
  unsigned long long counters[5] = {0, 0, 0, 0, 0};  // inner, leaves, triangles, pushes, rays
};

std::vector<std::string> cuda_variant_names();
void cuda_print_attributes();
CudaResult cuda_cast(const CudaScene& scene, const std::string& variant, int reps);
