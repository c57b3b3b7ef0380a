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
// Edges are matched through the faces around each vertex (linear time, no sort of all edges:
// this runs on every compute() call).
std::vector<char> consistent_flips(const Mesh& mesh) {
  const std::size_t n = mesh.triangles.size(), nv = mesh.vertices.size();
  // Around each vertex: the faces using it, each with its next and previous corner, stored
  // inline so that matching an edge reads one short contiguous list (no random face loads).
  struct Corner {
    std::uint32_t face, next, prev;
  };
  std::vector<std::uint32_t> offsets(nv + 1, 0);
  for (const glm::uvec3& t : mesh.triangles)
    for (int k = 0; k < 3; ++k) ++offsets[t[k] + 1];
  for (std::size_t v = 0; v < nv; ++v) offsets[v + 1] += offsets[v];
  std::vector<Corner> around(offsets[nv]);
  {
    std::vector<std::uint32_t> cursor(offsets.begin(), offsets.end() - 1);
    for (std::uint32_t f = 0; f < n; ++f) {
      const glm::uvec3 t = mesh.triangles[f];
      for (int k = 0; k < 3; ++k) around[cursor[t[k]]++] = Corner{f, t[(k + 1) % 3], t[(k + 2) % 3]};
    }
  }
  // Up to three neighbours per face (one per manifold edge), each with "runs the same way".
  constexpr std::uint32_t kNone = 0xffffffffu;
  std::vector<std::uint32_t> neighbour(3 * n, kNone);
  std::vector<char> same(3 * n, 0);
  for (std::uint32_t f = 0; f < n; ++f) {
    const glm::uvec3 t = mesh.triangles[f];
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = t[k], b = t[(k + 1) % 3];
      if (a == b) continue;
      // The other faces using edge {a, b}: those with a -> b run the same way, b -> a
      // opposite. The edge is manifold when exactly one other face uses it.
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
        if (g == kNone || seen[g]) continue;  // a non-orientable patch keeps its first choice
        seen[g] = 1;
        flip[g] = flip[f] ^ same[3 * f + k];
        queue.push_back(g);
      }
    }
    // Keep the winding that most of the patch's area already has.
    double kept = 0.0, reversed = 0.0;
    bool any_reversed = false;
    for (std::uint32_t f : patch) any_reversed |= flip[f] != 0;
    if (!any_reversed) continue;  // the common case: the patch already agrees
    for (std::uint32_t f : patch) (flip[f] ? reversed : kept) += glm::length(face_area_normal(mesh, f));
    if (reversed > kept)
      for (std::uint32_t f : patch) flip[f] ^= 1;
  }
  return flip;
}

// Per vertex, the index of the first vertex at exactly the same position.
std::vector<std::uint32_t> weld_exact(const Mesh& mesh) {
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
    rep[keyed[i].v] = (i > 0 && keyed[i].same_place(keyed[i - 1])) ? rep[keyed[i - 1].v] : keyed[i].v;
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
