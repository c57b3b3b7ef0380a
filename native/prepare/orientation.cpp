// SPDX-License-Identifier: GPL-3.0-or-later
#include "prepare/orientation.h"

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <utility>
#include <vector>

#include "prepare/orientation_edges.h"
#include "prepare/orientation_nesting.h"
#include "prepare/orientation_parts.h"
#include "prepare/orientation_patches.h"
#include "util/parallel.h"
#include "util/stopwatch.h"
#include "util/uninitialized_vector.h"

namespace sdf {

namespace {

constexpr std::size_t kGrain = 1 << 14;

void reverse_face(glm::uvec3& t) { std::swap(t.y, t.z); }

OrientationReport orient_auto(const Mesh& mesh, unsigned threads, bool fast_path,
                              StageTimings* steps) {
  StageClock step(steps);
  OrientationReport report;
  const std::size_t n = mesh.triangles.size();
  std::vector<char> flip;
  // Faces meet where their corners' positions do, whether or not they share the vertices: the
  // windings agree across unwelded seams (a cube with each side on vertices of its
  // own, one side reversed, kept it so: values 0.48-5.2x), and the parts below join there.
  UninitializedVector<std::uint32_t> same_place = weld_exact(mesh, threads);
  const bool welds = any_shared_place(same_place, threads);
  {
    const EdgeUses edges(mesh, threads, welds ? same_place.data() : nullptr);
    step.lap("orientation: edges");
    // Fast path: no manifold edge runs the same way in its two faces, so propagation would
    // reverse nothing (every patch already agrees).
    flip = edges.any_same() || !fast_path ? patch_flips(mesh, edges, threads)
                                          : std::vector<char>(n, 0);
  }
  step.lap("orientation: patches");

  const Parts parts = find_parts(mesh, std::move(same_place), threads);
  report.parts = parts.count;
  step.lap("orientation: parts");
  const std::vector<PartBox> boxes = part_boxes(mesh, parts, threads);
  // Signed volume of each part about its bounding-box centre, in double. The terms in
  // parallel; their sum in face order, as always, so that no rounding changes.
  // And each face's area, for the threshold below.
  UninitializedVector<double> term(n), area(n);
  parallel_for(n, kGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t f = begin; f < end; ++f) {
      const PartBox& box = boxes[parts.part_of[f]];
      const glm::dvec3 c = 0.5 * (box.lo + box.hi);
      const glm::uvec3 t = mesh.triangles[f];
      const glm::dvec3 p0 = glm::dvec3(mesh.vertices[t.x]) - c,
                       p1 = glm::dvec3(mesh.vertices[t.y]) - c,
                       p2 = glm::dvec3(mesh.vertices[t.z]) - c;
      const double v = glm::dot(p0, glm::cross(p1, p2)) / 6.0;
      term[f] = flip[f] ? -v : v;
      area[f] = 0.5 * glm::length(glm::cross(p1 - p0, p2 - p0));
    }
  });
  std::vector<double> volume(parts.count, 0.0), surface(parts.count, 0.0);
  for (std::size_t f = 0; f < n; ++f) {
    volume[parts.part_of[f]] += term[f];
    surface[parts.part_of[f]] += area[f];
  }
  step.lap("orientation: volumes");
  // A part's volume says 'inside out' when clearly negative, 'outward' when clearly positive:
  // beyond 1e-6 x its surface's area x the larger of its box's diagonal and its farthest
  // coordinate. A flat sheet tilted off the axes has corners rounded off its plane (float
  // coordinates, about 6e-8 of each coordinate, the mesh centred on its box), a volume of at
  // most area x that: the threshold is 16x more (a review's small sheet 1500 units from a
  // large sphere took the rounding for a winding in 25 of 80 placements). It was 1e-6 x the
  // diagonal cubed: an inside-out cylinder 1000 times longer than its radius read as flat
  // and stayed inside out; now up to 500,000 times.
  std::vector<char> negative(parts.count), clear(parts.count);
  for (std::size_t p = 0; p < parts.count; ++p) {
    const double diagonal = glm::length(boxes[p].hi - boxes[p].lo);
    const glm::dvec3 far = glm::max(glm::abs(boxes[p].lo), glm::abs(boxes[p].hi));
    const double reach = std::max(diagonal, std::max(far.x, std::max(far.y, far.z)));
    const double threshold = 1e-6 * reach * surface[p];
    negative[p] = volume[p] < -threshold;
    clear[p] = negative[p] || volume[p] > threshold;
  }
  // A part inside another (a hollow solid's inner wall, wound inward) keeps its winding
  // relative to the innermost part around it: reversed only with it.
  const std::vector<std::uint32_t> inside =
      enclosing_parts(mesh, parts, boxes, volume, clear, threads);
  std::vector<char> reverse_part(parts.count), decided(parts.count, 0);
  std::vector<std::uint32_t> chain;
  for (std::uint32_t p = 0; p < parts.count; ++p) {
    std::uint32_t q = p;
    chain.clear();
    while (!decided[q] && inside[q] != kNoPart) {  // enclosers rank higher: no cycle
      chain.push_back(q);
      q = inside[q];
    }
    if (!decided[q]) reverse_part[q] = negative[q], decided[q] = 1;
    for (auto it = chain.rbegin(); it != chain.rend(); ++it)
      reverse_part[*it] = reverse_part[inside[*it]], decided[*it] = 1;
  }
  // flip[f] becomes whether face f is reversed.
  std::atomic<std::size_t> flipped{0};
  parallel_for(n, kGrain, threads, [&](std::size_t begin, std::size_t end) {
    std::size_t mine = 0;
    for (std::size_t f = begin; f < end; ++f) {
      flip[f] = flip[f] ^ reverse_part[parts.part_of[f]];
      mine += flip[f] != 0;
    }
    flipped.fetch_add(mine, std::memory_order_relaxed);
  });
  report.flipped_faces = flipped.load();
  if (report.flipped_faces > 0) report.reversed.assign(flip.begin(), flip.end());
  step.lap("orientation: nesting");
  return report;
}

}  // namespace

OrientationReport decide_orientation(const Mesh& mesh, Orientation mode, unsigned threads,
                                     StageTimings* steps) {
  if (mode == Orientation::AsIs) return OrientationReport{};
  if (mode == Orientation::Auto) return orient_auto(mesh, threads, true, steps);
  OrientationReport report;
  report.flipped_faces = mesh.triangles.size();
  report.reversed.assign(mesh.triangles.size(), 1);
  return report;
}

void apply_orientation(Mesh& mesh, const OrientationReport& report, unsigned threads) {
  if (report.flipped_faces == 0) return;
  parallel_for(mesh.triangles.size(), kGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t f = begin; f < end; ++f)
      if (report.reversed[f]) reverse_face(mesh.triangles[f]);
  });
}

OrientationReport orient(Mesh& mesh, Orientation mode, unsigned threads, StageTimings* steps) {
  OrientationReport report = decide_orientation(mesh, mode, threads, steps);
  apply_orientation(mesh, report, threads);
  return report;
}

OrientationReport orient_auto_without_fast_path(Mesh& mesh, unsigned threads) {
  OrientationReport report = orient_auto(mesh, threads, false, nullptr);
  apply_orientation(mesh, report, threads);
  return report;
}

}  // namespace sdf
