// SPDX-License-Identifier: GPL-3.0-or-later
#include "segment/face_graph.h"

#include <algorithm>

#include "util/parallel.h"

namespace sdf::segment {
namespace {

// A face's directed edge, filed under its smaller vertex.
struct EdgeEntry {
  std::uint32_t other;  // the larger vertex
  std::uint32_t face;
  std::uint8_t corner;  // where the edge starts in the face
};

// Edges bucketed by their smaller vertex (a counting sort), each bucket sorted by the larger
// vertex then the face: equal edges end up adjacent, in an order no thread count changes.
void bucket_edges(const std::int64_t* triangles, std::size_t face_count, std::size_t vertex_count,
                  unsigned threads, std::vector<std::uint32_t>& starts,
                  std::vector<EdgeEntry>& entries, const WorkCheck& check) {
  starts.assign(vertex_count + 1, 0);
  auto for_each_edge = [&](auto&& visit) {
    for (std::size_t f = 0; f < face_count; ++f)
      for (std::uint8_t c = 0; c < 3; ++c) {
        const auto u = static_cast<std::uint32_t>(triangles[3 * f + c]);
        const auto v = static_cast<std::uint32_t>(triangles[3 * f + (c + 1) % 3]);
        if (u != v) visit(std::min(u, v), std::max(u, v), static_cast<std::uint32_t>(f), c);
      }
  };
  for_each_edge(
      [&](std::uint32_t lo, std::uint32_t, std::uint32_t, std::uint8_t) { ++starts[lo + 1]; });
  for (std::size_t v = 0; v < vertex_count; ++v) starts[v + 1] += starts[v];
  if (check) check(0.15);
  entries.resize(starts[vertex_count]);
  std::vector<std::uint32_t> fill(starts.begin(), starts.end() - 1);
  for_each_edge([&](std::uint32_t lo, std::uint32_t hi, std::uint32_t f, std::uint8_t c) {
    entries[fill[lo]++] = EdgeEntry{hi, f, c};
  });
  if (check) check(0.3);
  parallel_for(
      vertex_count, 4096, threads,
      [&](std::size_t begin, std::size_t end) {
        for (std::size_t v = begin; v < end; ++v)
          std::sort(entries.begin() + starts[v], entries.begin() + starts[v + 1],
                    [](const EdgeEntry& a, const EdgeEntry& b) {
                      return a.other != b.other ? a.other < b.other : a.face < b.face;
                    });
      },
      as_progress(check), 0.3, 0.5);
}

// Pairs for one edge's run of faces [begin, end), sorted by face: first < second.
void pair_run(const EdgeEntry* begin, const EdgeEntry* end, std::vector<FacePair>& pairs) {
  const std::size_t n = static_cast<std::size_t>(end - begin);
  auto add = [&](const EdgeEntry& a, const EdgeEntry& b) {
    if (a.face != b.face) pairs.push_back(FacePair{a.face, b.face, a.corner, b.corner});
  };
  if (n <= 8) {
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t j = i + 1; j < n; ++j) add(begin[i], begin[j]);
  } else {
    for (std::size_t i = 0; i + 1 < n; ++i) add(begin[i], begin[i + 1]);
    add(begin[0], begin[n - 1]);
  }
}

}  // namespace

FaceGraph build_face_graph(const std::int64_t* triangles, std::size_t face_count,
                           std::size_t vertex_count, unsigned threads, const WorkCheck& check) {
  std::vector<std::uint32_t> starts;
  std::vector<EdgeEntry> entries;
  bucket_edges(triangles, face_count, vertex_count, threads, starts, entries, check);

  FaceGraph graph;
  graph.pairs.reserve(entries.size() / 2);
  for (std::size_t v = 0; v < vertex_count; ++v) {
    for (std::size_t i = starts[v]; i < starts[v + 1];) {
      std::size_t j = i + 1;
      while (j < starts[v + 1] && entries[j].other == entries[i].other) ++j;
      if (j - i > 1) pair_run(entries.data() + i, entries.data() + j, graph.pairs);
      i = j;
    }
  }
  if (check) check(0.75);

  graph.offsets.assign(face_count + 1, 0);
  for (const FacePair& p : graph.pairs) {
    ++graph.offsets[p.first + 1];
    ++graph.offsets[p.second + 1];
  }
  for (std::size_t f = 0; f < face_count; ++f) graph.offsets[f + 1] += graph.offsets[f];
  graph.neighbours.resize(graph.offsets[face_count]);
  std::vector<std::uint32_t> fill(graph.offsets.begin(), graph.offsets.end() - 1);
  for (const FacePair& p : graph.pairs) {
    graph.neighbours[fill[p.first]++] = p.second;
    graph.neighbours[fill[p.second]++] = p.first;
  }
  return graph;
}

}  // namespace sdf::segment
