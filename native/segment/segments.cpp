// SPDX-License-Identifier: GPL-3.0-or-later
#include "segment/segments.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <utility>

#include "util/parallel.h"

namespace sdf::segment {

std::size_t number_segments(const FaceGraph& graph, const int* clusters, const double* values,
                            std::size_t n, int* segments) {
  std::fill(segments, segments + n, -1);
  std::vector<double> means;
  std::vector<std::uint32_t> queue;
  for (std::size_t root = 0; root < n; ++root) {
    if (segments[root] >= 0) continue;
    const int id = static_cast<int>(means.size());
    queue.assign(1, static_cast<std::uint32_t>(root));
    segments[root] = id;
    double sum = values[root];
    for (std::size_t head = 0; head < queue.size(); ++head) {
      const std::uint32_t f = queue[head];
      for (std::uint32_t i = graph.offsets[f]; i < graph.offsets[f + 1]; ++i) {
        const std::uint32_t g = graph.neighbours[i];
        if (segments[g] >= 0 || clusters[g] != clusters[root]) continue;
        segments[g] = id;
        sum += values[g];
        queue.push_back(g);
      }
    }
    means.push_back(sum / static_cast<double>(queue.size()));
  }
  std::vector<int> order(means.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return means[a] < means[b]; });
  std::vector<int> rank(means.size());
  for (std::size_t r = 0; r < order.size(); ++r) rank[order[r]] = static_cast<int>(r);
  for (std::size_t f = 0; f < n; ++f) segments[f] = rank[segments[f]];
  return means.size();
}

namespace {

double face_area(const double* vertices, const std::int64_t* triangles, std::size_t f) {
  const double* a = vertices + 3 * triangles[3 * f];
  const double* b = vertices + 3 * triangles[3 * f + 1];
  const double* c = vertices + 3 * triangles[3 * f + 2];
  const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  const double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  const double x = u[1] * v[2] - u[2] * v[1], y = u[2] * v[0] - u[0] * v[2],
               z = u[0] * v[1] - u[1] * v[0];
  return 0.5 * std::sqrt(x * x + y * y + z * z);
}

}  // namespace

std::vector<double> face_areas(const double* vertices, const std::int64_t* triangles, std::size_t n,
                               unsigned threads) {
  std::vector<double> areas(n);
  parallel_for(n, 16384, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t f = begin; f < end; ++f) areas[f] = face_area(vertices, triangles, f);
  });
  return areas;
}

SegmentStats segment_stats(const double* areas, const double* values, const int* segments,
                           std::size_t n, std::size_t segment_count) {
  SegmentStats stats;
  stats.area.assign(segment_count, 0.0);
  stats.mean_value.assign(segment_count, 0.0);
  std::vector<std::size_t> faces(segment_count, 0);
  for (std::size_t f = 0; f < n; ++f) {
    const auto s = static_cast<std::size_t>(segments[f]);
    stats.area[s] += areas[f];
    stats.mean_value[s] += values[f];
    ++faces[s];
  }
  for (std::size_t s = 0; s < segment_count; ++s)
    if (faces[s]) stats.mean_value[s] /= static_cast<double>(faces[s]);
  return stats;
}

}  // namespace sdf::segment
