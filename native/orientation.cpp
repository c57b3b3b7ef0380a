// SPDX-License-Identifier: GPL-3.0-or-later
#include "orientation.h"

#include <algorithm>
#include <cstdint>
#include <numeric>
#include <tuple>
#include <utility>
#include <vector>

namespace sdf {

namespace {

struct DisjointSets {
  explicit DisjointSets(std::size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0u); }
  std::uint32_t find(std::uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void unite(std::uint32_t a, std::uint32_t b) { parent[find(a)] = find(b); }
  std::vector<std::uint32_t> parent;
};

// Per face: reverse it (1) or not (0) so that faces agree with their manifold-edge neighbours.
std::vector<char> consistent_flips(const Mesh& mesh) {
  const std::size_t n = mesh.triangles.size();
  // Every directed edge as (low vertex, high vertex, face, runs low->high).
  std::vector<std::tuple<std::uint32_t, std::uint32_t, std::uint32_t, bool>> edges;
  edges.reserve(3 * n);
  for (std::uint32_t f = 0; f < n; ++f) {
    const glm::uvec3 t = mesh.triangles[f];
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = t[k], b = t[(k + 1) % 3];
      if (a != b) edges.emplace_back(std::min(a, b), std::max(a, b), f, a < b);
    }
  }
  std::sort(edges.begin(), edges.end());
  // Manifold edges join two faces; `same` says they run the same way (so they disagree).
  std::vector<std::vector<std::pair<std::uint32_t, bool>>> neighbours(n);
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i;
    while (j < edges.size() && std::get<0>(edges[j]) == std::get<0>(edges[i]) &&
           std::get<1>(edges[j]) == std::get<1>(edges[i]))
      ++j;
    if (j - i == 2) {
      const auto& [a0, b0, f, dir_f] = edges[i];
      const auto& [a1, b1, g, dir_g] = edges[i + 1];
      if (f != g) {
        neighbours[f].emplace_back(g, dir_f == dir_g);
        neighbours[g].emplace_back(f, dir_f == dir_g);
      }
    }
    i = j;
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
      for (const auto& [g, same] : neighbours[f]) {
        if (seen[g]) continue;  // a non-orientable patch keeps its first assignment
        seen[g] = 1;
        flip[g] = flip[f] ^ static_cast<char>(same);
        queue.push_back(g);
      }
    }
    // Keep the winding that most of the patch's area already has.
    double kept = 0.0, reversed = 0.0;
    for (std::uint32_t f : patch) (flip[f] ? reversed : kept) += glm::length(face_area_normal(mesh, f));
    if (reversed > kept)
      for (std::uint32_t f : patch) flip[f] ^= 1;
  }
  return flip;
}

// Per vertex, the index of the first vertex at exactly the same position.
std::vector<std::uint32_t> weld_exact(const Mesh& mesh) {
  std::vector<std::uint32_t> order(mesh.vertices.size());
  std::iota(order.begin(), order.end(), 0u);
  auto key = [&](std::uint32_t v) {
    const glm::vec3 p = mesh.vertices[v];
    return std::make_tuple(p.x, p.y, p.z);
  };
  std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
    return key(a) < key(b) || (key(a) == key(b) && a < b);
  });
  std::vector<std::uint32_t> rep(mesh.vertices.size());
  for (std::size_t i = 0; i < order.size(); ++i)
    rep[order[i]] = (i > 0 && key(order[i]) == key(order[i - 1])) ? rep[order[i - 1]] : order[i];
  return rep;
}

void reverse_face(glm::uvec3& t) { std::swap(t.y, t.z); }

}  // namespace

OrientationReport orient(Mesh& mesh, Orientation mode) {
  OrientationReport report;
  if (mode == Orientation::AsIs) return report;
  if (mode == Orientation::Flip) {
    for (glm::uvec3& t : mesh.triangles) reverse_face(t);
    report.flipped_faces = mesh.triangles.size();
    return report;
  }
  std::vector<char> flip = consistent_flips(mesh);

  // Parts: faces joined through shared vertex positions.
  const std::vector<std::uint32_t> rep = weld_exact(mesh);
  DisjointSets sets(mesh.vertices.size());
  for (const glm::uvec3& t : mesh.triangles) {
    sets.unite(rep[t.x], rep[t.y]);
    sets.unite(rep[t.x], rep[t.z]);
  }
  std::vector<std::uint32_t> part_of(mesh.triangles.size());
  std::vector<std::uint32_t> part_index(mesh.vertices.size(), 0xffffffffu);
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    const std::uint32_t root = sets.find(rep[mesh.triangles[f].x]);
    if (part_index[root] == 0xffffffffu) part_index[root] = static_cast<std::uint32_t>(report.parts++);
    part_of[f] = part_index[root];
  }
  // Signed volume of each part about its bounding-box centre, in double.
  std::vector<glm::dvec3> lo(report.parts, glm::dvec3(1e300)), hi(report.parts, glm::dvec3(-1e300));
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f)
    for (int k = 0; k < 3; ++k) {
      const glm::dvec3 p(mesh.vertices[mesh.triangles[f][k]]);
      lo[part_of[f]] = glm::min(lo[part_of[f]], p);
      hi[part_of[f]] = glm::max(hi[part_of[f]], p);
    }
  std::vector<double> volume(report.parts, 0.0);
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    const std::uint32_t part = part_of[f];
    const glm::dvec3 c = 0.5 * (lo[part] + hi[part]);
    const glm::uvec3 t = mesh.triangles[f];
    const glm::dvec3 p0 = glm::dvec3(mesh.vertices[t.x]) - c, p1 = glm::dvec3(mesh.vertices[t.y]) - c,
                     p2 = glm::dvec3(mesh.vertices[t.z]) - c;
    const double v = glm::dot(p0, glm::cross(p1, p2)) / 6.0;
    volume[part] += flip[f] ? -v : v;
  }
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    const std::uint32_t part = part_of[f];
    const double diagonal = glm::length(hi[part] - lo[part]);
    if (volume[part] < -1e-6 * diagonal * diagonal * diagonal) flip[f] ^= 1;
    if (flip[f]) {
      reverse_face(mesh.triangles[f]);
      ++report.flipped_faces;
    }
  }
  return report;
}

}  // namespace sdf
