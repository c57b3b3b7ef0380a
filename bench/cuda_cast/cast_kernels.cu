// SPDX-License-Identifier: GPL-3.0-or-later
// Benchmark tool, never part of the product: the OpenCL engine's per-ray BVH cast kernel
// (kernels/sdf_kernels.cl, sdf_cast_bvh_per_ray) as CUDA, from the same shared headers, so that
// Nsight Compute can profile it, plus variants of the traversal to test what the profile points
// at. Every variant must give the CPU engine's bits; main.cpp checks that.
#include "cuda_compat.h"  // first: takes sdf_compat.h's place

#include "../../kernels/sdf_bvh_traverse.h"
#include "../../kernels/sdf_reduce.h"

#include <algorithm>
#include <cstdio>
#include <vector>

#include "cast_kernels.h"

#define CK(call)                                                                    \
  do {                                                                              \
    cudaError_t e_ = (call);                                                        \
    if (e_ != cudaSuccess) {                                                        \
      std::fprintf(stderr, "CUDA error %s at %s:%d: %s\n", cudaGetErrorName(e_),    \
                   __FILE__, __LINE__, cudaGetErrorString(e_));                     \
      std::exit(1);                                                                 \
    }                                                                               \
  } while (0)

namespace {


// Traversal counters (variant "count"): per ray.
struct Counters {
  unsigned long long inner, leaves, tris, pushes, rays;
};

// The binary BVH traversal as kernels/sdf_bvh_traverse.h had it before 16-byte loads
// (commit 579c5e9), with a choice of where the stack lives:
// SHS > 0 keeps its first SHS entries in shared memory (entry k of this thread at
// sh[k * stride]), deeper ones in the local-memory arrays; COUNT adds traversal counters.
// LDG4: node boxes read as two 16-byte loads each. The visiting order is the header's.
template <int SHS, bool COUNT, bool LDG4>
__device__ __forceinline__ SdfHit trav(const SdfBvhNode* __restrict__ nodes,
                                       const SdfTriangle* __restrict__ tris, float3 o, float3 d,
                                       float tmin, int skip_id, int2* sh, int stride,
                                       unsigned* cnt) {
  SdfHit hit = sdf_no_hit();
  float3 inv_d = sdf_safe_inverse(d, o);
  int stack_node[SDF_BVH_STACK_SIZE];
  float stack_entry[SDF_BVH_STACK_SIZE];
  int sp = 0;
  int index = 0;
  auto push = [&](int node, float entry) {
    if (SHS > 0 && sp < SHS) {
      sh[sp * stride] = make_int2(node, __float_as_int(entry));
    } else {
      stack_node[sp] = node;
      stack_entry[sp] = entry;
    }
    ++sp;
    if (COUNT) ++cnt[3];
  };
  auto entry_at = [&](int k) -> float {
    if (SHS > 0 && k < SHS) return __int_as_float(sh[k * stride].y);
    return stack_entry[k];
  };
  auto node_at = [&](int k) -> int {
    if (SHS > 0 && k < SHS) return sh[k * stride].x;
    return stack_node[k];
  };
  auto box = [&](int i, float tmax) -> float {
    if (LDG4) {
      const float4* p = reinterpret_cast<const float4*>(nodes + i);
      float4 a = __ldg(p), b = __ldg(p + 1);
      SdfBvhNode n;
      n.lo_x = a.x; n.lo_y = a.y; n.lo_z = a.z;
      n.hi_x = b.x; n.hi_y = b.y; n.hi_z = b.z;
      return sdf_box_entry(&n, o, inv_d, tmax);
    }
    return sdf_box_entry(&nodes[i], o, inv_d, tmax);
  };
  if (box(0, hit.t) == INFINITY) return hit;
  for (;;) {
    const SdfBvhNode* node = &nodes[index];
    int count, first;
    if (LDG4) {
      int2 fc = make_int2(__ldg(&node->first), __ldg(&node->count));
      first = fc.x;
      count = fc.y;
    } else {
      count = node->count;
      first = node->first;
    }
    if (count > 0) {
      if (COUNT) ++cnt[1];
      for (int k = first; k < first + count; ++k) {
        if (COUNT) ++cnt[2];
        if (tris[k].id != skip_id) sdf_intersect_triangle(o, d, tmin, &tris[k], &hit);
      }
    } else {
      if (COUNT) ++cnt[0];
      int left = first;
      float t_left = box(left, hit.t);
      float t_right = box(left + 1, hit.t);
      if (t_left != INFINITY || t_right != INFINITY) {
        if (t_left == INFINITY) {
          index = left + 1;
        } else if (t_right == INFINITY) {
          index = left;
        } else if (t_left <= t_right) {
          push(left + 1, t_right);
          index = left;
        } else {
          push(left, t_left);
          index = left + 1;
        }
        continue;
      }
    }
    for (;;) {
      if (sp == 0) return hit;
      --sp;
      if (entry_at(sp) <= hit.t) break;
    }
    index = node_at(sp);
  }
}

// SDF_CAST_PER_RAY_BODY of kernels/sdf_kernels.cl, line for line. V: 0 = the header's
// traversal; 1 = trav<...> with the template arguments below. PPG points per block (the
// OpenCL engine: 4), MINB the blocks per SM asked of the register allocator (1: no cap).
// PSORT: the kept rays ranked in parallel before the reduction (sdf_kernels.cl since 5c4e0b6+1).
template <int V, int SHS, bool COUNT, bool LDG4, int MINB, int PPG, bool PSORT>
__global__ void __launch_bounds__(PPG * 32, MINB)
    cast_per_ray(const SdfBvhNode* __restrict__ nodes, const SdfTriangle* __restrict__ tris,
                 const float* __restrict__ origins, const float* __restrict__ axes,
                 const float* __restrict__ tangents, const int* __restrict__ own_face,
                 const unsigned* __restrict__ order, const float4* __restrict__ local_rays,
                 SdfCastParams params, float* __restrict__ raw, int* __restrict__ valid_rays,
                 unsigned long long* __restrict__ counters) {
  extern __shared__ float smem[];
  float* ray_t = smem;
  const unsigned arrays = PSORT ? 2 * blockDim.x : blockDim.x;  // each array's floats
  float* ray_angle = smem + arrays;
  int2* sh_stack = reinterpret_cast<int2*>(smem + 2 * arrays);
  unsigned lid = threadIdx.x;
  unsigned group_points = blockDim.x / params.rays;
  unsigned slot = lid / params.rays;
  int r = (int)(lid % params.rays);
  unsigned gid = blockIdx.x * group_points + slot;
  float t_kept = -1.0f;
  float angle = 0.0f;
  unsigned p = 0;
  float3 axis = make_float3(0.0f, 0.0f, 0.0f);
  unsigned cnt[4] = {0, 0, 0, 0};
  if (gid < params.count && r < params.rays) {
    p = order[params.first + gid];
    axis = make_float3(axes[3 * p], axes[3 * p + 1], axes[3 * p + 2]);
  }
  if (axis.x != 0.0f || axis.y != 0.0f || axis.z != 0.0f) {
    float3 origin = make_float3(origins[3 * p], origins[3 * p + 1], origins[3 * p + 2]);
    int own = own_face[p];
    float3 b1, b2;
    sdf_frame(params.sampling, axis,
              make_float3(tangents[3 * p], tangents[3 * p + 1], tangents[3 * p + 2]), &b1, &b2);
    float4 table = local_rays[r];
    angle = table.w;
    float3 d = sdf_to_world(make_float3(table.x, table.y, table.z), b1, b2, axis);
    SdfHit hit;
    if (V == 0) {
      hit = sdf_bvh_closest_hit_units(reinterpret_cast<const float4*>(nodes),
                                      reinterpret_cast<const float4*>(tris), 0, origin, d,
                                      params.tmin, own);
    } else {
      hit = trav<SHS, COUNT, LDG4>(nodes, tris, origin, d, params.tmin, own, sh_stack + lid,
                                   blockDim.x, cnt);
    }
    if (sdf_exit_hit(hit)) t_kept = hit.t;
    if (COUNT) {
      atomicAdd(&counters[0], (unsigned long long)cnt[0]);
      atomicAdd(&counters[1], (unsigned long long)cnt[1]);
      atomicAdd(&counters[2], (unsigned long long)cnt[2]);
      atomicAdd(&counters[3], (unsigned long long)cnt[3]);
      atomicAdd(&counters[4], 1ull);
    }
  }
  ray_t[lid] = t_kept;
  ray_angle[lid] = angle;
  __syncthreads();
  if (PSORT) {
    unsigned group_size = blockDim.x;
    if (t_kept >= 0.0f) {
      unsigned base = slot * params.rays;
      int rank = 0;
      for (int k = 0; k < params.rays; ++k) {
        float t = ray_t[base + k];
        rank += t >= 0.0f && (t < t_kept || (t == t_kept && k < r));
      }
      ray_t[group_size + base + rank] = t_kept;
      ray_angle[group_size + base + rank] = angle;
    }
    __syncthreads();
  }
  slot = lid;
  gid = blockIdx.x * group_points + slot;
  if (lid >= group_points || gid >= params.count) return;
  float lengths[SDF_MAX_RAYS];
  float angles[SDF_MAX_RAYS];
  int kept = 0;
  if (PSORT) {
    for (int k = 0; k < params.rays; ++k) kept += ray_t[slot * params.rays + k] >= 0.0f;
    for (int k = 0; k < kept; ++k) {
      unsigned at = blockDim.x + slot * params.rays + k;
      lengths[k] = ray_t[at];
      angles[k] = ray_angle[at];
    }
  } else {
    for (int k = 0; k < params.rays; ++k) {
      unsigned at = slot * params.rays + k;
      float t = ray_t[at];
      if (t >= 0.0f) {
        lengths[kept] = t;
        angles[kept] = ray_angle[at];
        ++kept;
      }
    }
  }
  unsigned out = params.first + gid;
  raw[out] = sdf_reduce(params.sampling, lengths, angles, kept, params.angle_floor);
  valid_rays[out] = kept;
}

struct VariantDef {
  const char* name;
  const void* fn;
  int shs;
  int ppg;
  bool psort;
};

#define VARS(NAME, V, SHS, COUNT, LDG4, MINB, PPG, PSORT)                                   \
  {NAME, reinterpret_cast<const void*>(&cast_per_ray<V, SHS, COUNT, LDG4, MINB, PPG, PSORT>), \
   SHS, PPG, PSORT}
#define VARP(NAME, V, SHS, COUNT, LDG4, MINB, PPG) VARS(NAME, V, SHS, COUNT, LDG4, MINB, PPG, false)
#define VAR(NAME, V, SHS, COUNT, LDG4, MINB) VARP(NAME, V, SHS, COUNT, LDG4, MINB, 4)

const VariantDef kVariants[] = {
    VAR("new", 0, 0, false, false, 1),           // the header's traversal (16-byte loads)
    VARS("new_psort", 0, 0, false, false, 1, 4, true),  // + rays ranked before the reduction
    VAR("old", 1, 0, false, false, 1),           // the traversal before (commit 579c5e9)
    VARS("old_psort", 1, 0, false, false, 1, 4, true),
    VAR("count", 1, 0, true, false, 1),          // old + traversal counters
    VAR("old_ldg4", 1, 0, false, true, 1),       // old with node boxes as 16-byte loads
    VARS("old_ldg4_psort", 1, 0, false, true, 1, 4, true),
    VAR("new_minb8", 0, 0, false, false, 8),     // <= 64 registers
    VARS("new_psort_minb10", 0, 0, false, false, 10, 4, true),  // <= 48 registers
    VARS("new_psort_ppg8", 0, 0, false, false, 1, 8, true),  // 8 points (240 items) per block
    VARS("new_psort_ppg2", 0, 0, false, false, 1, 2, true),  // 2 points (60 items) per block
};

}  // namespace

std::vector<std::string> cuda_variant_names() {
  std::vector<std::string> names;
  for (const VariantDef& v : kVariants) names.push_back(v.name);
  return names;
}

void cuda_print_attributes() {
  for (const VariantDef& v : kVariants) {
    cudaFuncAttributes a;
    CK(cudaFuncGetAttributes(&a, v.fn));
    std::printf("  %-12s regs %3d  local(stack) %5zu B  static shared %zu B\n", v.name,
                a.numRegs, a.localSizeBytes, a.sharedSizeBytes);
  }
}

CudaResult cuda_cast(const CudaScene& s, const std::string& variant, int reps) {
  const VariantDef* def = nullptr;
  for (const VariantDef& v : kVariants)
    if (variant == v.name) def = &v;
  if (!def) {
    std::fprintf(stderr, "unknown variant %s\n", variant.c_str());
    std::exit(2);
  }
  auto up = [](const void* host, std::size_t bytes) {
    void* p = nullptr;
    CK(cudaMalloc(&p, bytes));
    CK(cudaMemcpy(p, host, bytes, cudaMemcpyHostToDevice));
    return p;
  };
  const std::size_t n = s.points;
  void* nodes = up(s.nodes, s.node_bytes);
  void* tris = up(s.tris, s.tri_bytes);
  void* origins = up(s.origins, 12 * n);
  void* axes = up(s.axes, 12 * n);
  void* tangents = up(s.tangents, 12 * n);
  void* own = up(s.own_face, 4 * n);
  void* order = up(s.order, 4 * n);
  void* table = up(s.ray_table, 16 * s.rays);
  float* raw = nullptr;
  int* valid = nullptr;
  unsigned long long* counters = nullptr;
  CK(cudaMalloc(&raw, 4 * n));
  CK(cudaMalloc(&valid, 4 * n));
  CK(cudaMalloc(&counters, 8 * 8));
  CK(cudaMemset(counters, 0, 64));

  SdfCastParams params{};
  params.rays = s.rays;
  params.sampling = s.sampling;
  params.one_minus_cos_half = s.one_minus_cos_half;
  params.sin_half = s.sin_half;
  params.angle_floor = s.angle_floor;
  params.seed = s.seed;
  params.tmin = s.tmin;
  params.first = 0;
  params.count = static_cast<unsigned>(n);
  const unsigned block = def->ppg * s.rays;
  const unsigned grid = static_cast<unsigned>((n + def->ppg - 1) / def->ppg);
  const std::size_t shared = 2 * (def->psort ? 2 : 1) * block * sizeof(float) +
                             def->shs * block * sizeof(int2);
  if (shared > 48 * 1024)
    CK(cudaFuncSetAttribute(def->fn, cudaFuncAttributeMaxDynamicSharedMemorySize, (int)shared));
  void* args[] = {&nodes, &tris, &origins, &axes, &tangents, &own, &order, &table,
                  &params, &raw, &valid, &counters};
  CudaResult result;
  cudaEvent_t e0, e1;
  CK(cudaEventCreate(&e0));
  CK(cudaEventCreate(&e1));
  std::vector<float> times;
  for (int rep = 0; rep < std::max(reps, 1); ++rep) {
    CK(cudaMemset(raw, 0xff, 4 * n));  // poison: NaN
    CK(cudaMemset(valid, 0xff, 4 * n));
    if (rep == 0) CK(cudaMemset(counters, 0, 64));
    CK(cudaEventRecord(e0));
    CK(cudaLaunchKernel(def->fn, dim3(grid), dim3(block), args, shared, 0));
    CK(cudaGetLastError());
    CK(cudaEventRecord(e1));
    CK(cudaEventSynchronize(e1));
    float ms = 0;
    CK(cudaEventElapsedTime(&ms, e0, e1));
    times.push_back(ms);
    if (rep == 0) {
      unsigned long long c[8];
      CK(cudaMemcpy(c, counters, 64, cudaMemcpyDeviceToHost));
      for (int i = 0; i < 5; ++i) result.counters[i] = c[i];
    }
  }
  std::sort(times.begin(), times.end());
  result.ms_median = times[times.size() / 2];
  result.ms_min = times.front();
  result.raw.resize(n);
  result.valid.resize(n);
  CK(cudaMemcpy(result.raw.data(), raw, 4 * n, cudaMemcpyDeviceToHost));
  CK(cudaMemcpy(result.valid.data(), valid, 4 * n, cudaMemcpyDeviceToHost));
  for (void* p : {nodes, tris, origins, axes, tangents, own, order, table}) CK(cudaFree(p));
  CK(cudaFree(raw));
  CK(cudaFree(valid));
  CK(cudaFree(counters));
  CK(cudaEventDestroy(e0));
  CK(cudaEventDestroy(e1));
  return result;
}
