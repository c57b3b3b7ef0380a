// SPDX-License-Identifier: GPL-3.0-or-later
// orient(Auto) as it was written first: serial, vertex-corner lists and a sort to weld. Kept
// as the specification the parallel version (native/orientation*.cpp) must match face for
// face: the same faces reversed, the same parts.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <tuple>
#include <utility>
#include <vector>

#include "prepare/orientation.h"

namespace sdf::test {

inline std::vector<std::uint32_t> reference_weld_exact(const Mesh& mesh) {
  struct Keyed {
    float x, y, z;
    std::uint32_t v;
    bool operator<(const Keyed& o) const {
      return std::tie(x, y, z, v) < std::tie(o.x, o.y, o.z, o.v);
    }
    bool same_place(const Keyed& o) const { return x == o.x && y == o.y && z == o.z; }
  };
  std::vector<Keyed> keyed(mesh.vertices.size());
  for (std::uint32_t v = 0; v < keyed.size(); ++v)
    keyed[v] = Keyed{mesh.vertices[v].x, mesh.vertices[v].y, mesh.vertices[v].z, v};
  std::sort(keyed.begin(), keyed.end());
  std::vector<std::uint32_t> rep(mesh.vertices.size());
  for (std::size_t i = 0; i < keyed.size(); ++i)
    rep[keyed[i].v] =
        (i > 0 && keyed[i].same_place(keyed[i - 1])) ? rep[keyed[i - 1].v] : keyed[i].v;
  return rep;
}

// Edges are their ends' positions: corners are listed by `rep` (one vertex per position).
inline std::vector<char> reference_consistent_flips(const Mesh& mesh,
                                                    const std::vector<std::uint32_t>& rep) {
  const std::size_t n = mesh.triangles.size(), nv = mesh.vertices.size();
  auto welded = [&](std::size_t f) {
    const glm::uvec3 t = mesh.triangles[f];
    return glm::uvec3(rep[t.x], rep[t.y], rep[t.z]);
  };
  struct Corner {
    std::uint32_t face, next, prev;
  };
  std::vector<std::uint32_t> offsets(nv + 1, 0);
  for (std::size_t f = 0; f < n; ++f)
    for (int k = 0; k < 3; ++k) ++offsets[welded(f)[k] + 1];
  for (std::size_t v = 0; v < nv; ++v) offsets[v + 1] += offsets[v];
  std::vector<Corner> around(offsets[nv]);
  {
    std::vector<std::uint32_t> cursor(offsets.begin(), offsets.end() - 1);
    for (std::uint32_t f = 0; f < n; ++f) {
      const glm::uvec3 t = welded(f);
      for (int k = 0; k < 3; ++k)
        around[cursor[t[k]]++] = Corner{f, t[(k + 1) % 3], t[(k + 2) % 3]};
    }
  }
  constexpr std::uint32_t kNone = 0xffffffffu;
  std::vector<std::uint32_t> neighbour(3 * n, kNone);
  std::vector<char> same(3 * n, 0);
  for (std::uint32_t f = 0; f < n; ++f) {
    const glm::uvec3 t = welded(f);
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = t[k], b = t[(k + 1) % 3];
      if (a == b) continue;
      std::uint32_t other = kNone, count = 0;
      bool other_same = false;
      for (std::uint32_t i = offsets[a]; i < offsets[a + 1]; ++i) {
        const Corner& c = around[i];
        if (c.face == f) continue;
        if (c.next == b) other = c.face, other_same = true, ++count;
        if (c.prev == b) other = c.face, other_same = false, ++count;
      }
      if (count == 1) {
        neighbour[3 * f + k] = other;
        same[3 * f + k] = other_same;
      }
    }
  }
  std::vector<char> flip(n, 0), seen(n, 0);
  std::vector<std::uint32_t> patch, queue;
  for (std::uint32_t seed = 0; seed < n; ++seed) {
    if (seen[seed]) continue;
    patch.clear();
    queue.assign(1, seed);
    seen[seed] = 1;
    while (!queue.empty()) {
      const std::uint32_t f = queue.back();
      queue.pop_back();
      patch.push_back(f);
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t g = neighbour[3 * f + k];
        if (g == kNone || seen[g]) continue;
        seen[g] = 1;
        flip[g] = flip[f] ^ same[3 * f + k];
        queue.push_back(g);
      }
    }
    double kept = 0.0, reversed = 0.0;
    bool any_reversed = false;
    for (std::uint32_t f : patch) any_reversed |= flip[f] != 0;
    if (!any_reversed) continue;
    std::sort(patch.begin(), patch.end());  // areas summed in face order
    for (std::uint32_t f : patch)
      (flip[f] ? reversed : kept) += glm::length(face_area_normal(mesh, f));
    if (reversed > kept)
      for (std::uint32_t f : patch) flip[f] ^= 1;
  }
  return flip;
}

inline OrientationReport reference_orient_auto(Mesh& mesh) {
  OrientationReport report;
  const std::vector<std::uint32_t> rep = reference_weld_exact(mesh);
  std::vector<char> flip = reference_consistent_flips(mesh, rep);
  std::vector<std::uint32_t> parent(mesh.vertices.size());
  std::iota(parent.begin(), parent.end(), 0u);
  auto find = [&](std::uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (const glm::uvec3& t : mesh.triangles) {
    parent[find(rep[t.x])] = find(rep[t.y]);
    parent[find(rep[t.x])] = find(rep[t.z]);
  }
  std::vector<std::uint32_t> part_of(mesh.triangles.size());
  std::vector<std::uint32_t> part_index(mesh.vertices.size(), 0xffffffffu);
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    const std::uint32_t root = find(rep[mesh.triangles[f].x]);
    if (part_index[root] == 0xffffffffu)
      part_index[root] = static_cast<std::uint32_t>(report.parts++);
    part_of[f] = part_index[root];
  }
  std::vector<glm::dvec3> lo(report.parts, glm::dvec3(1e300)), hi(report.parts, glm::dvec3(-1e300));
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f)
    for (int k = 0; k < 3; ++k) {
      const glm::dvec3 p(mesh.vertices[mesh.triangles[f][k]]);
      lo[part_of[f]] = glm::min(lo[part_of[f]], p);
      hi[part_of[f]] = glm::max(hi[part_of[f]], p);
    }
  std::vector<double> volume(report.parts, 0.0), area(report.parts, 0.0);
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    const std::uint32_t part = part_of[f];
    const glm::dvec3 c = 0.5 * (lo[part] + hi[part]);
    const glm::uvec3 t = mesh.triangles[f];
    const glm::dvec3 p0 = glm::dvec3(mesh.vertices[t.x]) - c,
                     p1 = glm::dvec3(mesh.vertices[t.y]) - c,
                     p2 = glm::dvec3(mesh.vertices[t.z]) - c;
    const double v = glm::dot(p0, glm::cross(p1, p2)) / 6.0;
    volume[part] += flip[f] ? -v : v;
    area[part] += 0.5 * glm::length(glm::cross(p1 - p0, p2 - p0));
  }
  // Nesting: part p lies in part q (at least 4 faces, volume clearly non-zero and larger than
  // p's, or as large with a lower number, a box holding p's) when three rays from the centroid
  // of p's first face all cross q's faces an odd number of times; the least such q is p's.
  const std::size_t parts = report.parts;
  std::vector<double> threshold(parts);
  std::vector<std::size_t> face_count(parts, 0), first_face(parts, mesh.triangles.size());
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    ++face_count[part_of[f]];
    first_face[part_of[f]] = std::min(first_face[part_of[f]], f);
  }
  for (std::size_t p = 0; p < parts; ++p) {
    const double diagonal = glm::length(hi[p] - lo[p]);
    const glm::dvec3 far = glm::max(glm::abs(lo[p]), glm::abs(hi[p]));
    threshold[p] = 1e-6 * std::max(diagonal, std::max(far.x, std::max(far.y, far.z))) * area[p];
  }
  const glm::dvec3 rays[3] = {glm::normalize(glm::dvec3(0.5377, 0.8271, -0.1642)),
                              glm::normalize(glm::dvec3(-0.7311, 0.2893, 0.6179)),
                              glm::normalize(glm::dvec3(0.1937, -0.5861, -0.7868))};
  auto corner = [&](std::size_t f, int k) {
    return glm::dvec3(mesh.vertices[mesh.triangles[f][k]]);
  };
  std::vector<std::size_t> inside(parts, parts);
  for (std::size_t p = 0; p < parts; ++p) {
    const std::size_t pf = first_face[p];
    const glm::dvec3 o = (corner(pf, 0) + corner(pf, 1) + corner(pf, 2)) / 3.0;
    for (std::size_t q = 0; q < parts; ++q) {
      if (q == p || face_count[q] < 4 || !(std::fabs(volume[q]) > threshold[q])) continue;
      if (!(lo[q].x <= lo[p].x && lo[q].y <= lo[p].y && lo[q].z <= lo[p].z && hi[q].x >= hi[p].x &&
            hi[q].y >= hi[p].y && hi[q].z >= hi[p].z))
        continue;
      const double vq = std::fabs(volume[q]), vp = std::fabs(volume[p]);
      if (!(vq > vp || (vq == vp && q < p))) continue;
      bool odd = true;
      for (const glm::dvec3& d : rays) {
        std::size_t crossings = 0;
        for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
          if (part_of[f] != q) continue;
          const glm::dvec3 a = corner(f, 0), e1 = corner(f, 1) - a, e2 = corner(f, 2) - a;
          const glm::dvec3 pv = glm::cross(d, e2);
          const double det = glm::dot(e1, pv);
          if (det == 0.0) continue;
          const glm::dvec3 s = o - a, qv = glm::cross(s, e1);
          const double u = glm::dot(s, pv) / det, v = glm::dot(d, qv) / det;
          crossings +=
              u >= 0.0 && u <= 1.0 && v >= 0.0 && u + v <= 1.0 && glm::dot(e2, qv) / det > 0.0;
        }
        odd = odd && crossings % 2 == 1;
      }
      const double vi = inside[p] == parts ? 0.0 : std::fabs(volume[inside[p]]);
      if (odd && (inside[p] == parts || vq < vi || (vq == vi && q > inside[p]))) inside[p] = q;
    }
  }
  // Outermost parts by their own volume; the others as the part around them.
  std::vector<char> reverse_part(parts);
  for (std::size_t p = 0; p < parts; ++p) {
    std::size_t outermost = p;
    while (inside[outermost] != parts) outermost = inside[outermost];
    reverse_part[p] = volume[outermost] < -threshold[outermost];
  }
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    if (reverse_part[part_of[f]]) flip[f] ^= 1;
    if (flip[f]) {
      std::swap(mesh.triangles[f].y, mesh.triangles[f].z);
      ++report.flipped_faces;
    }
  }
  return report;
}

}  // namespace sdf::test
