// SPDX-License-Identifier: GPL-3.0-or-later
#include "segment/postprocess.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "util/parallel.h"

namespace sdf::segment {

void fill_missing_from_edge_neighbours(const FaceGraph& graph, double* values, std::size_t n) {
  double smallest = std::numeric_limits<double>::infinity();
  for (std::size_t f = 0; f < n; ++f)
    if (!std::isnan(values[f])) smallest = std::min(smallest, values[f]);
  if (std::isinf(smallest) && smallest > 0) smallest = 0.0;  // no value anywhere
  std::vector<double> filled;
  std::vector<std::size_t> missing;
  for (std::size_t f = 0; f < n; ++f) {
    if (!std::isnan(values[f])) continue;
    double sum = 0.0;
    std::size_t count = 0;
    for (std::uint32_t i = graph.offsets[f]; i < graph.offsets[f + 1]; ++i) {
      const double v = values[graph.neighbours[i]];
      if (!std::isnan(v)) {
        sum += v;
        ++count;
      }
    }
    missing.push_back(f);
    filled.push_back(count ? sum / static_cast<double>(count) : smallest);
  }
  for (std::size_t i = 0; i < missing.size(); ++i) values[missing[i]] = filled[i];
}

std::size_t bilateral_window(std::size_t face_count) {
  return static_cast<std::size_t>(std::sqrt(static_cast<double>(face_count) / 2000.0)) + 1;
}

namespace {

// Faces within `window` rings of `root` with their ring, breadth first. `seen` is all 0 on
// entry and on return (only the faces gathered are marked, then cleared).
void gather_window(const FaceGraph& graph, std::uint32_t root, std::size_t window,
                   std::vector<std::uint8_t>& seen,
                   std::vector<std::pair<std::uint32_t, std::uint32_t>>& ring) {
  ring.clear();
  ring.emplace_back(root, 0);
  seen[root] = 1;
  for (std::size_t head = 0; head < ring.size(); ++head) {
    const auto [face, level] = ring[head];
    if (level >= window) continue;
    for (std::uint32_t i = graph.offsets[face]; i < graph.offsets[face + 1]; ++i) {
      const std::uint32_t g = graph.neighbours[i];
      if (seen[g]) continue;
      seen[g] = 1;
      ring.emplace_back(g, level + 1);
    }
  }
  for (const auto& entry : ring) seen[entry.first] = 0;
}

}  // namespace

void bilateral_filter(const FaceGraph& graph, const double* values, std::size_t n,
                      std::size_t window, unsigned threads, double* out, const ProgressFn& progress,
                      double progress_from, double progress_to) {
  const double spatial = static_cast<double>(window) / 2.0;
  // Small chunks: a face's window holds a thousand faces and more on large meshes (25 rings
  // at 1.2M faces), and a cancel waits for the chunks under way.
  const std::size_t grain = std::max<std::size_t>(64, 4096 / (window * window));
  parallel_for(
      n, grain, threads,
      [&](std::size_t begin, std::size_t end) {
        thread_local std::vector<std::uint8_t> seen;
        thread_local std::vector<std::pair<std::uint32_t, std::uint32_t>> ring;
        if (seen.size() < n) seen.resize(n, 0);
        for (std::size_t f = begin; f < end; ++f) {
          gather_window(graph, static_cast<std::uint32_t>(f), window, seen, ring);
          const double centre = values[f];
          double deviation = 0.0;
          for (const auto& [g, level] : ring)
            deviation += (values[g] - centre) * (values[g] - centre);
          deviation = std::sqrt(deviation / static_cast<double>(ring.size()));
          if (deviation == 0.0) {
            out[f] = centre;
            continue;
          }
          const double range = 1.5 * deviation;
          double sum = 0.0, weights = 0.0;
          for (const auto& [g, level] : ring) {
            const double ds = static_cast<double>(level) / spatial;
            const double dv = (values[g] - centre) / range;
            const double w = std::exp(-0.5 * ds * ds) * std::exp(-0.5 * dv * dv);
            sum += values[g] * w;
            weights += w;
          }
          out[f] = sum / weights;
        }
      },
      progress, progress_from, progress_to);
}

bool rescale_to_unit(double* values, std::size_t n) {
  if (n == 0) return false;
  const auto [lo, hi] = std::minmax_element(values, values + n);
  const double low = *lo, span = *hi - *lo;
  if (!(span > 0.0)) {
    std::fill(values, values + n, 0.0);
    return false;
  }
  for (std::size_t f = 0; f < n; ++f) values[f] = (values[f] - low) / span;
  return true;
}

}  // namespace sdf::segment
