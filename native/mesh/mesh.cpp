// SPDX-License-Identifier: GPL-3.0-or-later
#include "mesh/mesh.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "prepare/unit_scale.h"
#include "util/parallel.h"
#include "util/uninitialized_vector.h"

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

// Whether the vertex at p (x, y, z) has finite coordinates.
bool finite_vertex(const double* p) {
  return std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]);
}

// The box of the vertices the triangles with area use, with their marks; throws
// std::invalid_argument naming the first index out of range. The indices are checked and the
// vertices they use marked in one pass. A vertex no such triangle uses takes no part in the
// box: one far away would otherwise set the near-hit threshold and the unit scaling, and so
// every value (one unused vertex 10 mesh widths away changed values
// by up to 28%, 1e5 widths away zeroed them; a zero-area face reaching a vertex at the origin
// of a georeferenced building zeroed every value). A face has area where its cross product,
// in double, is not zero: exactly zero where corners coincide, zero or a rounding's worth
// (then the face counts) where they lie on one line. The corners of faces without area count
// only where no face has any (then every used vertex does).
// Each block of faces marks its own bit set, merged after: marks shared by all threads
// (atomic bytes) cost 3.3-4.6 ms on 1.21M faces on a 16-core host, most of it cache lines
// passed between cores (a subdivided mesh's faces use its first vertices everywhere).
struct UsedBox {
  std::vector<std::uint64_t> used;  // bit v % 64 of word v / 64: vertex v is used
  glm::dvec3 lo{std::numeric_limits<double>::infinity()};
  glm::dvec3 hi{-std::numeric_limits<double>::infinity()};

  bool is_used(std::size_t v) const { return (used[v / 64] >> (v % 64)) & 1u; }

  // copy_to, when set, receives the indices as 32 bits (make_mesh's triangles), in the same
  // pass that reads them.
  UsedBox(const double* vertices, std::size_t vertex_count, const std::int64_t* triangles,
          std::size_t triangle_count, unsigned threads, std::uint32_t* copy_to = nullptr) {
    const std::size_t words = (vertex_count + 63) / 64;
    auto point = [&](std::size_t i) {
      return glm::dvec3(vertices[3 * i], vertices[3 * i + 1], vertices[3 * i + 2]);
    };
    // At most 16 blocks: their sets take 16 x vertex_count / 8 bytes.
    const std::size_t blocks = std::max<std::size_t>(
        1, std::min<std::size_t>({resolve_threads(threads), 16, 3 * triangle_count / kGrain}));
    std::vector<std::uint64_t> marks(blocks * words, 0);
    std::vector<std::size_t> first_bad_of(blocks, kNoItem);
    std::vector<char> any_area_of(blocks, 0);
    // Marks the corners of faces with area, or (every_face) of every face.
    auto mark = [&](bool every_face) {
      parallel_for(blocks, 1, threads, [&](std::size_t b0, std::size_t b1) {
        for (std::size_t b = b0; b < b1; ++b) {
          std::uint64_t* mine = marks.data() + b * words;
          bool any_area = false;
          const std::size_t end = triangle_count * (b + 1) / blocks;
          for (std::size_t f = triangle_count * b / blocks; f < end; ++f) {
            const std::int64_t* corner = triangles + 3 * f;
            std::size_t bad = kNoItem;
            for (std::size_t c = 0; c < 3 && bad == kNoItem; ++c)
              if (corner[c] < 0 || static_cast<std::uint64_t>(corner[c]) >= vertex_count)
                bad = 3 * f + c;
            if (bad != kNoItem) {
              first_bad_of[b] = bad;
              break;
            }
            if (copy_to)
              for (std::size_t c = 0; c < 3; ++c)
                copy_to[3 * f + c] = static_cast<std::uint32_t>(corner[c]);
            bool counts = every_face;
            if (!every_face) {
              const glm::dvec3 a = point(static_cast<std::size_t>(corner[0]));
              const glm::dvec3 n = glm::cross(point(static_cast<std::size_t>(corner[1])) - a,
                                              point(static_cast<std::size_t>(corner[2])) - a);
              counts = n.x != 0.0 || n.y != 0.0 || n.z != 0.0;
              any_area = any_area || counts;
            }
            if (counts)
              for (std::size_t c = 0; c < 3; ++c) {
                const auto v = static_cast<std::size_t>(corner[c]);
                mine[v / 64] |= std::uint64_t{1} << (v % 64);
              }
          }
          any_area_of[b] = any_area;
        }
      });
    };
    mark(false);
    const bool any_area =
        std::any_of(any_area_of.begin(), any_area_of.end(), [](char a) { return a != 0; });
    const bool all_checked = std::all_of(first_bad_of.begin(), first_bad_of.end(),
                                         [](std::size_t i) { return i == kNoItem; });
    if (!any_area && all_checked) {
      copy_to = nullptr;  // copied already
      mark(true);
    }
    const std::size_t bad_index = *std::min_element(first_bad_of.begin(), first_bad_of.end());
    if (bad_index != kNoItem)
      throw std::invalid_argument("triangle " + std::to_string(bad_index / 3) +
                                  " uses vertex index " + std::to_string(triangles[bad_index]) +
                                  ", outside [0, " + std::to_string(vertex_count) + ")");
    // The marks merged, and per-chunk boxes merged (min and max of finite values are exact in
    // any order); chunks of whole words.
    used.resize(words);
    constexpr std::size_t kWordGrain = kGrain / 64;
    const std::size_t chunks = (words + kWordGrain - 1) / kWordGrain;
    std::vector<glm::dvec3> chunk_lo(chunks, lo), chunk_hi(chunks, hi);
    parallel_for(words, kWordGrain, threads, [&](std::size_t begin, std::size_t end) {
      glm::dvec3 l = lo, h = hi;
      for (std::size_t w = begin; w < end; ++w) {
        std::uint64_t bits = 0;
        for (std::size_t b = 0; b < blocks; ++b) bits |= marks[b * words + w];
        used[w] = bits;
        for (; bits != 0; bits &= bits - 1) {
          const std::size_t i = 64 * w + static_cast<std::size_t>(__builtin_ctzll(bits));
          l = glm::min(l, point(i));
          h = glm::max(h, point(i));
        }
      }
      chunk_lo[begin / kWordGrain] = l;
      chunk_hi[begin / kWordGrain] = h;
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

MeshValues mesh_values(const double* vertices, std::size_t vertex_count,
                       const std::int64_t* triangles, std::size_t triangle_count,
                       unsigned threads) {
  struct Part {
    std::size_t not_finite = 0, first = kNoItem;
    std::int64_t lo = std::numeric_limits<std::int64_t>::max();
    std::int64_t hi = std::numeric_limits<std::int64_t>::min();
  };
  // Chunks of vertices and of corners alike, each chunk its own part, merged in order.
  const std::size_t corners = 3 * triangle_count, items = std::max(vertex_count, corners);
  std::vector<Part> parts((items + kGrain - 1) / kGrain);
  parallel_for(items, kGrain, threads, [&](std::size_t begin, std::size_t end) {
    // Locals, not the part's fields, in the loops: they then vectorise (a store through the
    // part could alias the indices).
    std::size_t bad = 0;
    const std::size_t v_end = std::min(end, vertex_count);
    for (std::size_t i = begin; i < v_end; ++i) bad += !finite_vertex(vertices + 3 * i);
    Part& part = parts[begin / kGrain];
    part.not_finite = bad;
    for (std::size_t i = begin; bad > 0 && i < v_end; ++i)
      if (!finite_vertex(vertices + 3 * i)) {
        part.first = i;
        break;
      }
    std::int64_t lo = part.lo, hi = part.hi;
    for (std::size_t i = begin; i < std::min(end, corners); ++i) {
      lo = std::min(lo, triangles[i]);
      hi = std::max(hi, triangles[i]);
    }
    part.lo = lo;
    part.hi = hi;
  });
  MeshValues out;
  out.first_not_finite = kNoItem;
  std::int64_t lo = std::numeric_limits<std::int64_t>::max(),
               hi = std::numeric_limits<std::int64_t>::min();
  for (const Part& part : parts) {
    out.not_finite += part.not_finite;
    out.first_not_finite = std::min(out.first_not_finite, part.first);
    lo = std::min(lo, part.lo);
    hi = std::max(hi, part.hi);
  }
  if (out.not_finite == 0) out.first_not_finite = 0;
  if (corners > 0) out.min_index = lo, out.max_index = hi;
  return out;
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
  const std::size_t not_finite = first_bad(
      vertex_count, threads, [&](std::size_t i) { return !finite_vertex(vertices + 3 * i); });
  if (not_finite != kNoItem)
    throw std::invalid_argument("vertex " + std::to_string(not_finite) +
                                " has a coordinate that is not finite");
  Mesh mesh;
  mesh.triangles.resize(triangle_count);
  const UsedBox box(vertices, vertex_count, triangles, triangle_count, threads,
                    &mesh.triangles[0][0]);
  mesh.center = 0.5 * (box.lo + box.hi);
  mesh.max_extent = box.width();
  // The engines compute in 32-bit floats on coordinates centred on the box: past ~1e30 the
  // sums and differences of a centroid or an edge leave the float range (found by fuzzing).
  if (!(mesh.max_extent <= 1e30)) {
    char extent[32];
    std::snprintf(extent, sizeof extent, "%.3g", mesh.max_extent);
    throw std::invalid_argument(std::string("the mesh spans ") + extent +
                                " units on an axis, more than the 1e30 that 32-bit floats "
                                "leave room for; scale it down");
  }
  // An unused vertex (or one only faces without area use) is still stored (points='vertices'
  // gives it a value, and such a face's centroid is made of it): it must fit the
  // floats too, also once compute() has scaled a mesh far from unit size (unit_scale.h: a
  // tiny mesh's stray vertex would overflow; found by fuzzing).
  const double reach = std::min(1e30, std::ldexp(1e30, -unit_scale_exponent(mesh.max_extent)));
  const std::size_t too_far = first_bad(vertex_count, threads, [&](std::size_t i) {
    if (box.is_used(i)) return false;  // within the box
    const glm::dvec3 d = glm::abs(point(i) - mesh.center);
    return !(std::max(d.x, std::max(d.y, d.z)) <= reach);
  });
  if (too_far != kNoItem)
    throw std::invalid_argument("vertex " + std::to_string(too_far) +
                                ", used by no triangle with area, lies too far from the mesh "
                                "for 32-bit floats (more than 1e30 units, or 1e30 times the "
                                "mesh's width); remove it");
  mesh.vertices.resize(vertex_count);
  parallel_for(vertex_count, kGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) mesh.vertices[i] = glm::vec3(point(i) - mesh.center);
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

float minimum_closeness(const Mesh& mesh) {
  return static_cast<float>(kNearCutoffShare * mesh.max_extent);
}

}  // namespace sdf
