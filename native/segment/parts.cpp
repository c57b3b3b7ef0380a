// SPDX-License-Identifier: GPL-3.0-or-later
#include "segment/parts.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <tuple>

#include "util/parallel.h"

namespace sdf::segment {
namespace {

// Faces around each vertex, CSR.
struct VertexFaces {
  std::vector<std::uint32_t> offsets, faces;
};

VertexFaces vertex_faces(const std::int64_t* triangles, std::size_t n, std::size_t vertex_count) {
  VertexFaces vf;
  vf.offsets.assign(vertex_count + 1, 0);
  for (std::size_t i = 0; i < 3 * n; ++i) ++vf.offsets[triangles[i] + 1];
  for (std::size_t v = 0; v < vertex_count; ++v) vf.offsets[v + 1] += vf.offsets[v];
  vf.faces.resize(3 * n);
  std::vector<std::uint32_t> fill(vf.offsets.begin(), vf.offsets.end() - 1);
  for (std::size_t i = 0; i < 3 * n; ++i)
    vf.faces[fill[triangles[i]]++] = static_cast<std::uint32_t>(i / 3);
  return vf;
}

// Adds `amount` to segment s's entry of a small list of (segment, amount).
void accumulate(std::vector<std::pair<int, double>>& list, int s, double amount) {
  for (auto& entry : list)
    if (entry.first == s) {
      entry.second += amount;
      return;
    }
  list.emplace_back(s, amount);
}

}  // namespace

std::vector<int> vertex_labels(std::size_t vertex_count, const std::int64_t* triangles,
                               const double* face_areas, const int* segments, std::size_t n) {
  const VertexFaces vf = vertex_faces(triangles, n, vertex_count);
  std::vector<int> labels(vertex_count, -1);
  std::vector<std::pair<int, double>> areas;
  for (std::size_t v = 0; v < vertex_count; ++v) {
    areas.clear();
    for (std::uint32_t i = vf.offsets[v]; i < vf.offsets[v + 1]; ++i)
      accumulate(areas, segments[vf.faces[i]], face_areas[vf.faces[i]]);
    std::sort(areas.begin(), areas.end());
    double best = -1.0;
    for (const auto& [s, area] : areas)
      if (area > best) best = area, labels[v] = s;
  }
  return labels;
}

namespace {

// Per vertex, whether a face of another segment than its own lies within `reach` steps along
// edges: only those vertices blend segments (a breadth-first search from the vertices where
// segments meet). The others weigh their one segment fully.
std::vector<std::uint8_t> near_boundary(const VertexFaces& vf, const std::int64_t* triangles,
                                        const int* segments, std::size_t vertex_count,
                                        std::size_t reach) {
  std::vector<std::uint8_t> near(vertex_count, 0);
  std::vector<std::uint32_t> frontier, next;
  for (std::size_t v = 0; v < vertex_count; ++v)
    for (std::uint32_t i = vf.offsets[v] + 1; i < vf.offsets[v + 1]; ++i)
      if (segments[vf.faces[i]] != segments[vf.faces[vf.offsets[v]]]) {
        near[v] = 1;
        frontier.push_back(static_cast<std::uint32_t>(v));
        break;
      }
  for (std::size_t step = 0; step < reach && !frontier.empty(); ++step) {
    next.clear();
    for (std::uint32_t v : frontier)
      for (std::uint32_t i = vf.offsets[v]; i < vf.offsets[v + 1]; ++i)
        for (int c = 0; c < 3; ++c) {
          const auto u = static_cast<std::uint32_t>(triangles[3 * vf.faces[i] + c]);
          if (!near[u]) near[u] = 1, next.push_back(u);
        }
    frontier.swap(next);
  }
  return near;
}

}  // namespace

VertexWeights vertex_weights(std::size_t vertex_count, const std::int64_t* triangles,
                             const double* face_areas, const int* segments, std::size_t n,
                             std::size_t rings, unsigned threads, const WorkCheck& check) {
  const VertexFaces vf = vertex_faces(triangles, n, vertex_count);
  if (check) check(0.1);
  // A vertex's window reaches faces within rings + 1 edge steps of it.
  const std::vector<std::uint8_t> near =
      near_boundary(vf, triangles, segments, vertex_count, rings + 1);
  if (check) check(0.2);
  constexpr std::size_t kBlock = 4096;
  const std::size_t blocks = (vertex_count + kBlock - 1) / kBlock;
  std::vector<std::vector<std::pair<int, double>>> block_entries(blocks);
  std::vector<std::vector<std::uint32_t>> block_counts(blocks);
  parallel_for(
      blocks, 1, threads,
      [&](std::size_t b0, std::size_t b1) {
        thread_local std::vector<std::uint8_t> seen;
        if (seen.size() < n) seen.resize(n, 0);
        std::vector<std::uint32_t> ring, next, visited;
        std::vector<std::pair<int, double>> sums;
        for (std::size_t b = b0; b < b1; ++b) {
          for (std::size_t v = b * kBlock; v < std::min(vertex_count, (b + 1) * kBlock); ++v) {
            if (!near[v]) {  // one segment all around (or no face at all)
              const bool used = vf.offsets[v + 1] > vf.offsets[v];
              if (used) block_entries[b].emplace_back(segments[vf.faces[vf.offsets[v]]], 1.0);
              block_counts[b].push_back(used ? 1 : 0);
              continue;
            }
            sums.clear();
            ring.assign(vf.faces.begin() + vf.offsets[v], vf.faces.begin() + vf.offsets[v + 1]);
            for (std::uint32_t f : ring) seen[f] = 1;
            visited = ring;
            for (std::size_t r = 0; r <= rings && !ring.empty(); ++r) {
              const double falloff =
                  static_cast<double>(rings + 1 - r) / static_cast<double>(rings + 1);
              next.clear();
              for (std::uint32_t f : ring) {
                accumulate(sums, segments[f], falloff * face_areas[f]);
                if (r == rings) continue;
                for (int c = 0; c < 3; ++c) {
                  const auto u = static_cast<std::size_t>(triangles[3 * f + c]);
                  for (std::uint32_t i = vf.offsets[u]; i < vf.offsets[u + 1]; ++i)
                    if (!seen[vf.faces[i]]) seen[vf.faces[i]] = 1, next.push_back(vf.faces[i]);
                }
              }
              visited.insert(visited.end(), next.begin(), next.end());
              ring.swap(next);
            }
            for (std::uint32_t f : visited) seen[f] = 0;
            std::sort(sums.begin(), sums.end());
            double total = 0.0;
            for (const auto& entry : sums) total += entry.second;
            std::uint32_t count = 0;
            for (const auto& [s, w] : sums) {
              // Faces without area: equal shares.
              const double share = total > 0.0 ? w / total : 1.0 / static_cast<double>(sums.size());
              block_entries[b].emplace_back(s, share);
              ++count;
            }
            block_counts[b].push_back(count);
          }
        }
      },
      as_progress(check), 0.2, 0.9);
  VertexWeights out;
  out.offsets.assign(1, 0);
  for (std::size_t b = 0; b < blocks; ++b) {
    for (std::uint32_t c : block_counts[b]) out.offsets.push_back(out.offsets.back() + c);
    for (const auto& [s, w] : block_entries[b]) {
      out.segment.push_back(s);
      out.weight.push_back(static_cast<float>(w));
    }
  }
  return out;
}

namespace {

// The loops among one pair of segments' edges (pair indices into graph.pairs), appended to
// `loops`: edges sharing a vertex join one loop (a union-find over their vertices).
void split_into_loops(const FaceGraph& graph, const double* vertices, const std::int64_t* triangles,
                      int a, int b, const std::vector<std::uint32_t>& edges,
                      std::vector<Boundary>& loops) {
  auto end_of = [&](std::uint32_t e, int which) {
    const FacePair& p = graph.pairs[e];
    return triangles[3 * p.first + (p.first_corner + which) % 3];
  };
  std::vector<std::int64_t> ends;
  for (std::uint32_t e : edges) ends.push_back(end_of(e, 0)), ends.push_back(end_of(e, 1));
  std::sort(ends.begin(), ends.end());
  ends.erase(std::unique(ends.begin(), ends.end()), ends.end());
  auto index = [&](std::int64_t v) {
    return static_cast<std::size_t>(std::lower_bound(ends.begin(), ends.end(), v) - ends.begin());
  };
  std::vector<std::size_t> up(ends.size());
  std::iota(up.begin(), up.end(), 0);
  auto root = [&](std::size_t x) {
    while (up[x] != x) x = up[x] = up[up[x]];
    return x;
  };
  for (std::uint32_t e : edges) up[root(index(end_of(e, 0)))] = root(index(end_of(e, 1)));
  std::vector<std::int64_t> loop_of(ends.size(), -1);
  const std::size_t first = loops.size();
  for (std::uint32_t e : edges) {
    const std::size_t r = root(index(end_of(e, 0)));
    if (loop_of[r] < 0) {
      loop_of[r] = static_cast<std::int64_t>(loops.size());
      loops.push_back(Boundary{a, b, {0, 0, 0}, 0.0, 0});
    }
    Boundary& loop = loops[static_cast<std::size_t>(loop_of[r])];
    const double* p = vertices + 3 * end_of(e, 0);
    const double* q = vertices + 3 * end_of(e, 1);
    const double length = std::hypot(p[0] - q[0], p[1] - q[1], p[2] - q[2]);
    for (int c = 0; c < 3; ++c) loop.centroid[c] += length * 0.5 * (p[c] + q[c]);
    loop.length += length;
    ++loop.edges;
  }
  for (std::size_t l = first; l < loops.size(); ++l)
    for (double& c : loops[l].centroid) c = loops[l].length > 0.0 ? c / loops[l].length : 0.0;
}

}  // namespace

std::vector<Boundary> boundaries(const FaceGraph& graph, const double* vertices, std::size_t,
                                 const std::int64_t* triangles, const int* segments) {
  // Edges between segments, grouped by the pair of segments, in pair order within a group.
  std::vector<std::tuple<int, int, std::uint32_t>> cut;
  for (std::size_t p = 0; p < graph.pairs.size(); ++p) {
    const int s = segments[graph.pairs[p].first], t = segments[graph.pairs[p].second];
    if (s != t) cut.emplace_back(std::min(s, t), std::max(s, t), static_cast<std::uint32_t>(p));
  }
  std::sort(cut.begin(), cut.end());
  std::vector<Boundary> loops;
  std::vector<std::uint32_t> edges;
  for (std::size_t i = 0; i < cut.size();) {
    const int a = std::get<0>(cut[i]), b = std::get<1>(cut[i]);
    edges.clear();
    for (; i < cut.size() && std::get<0>(cut[i]) == a && std::get<1>(cut[i]) == b; ++i)
      edges.push_back(std::get<2>(cut[i]));
    split_into_loops(graph, vertices, triangles, a, b, edges, loops);
  }
  return loops;
}

}  // namespace sdf::segment
