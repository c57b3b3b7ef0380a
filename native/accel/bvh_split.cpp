// SPDX-License-Identifier: GPL-3.0-or-later
#include "accel/bvh_split.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <vector>

#include <glm/glm.hpp>

#include "util/parallel.h"
#include "util/test_overrides.h"

namespace sdf::bvh_build {

namespace {

// A triangle is cut when its box's half area exceeds kCutAbove times its area, into as many
// pieces as bring each piece's ratio near kPieceRatio. Ratios up to 3 come from the shape
// of a triangle in general position; kCutAbove leaves every mesh of well-shaped triangles as
// it was.
constexpr float kCutAbove = 64.0f;
constexpr float kPieceRatio = 4.0f;
// Added references at most this share of the triangles (each costs a reference in both
// build buffers, a triangle record and about two nodes).
constexpr double kBudget = 2.0;
constexpr std::size_t kChunk = 8192;

using dvec3 = glm::dvec3;

// Sutherland-Hodgman: the polygon `in` (n corners) cut to the side of the plane
// coordinate[axis] = value that `below` names; at most n + 1 corners.
int clip_plane(const dvec3* in, int n, int axis, double value, bool below, dvec3* out) {
  int m = 0;
  for (int i = 0; i < n; ++i) {
    const dvec3& a = in[i];
    const dvec3& b = in[(i + 1) % n];
    const bool a_in = below ? a[axis] <= value : a[axis] >= value;
    const bool b_in = below ? b[axis] <= value : b[axis] >= value;
    if (a_in) out[m++] = a;
    if (a_in != b_in) {
      const double s = (value - a[axis]) / (b[axis] - a[axis]);
      dvec3 p = a + s * (b - a);
      p[axis] = value;  // on the plane exactly
      out[m++] = p;
    }
  }
  return m;
}

// The box of the part of the triangle inside `box`, rounded outward to floats and kept
// within `box`: it holds every point of the triangle that lies in `box`. Falls back to `box`
// itself when rounding left no part.
Box clipped_box(const dvec3 corners[3], const Box& box) {
  dvec3 polygon[2][9];
  std::copy(corners, corners + 3, polygon[0]);
  int n = 3, from = 0;
  for (int axis = 0; axis < 3 && n > 0; ++axis)
    for (const bool below : {false, true}) {
      if (n == 0) break;
      const double value = below ? box.hi[axis] : box.lo[axis];
      n = clip_plane(polygon[from], n, axis, value, below, polygon[1 - from]);
      from = 1 - from;
    }
  if (n == 0) return box;
  dvec3 lo = polygon[from][0], hi = polygon[from][0];
  for (int i = 1; i < n; ++i) {
    lo = glm::min(lo, polygon[from][i]);
    hi = glm::max(hi, polygon[from][i]);
  }
  // The corners made on a plane are rounded in double (a few ulps of the largest coordinate
  // of the triangle; a review found one 1e-17 inside the exact part): widened by more than
  // that before the outward rounding to floats.
  double largest = 0.0;
  for (int k = 0; k < 3; ++k)
    largest = std::max(
        {largest, std::fabs(corners[k].x), std::fabs(corners[k].y), std::fabs(corners[k].z)});
  const double slack = 64.0 * std::numeric_limits<double>::epsilon() * largest;
  lo -= slack;
  hi += slack;
  Box out;
  for (int a = 0; a < 3; ++a) {
    float l = static_cast<float>(lo[a]), h = static_cast<float>(hi[a]);
    if (double(l) > lo[a]) l = std::nextafter(l, -std::numeric_limits<float>::infinity());
    if (double(h) < hi[a]) h = std::nextafter(h, std::numeric_limits<float>::infinity());
    // + 0: a -0 becomes +0, as make_references' boxes (a reversed face gives the same).
    out.lo[a] = std::max(l, box.lo[a]) + 0.0f;
    out.hi[a] = std::min(h, box.hi[a]) + 0.0f;
  }
  return out;
}

// Writes `pieces` references of triangle `id`, halving `box` along its longest axis.
void cut(const dvec3 corners[3], const Box& box, int pieces, std::uint32_t id, PrimRef*& out) {
  if (pieces == 1) {
    *out++ = PrimRef{box.lo, id, box.hi, 0u};
    return;
  }
  const glm::vec3 extent = box.hi - box.lo;
  const int axis =
      extent.x >= extent.y ? (extent.x >= extent.z ? 0 : 2) : (extent.y >= extent.z ? 1 : 2);
  const float mid = 0.5f * (box.lo[axis] + box.hi[axis]);
  Box below = box, above = box;
  below.hi[axis] = mid;
  above.lo[axis] = mid;
  cut(corners, clipped_box(corners, below), pieces / 2, id, out);
  cut(corners, clipped_box(corners, above), pieces / 2, id, out);
}

// The largest cap on the piece level whose added references fit the budget (and leave the
// nodes, about two a reference, within the int32 indices of SdfBvhNode).
int piece_cap(const PieceCounts& wanted, std::size_t count) {
  const double budget =
      std::min(kBudget * static_cast<double>(count),
               double(std::numeric_limits<std::int32_t>::max() / 4) - static_cast<double>(count));
  for (int cap = kPieceLevels - 1; cap > 0; --cap) {
    double added = 0.0;
    for (int k = 1; k < kPieceLevels; ++k)
      added += static_cast<double>(wanted[k]) * ((1u << std::min(k, cap)) - 1u);
    if (added <= budget) return cap;
  }
  return 0;
}

}  // namespace

int wanted_piece_level(const Box& box, float twice_area) {
  const float ratio = 2.0f * box.half_area() / twice_area;
  if (!(ratio > kCutAbove)) return 0;
  int level = 1;
  while (level < kPieceLevels - 1 && ratio > kPieceRatio * float(1 << level)) ++level;
  return level;
}

std::size_t split_slivers(const Mesh& mesh, const PieceCounts& wanted, std::size_t count,
                          unsigned threads, UninitializedVector<PrimRef>& refs,
                          UninitializedVector<PrimRef>& scratch, Range& root) {
  // No cutting at all for bench/slivers.py's comparison (a test override).
  const int cap = test_overrides().no_sliver_cutting ? 0 : piece_cap(wanted, count);
  if (cap == 0) return count;
  const std::size_t chunks = (count + kChunk - 1) / kChunk;
  auto pieces_of = [&](const PrimRef& r) {
    return std::size_t(1) << std::min<std::uint32_t>(r.bins, static_cast<std::uint32_t>(cap));
  };
  std::vector<std::size_t> offset(chunks + 1, 0);
  parallel_for(chunks, 1, threads, [&](std::size_t b, std::size_t e) {
    for (std::size_t c = b; c < e; ++c) {
      std::size_t n = 0;
      for (std::size_t i = c * kChunk; i < std::min(count, (c + 1) * kChunk); ++i)
        n += pieces_of(refs[i]);
      offset[c + 1] = n;
    }
  });
  std::partial_sum(offset.begin(), offset.end(), offset.begin());
  const std::size_t total = offset[chunks];
  UninitializedVector<PrimRef> out(total);
  std::vector<Box> chunk_centroids(chunks);
  parallel_for(chunks, 1, threads, [&](std::size_t b, std::size_t e) {
    for (std::size_t c = b; c < e; ++c) {
      PrimRef* next = out.data() + offset[c];
      for (std::size_t i = c * kChunk; i < std::min(count, (c + 1) * kChunk); ++i) {
        const PrimRef& r = refs[i];
        const std::size_t pieces = pieces_of(r);
        if (pieces == 1) {
          *next = r;
          (next++)->bins = 0;
          continue;
        }
        const glm::uvec3 t = mesh.triangles[r.id];
        dvec3 corners[3] = {dvec3(mesh.vertices[t.x]), dvec3(mesh.vertices[t.y]),
                            dvec3(mesh.vertices[t.z])};
        // In one order whatever the winding, so that a reversed face (orientation's, which
        // rewrite_triangles relies on) is cut into the same boxes to the bit.
        std::sort(corners, corners + 3, [](const dvec3& a, const dvec3& b) {
          return a.x != b.x ? a.x < b.x : a.y != b.y ? a.y < b.y : a.z < b.z;
        });
        cut(corners, Box{r.lo, r.hi}, static_cast<int>(pieces), r.id, next);
      }
      Box centroids;
      for (const PrimRef* p = out.data() + offset[c]; p != next; ++p)
        centroids.grow(p->lo + p->hi);  // twice the centre, as make_references keeps it
      chunk_centroids[c] = centroids;
    }
  });
  root.centroids = Box();
  for (const Box& c : chunk_centroids) root.centroids.grow(c);
  root.end = total;
  refs = std::move(out);
  scratch = UninitializedVector<PrimRef>(total);
  return total;
}

}  // namespace sdf::bvh_build
