// SPDX-License-Identifier: GPL-3.0-or-later
#include "orientation_nesting.h"

#include <algorithm>
#include <atomic>
#include <utility>

#include "parallel.h"

namespace sdf {

namespace {

constexpr std::size_t kGrain = 1 << 12;

// Three directions in no special relation to the axes (meshes are often aligned with them)
// or to each other.
const glm::dvec3 kRays[3] = {glm::normalize(glm::dvec3(0.5377, 0.8271, -0.1642)),
                             glm::normalize(glm::dvec3(-0.7311, 0.2893, 0.6179)),
                             glm::normalize(glm::dvec3(0.1937, -0.5861, -0.7868))};

// Does the ray o + t d, t > 0, cross the triangle (a, b, c)? Moller-Trumbore in double; a ray
// through an edge may count for both faces there, which makes that ray's count even: it then
// says "not inside", never "inside" wrongly.
bool crosses(glm::dvec3 o, glm::dvec3 d, glm::dvec3 a, glm::dvec3 b, glm::dvec3 c) {
  const glm::dvec3 e1 = b - a, e2 = c - a, p = glm::cross(d, e2);
  const double det = glm::dot(e1, p);
  if (det == 0.0) return false;
  const double inv = 1.0 / det;
  const glm::dvec3 s = o - a;
  const double u = glm::dot(s, p) * inv;
  if (!(u >= 0.0 && u <= 1.0)) return false;
  const glm::dvec3 q = glm::cross(s, e1);
  const double v = glm::dot(d, q) * inv;
  if (!(v >= 0.0 && u + v <= 1.0)) return false;
  return glm::dot(e2, q) * inv > 0.0;
}

bool box_holds(const PartBox& outer, const PartBox& inner) {
  return glm::all(glm::lessThanEqual(outer.lo, inner.lo)) &&
         glm::all(glm::greaterThanEqual(outer.hi, inner.hi));
}

double box_volume(const PartBox& b) {
  const glm::dvec3 e = b.hi - b.lo;
  return e.x * e.y * e.z;
}

}  // namespace

std::vector<std::uint32_t> enclosing_parts(const Mesh& mesh, const Parts& parts,
                                           const std::vector<PartBox>& boxes,
                                           const std::vector<char>& encloser, unsigned threads) {
  const std::size_t n = mesh.triangles.size(), count = parts.count;
  std::vector<std::uint32_t> inside(count, kNoPart);
  std::vector<std::uint32_t> candidates;  // parts that can enclose
  for (std::uint32_t p = 0; p < count; ++p)
    if (encloser[p]) candidates.push_back(p);
  if (count < 2 || candidates.empty()) return inside;  // the common case: nothing to do

  // An encloser ranks above what it encloses (a larger box, or the lower part number for
  // equal boxes), so no chain of enclosers comes back to where it started.
  auto ranks_above = [&](std::uint32_t q, std::uint32_t p) {
    const double vq = box_volume(boxes[q]), vp = box_volume(boxes[p]);
    return vq > vp || (vq == vp && q < p);
  };
  // Pairs (inner, outer) whose boxes nest, in inner-part order.
  const std::size_t chunks = (count + kGrain - 1) / kGrain;
  std::vector<std::vector<std::pair<std::uint32_t, std::uint32_t>>> chunk_pairs(chunks);
  parallel_for(count, kGrain, threads, [&](std::size_t begin, std::size_t end) {
    auto& mine = chunk_pairs[begin / kGrain];
    for (std::size_t p = begin; p < end; ++p)
      for (std::uint32_t q : candidates)
        if (q != p && box_holds(boxes[q], boxes[p]) && ranks_above(q, p))
          mine.emplace_back(static_cast<std::uint32_t>(p), q);
  });
  std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
  for (const auto& c : chunk_pairs) pairs.insert(pairs.end(), c.begin(), c.end());
  if (pairs.empty()) return inside;

  // Each part's faces, in face order (a counting sort by part).
  std::vector<std::size_t> first(count + 1, 0);
  for (std::size_t f = 0; f < n; ++f) ++first[parts.part_of[f] + 1];
  for (std::size_t p = 0; p < count; ++p) first[p + 1] += first[p];
  std::vector<std::uint32_t> faces(n);
  {
    std::vector<std::size_t> at(first.begin(), first.end() - 1);
    for (std::size_t f = 0; f < n; ++f) faces[at[parts.part_of[f]]++] = static_cast<std::uint32_t>(f);
  }
  auto corner = [&](std::uint32_t f, int k) { return glm::dvec3(mesh.vertices[mesh.triangles[f][k]]); };
  for (const auto& [p, q] : pairs) {
    if (first[q + 1] - first[q] < 4) continue;  // fewer faces close nothing
    // From the centroid of p's first face, along each ray, count q's faces crossed.
    const std::uint32_t probe_face = faces[first[p]];
    const glm::dvec3 o = (corner(probe_face, 0) + corner(probe_face, 1) + corner(probe_face, 2)) / 3.0;
    std::atomic<std::uint64_t> crossings[3] = {0, 0, 0};
    parallel_for(first[q + 1] - first[q], kGrain, threads, [&](std::size_t begin, std::size_t end) {
      std::uint64_t mine[3] = {0, 0, 0};
      for (std::size_t i = first[q] + begin; i < first[q] + end; ++i) {
        const std::uint32_t f = faces[i];
        const glm::dvec3 a = corner(f, 0), b = corner(f, 1), c = corner(f, 2);
        for (int r = 0; r < 3; ++r) mine[r] += crosses(o, kRays[r], a, b, c);
      }
      for (int r = 0; r < 3; ++r) crossings[r].fetch_add(mine[r], std::memory_order_relaxed);
    });
    const bool enclosed = (crossings[0].load() & 1) && (crossings[1].load() & 1) &&
                          (crossings[2].load() & 1);
    if (!enclosed) continue;
    // The innermost: the smallest box (the lower part number on a tie).
    std::uint32_t& best = inside[p];
    const double v = box_volume(boxes[q]);
    if (best == kNoPart || v < box_volume(boxes[best]) || (v == box_volume(boxes[best]) && q < best))
      best = q;
  }
  return inside;
}

}  // namespace sdf
