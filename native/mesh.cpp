// SPDX-License-Identifier: GPL-3.0-or-later
#include "mesh.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "parallel.h"
#include "unit_scale.h"
#include "uninitialized_vector.h"

namespace sdf {

namespace {

// Items per parallel_for chunk: a few hundred microseconds of work each.
constexpr std::size_t kGrain = 1 << 15;
constexpr std::size_t kNoItem = static_cast<std::size_t>(-1);

// The smallest index in [0, count) for which bad(i) holds, or kNoItem; chunks in parallel,
// so that the error names the same item a serial scan would.
template <class Bad>
std::size_t first_bad(std::size_t count, unsigned threads, Bad&& bad) {
  std::vector<std::size_t> per_chunk((count + kGrain - 1) / kGrain, kNoItem);
  parallel_for(count, kGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i)
      if (bad(i)) {
        per_chunk[begin / kGrain] = i;
        return;
      }
  });
  for (std::size_t first : per_chunk)
    if (first != kNoItem) return first;
  return kNoItem;
}

// The box of the vertices the triangles use, with their marks; throws std::invalid_argument
// naming the first index out of range. The indices are checked and the vertices they use
// marked in one pass. A vertex no triangle uses takes no part in the box: one far away (a
// stray point at a georeferenced mesh's origin) would otherwise set the near-hit threshold
// and the unit scaling, and so every value (found by a new-user trial: one unused vertex 10
// mesh widths away changed values by up to 28%, 1e5 widths away zeroed them). The marks are
// atomic bytes: many threads mark a shared vertex, each mark written only while unset (H100
// host, 16 threads, 1.21M faces: make_mesh 2.0 ms without the marks, 5.0-5.5 with every
// corner's mark written, 4.1-4.6 so; boxing the corners' positions instead, read at random,
// 4.3-4.9, and 2.6x slower on one thread).
struct UsedBox {
  std::vector<std::atomic<std::uint8_t>> used;  // per vertex
  glm::dvec3 lo{std::numeric_limits<double>::infinity()};
  glm::dvec3 hi{-std::numeric_limits<double>::infinity()};

  UsedBox(const double* vertices, std::size_t vertex_count, const std::int64_t* triangles,
          std::size_t triangle_count, unsigned threads)
      : used(vertex_count) {  // zeroed
    const std::size_t bad_index = first_bad(3 * triangle_count, threads, [&](std::size_t i) {
      if (triangles[i] < 0 || static_cast<std::uint64_t>(triangles[i]) >= vertex_count)
        return true;
      auto& mark = used[static_cast<std::size_t>(triangles[i])];
      if (!mark.load(std::memory_order_relaxed)) mark.store(1, std::memory_order_relaxed);
      return false;
    });
    if (bad_index != kNoItem)
      throw std::invalid_argument("triangle " + std::to_string(bad_index / 3) +
                                  " uses vertex index " + std::to_string(triangles[bad_index]) +
                                  ", outside [0, " + std::to_string(vertex_count) + ")");
    // Per-chunk boxes merged (min and max of finite values are exact in any order).
    auto point = [&](std::size_t i) {
      return glm::dvec3(vertices[3 * i], vertices[3 * i + 1], vertices[3 * i + 2]);
    };
    const std::size_t chunks = (vertex_count + kGrain - 1) / kGrain;
    std::vector<glm::dvec3> chunk_lo(chunks, lo), chunk_hi(chunks, hi);
    parallel_for(vertex_count, kGrain, threads, [&](std::size_t begin, std::size_t end) {
      glm::dvec3 l = lo, h = hi;
      for (std::size_t i = begin; i < end; ++i)
        if (used[i].load(std::memory_order_relaxed)) {
          l = glm::min(l, point(i));
          h = glm::max(h, point(i));
        }
      chunk_lo[begin / kGrain] = l;
      chunk_hi[begin / kGrain] = h;
    });
    for (std::size_t c = 0; c < chunks; ++c) {
      lo = glm::min(lo, chunk_lo[c]);
      hi = glm::max(hi, chunk_hi[c]);
    }
  }
  // The box's largest side; 0 for no triangle.
  double width() const {
    if (!(lo.x <= hi.x)) return 0.0;
    const glm::dvec3 size = hi - lo;
    return std::max(size.x, std::max(size.y, size.z));
  }
};

}  // namespace

double used_width(const double* vertices, std::size_t vertex_count,
                  const std::int64_t* triangles, std::size_t triangle_count, unsigned threads) {
  return UsedBox(vertices, vertex_count, triangles, triangle_count, threads).width();
}

Mesh make_mesh(const double* vertices, std::size_t vertex_count, const std::int64_t* triangles,
               std::size_t triangle_count, unsigned threads) {
  if (vertex_count == 0) throw std::invalid_argument("the mesh has no vertices");
  if (triangle_count == 0) throw std::invalid_argument("the mesh has no triangles");
  if (vertex_count > std::numeric_limits<std::uint32_t>::max())
    throw std::invalid_argument("more than 2^32 - 1 vertices are not supported");
  // Corners are numbered 3 f + c in 32 bits (adjacency lists, UV islands).
  if (triangle_count > std::numeric_limits<std::uint32_t>::max() / 3)
    throw std::invalid_argument("more than " +
                                std::to_string(std::numeric_limits<std::uint32_t>::max() / 3) +
                                " triangles are not supported");

  auto point = [&](std::size_t i) {
    return glm::dvec3(vertices[3 * i], vertices[3 * i + 1], vertices[3 * i + 2]);
  };
  const std::size_t not_finite = first_bad(vertex_count, threads, [&](std::size_t i) {
    const glm::dvec3 p = point(i);
    return !std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z);
  });
  if (not_finite != kNoItem)
    throw std::invalid_argument("vertex " + std::to_string(not_finite) +
                                " has a coordinate that is not finite");
  const UsedBox box(vertices, vertex_count, triangles, triangle_count, threads);
  Mesh mesh;
  mesh.center = 0.5 * (box.lo + box.hi);
  mesh.max_extent = box.width();
  // The engines compute in 32-bit floats on coordinates centred on the box: past ~1e30 the
  // sums and differences of a centroid or an edge leave the float range (found by fuzzing).
  if (!(mesh.max_extent <= 1e30))
  {
    char extent[32];
    std::snprintf(extent, sizeof extent, "%.3g", mesh.max_extent);
    throw std::invalid_argument(std::string("the mesh spans ") + extent +
                                " units on an axis, more than the 1e30 that 32-bit floats "
                                "leave room for; scale it down");
  }
  // An unused vertex is still stored (points='vertices' gives it a value): it must fit the
  // floats too, also once compute() has scaled a mesh far from unit size (unit_scale.h: a
  // tiny mesh's stray vertex would overflow; found by fuzzing).
  const double reach = std::min(1e30, std::ldexp(1e30, -unit_scale_exponent(mesh.max_extent)));
  const std::size_t too_far = first_bad(vertex_count, threads, [&](std::size_t i) {
    if (box.used[i].load(std::memory_order_relaxed)) return false;  // within the box
    const glm::dvec3 d = glm::abs(point(i) - mesh.center);
    return !(std::max(d.x, std::max(d.y, d.z)) <= reach);
  });
  if (too_far != kNoItem)
    throw std::invalid_argument("vertex " + std::to_string(too_far) +
                                ", used by no triangle, lies too far from the mesh for 32-bit "
                                "floats (more than 1e30 units, or 1e30 times the mesh's "
                                "width); remove it");
  mesh.vertices.resize(vertex_count);
  parallel_for(vertex_count, kGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) mesh.vertices[i] = glm::vec3(point(i) - mesh.center);
  });
  mesh.triangles.resize(triangle_count);
  parallel_for(triangle_count, kGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t f = begin; f < end; ++f)
      for (int k = 0; k < 3; ++k)
        mesh.triangles[f][k] = static_cast<std::uint32_t>(triangles[3 * f + k]);
  });
  return mesh;
}

namespace {

template <class T>
void copy_in_parallel(const UninitializedVector<T>& from, UninitializedVector<T>& to,
                      unsigned threads) {
  to.resize(from.size());
  parallel_for(from.size(), kGrain, threads, [&](std::size_t begin, std::size_t end) {
    std::copy(from.begin() + begin, from.begin() + end, to.begin() + begin);
  });
}

}  // namespace

Mesh copy_mesh(const Mesh& mesh, unsigned threads) {
  Mesh copy;
  copy_in_parallel(mesh.vertices, copy.vertices, threads);
  copy_in_parallel(mesh.triangles, copy.triangles, threads);
  copy.center = mesh.center;
  copy.max_extent = mesh.max_extent;
  return copy;
}

float minimum_closeness(const Mesh& mesh) { return static_cast<float>(2e-5 * mesh.max_extent); }

}  // namespace sdf
