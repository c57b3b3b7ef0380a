// SPDX-License-Identifier: GPL-3.0-or-later
#include "segment/small_segments.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <numeric>
#include <queue>
#include <utility>
#include <vector>

namespace sdf::segment {
namespace {

double edge_length(const double* vertices, const std::int64_t* triangles, const FacePair& pair) {
  const std::int64_t* corners = triangles + 3 * std::size_t{pair.first};
  const double* a = vertices + 3 * corners[pair.first_corner];
  const double* b = vertices + 3 * corners[(pair.first_corner + 1) % 3];
  return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                   (a[2] - b[2]) * (a[2] - b[2]));
}

// The segments as they join: sums over their faces, and the length of boundary each shares
// with each neighbour (a std::map, so neighbours are visited by ascending index).
struct Parts {
  std::vector<double> area, value_sum;
  std::vector<std::size_t> faces;
  std::vector<std::map<int, double>> boundary;
  std::vector<int> into;  // the segment a joined one went into; its own index while alive

  Parts(const FaceGraph& graph, const double* vertices, const std::int64_t* triangles,
        const double* areas, const double* values, std::size_t n, const int* segments,
        std::size_t count)
      : area(count, 0.0), value_sum(count, 0.0), faces(count, 0), boundary(count), into(count) {
    std::iota(into.begin(), into.end(), 0);
    for (std::size_t f = 0; f < n; ++f) {
      const auto s = static_cast<std::size_t>(segments[f]);
      area[s] += areas[f];
      value_sum[s] += values[f];
      ++faces[s];
    }
    for (const FacePair& pair : graph.pairs) {
      const int a = segments[pair.first], b = segments[pair.second];
      if (a == b) continue;
      const double length = edge_length(vertices, triangles, pair);
      boundary[static_cast<std::size_t>(a)][b] += length;
      boundary[static_cast<std::size_t>(b)][a] += length;
    }
  }

  // The neighbour of s with the longest shared boundary (the lowest index of equals).
  int best_neighbour(int s) const {
    int best = -1;
    double longest = -1.0;
    for (const auto& [t, length] : boundary[static_cast<std::size_t>(s)])
      if (length > longest) {
        best = t;
        longest = length;
      }
    return best;
  }

  void join(int s, int t) {
    const auto si = static_cast<std::size_t>(s), ti = static_cast<std::size_t>(t);
    for (const auto& [u, length] : boundary[si]) {
      if (u == t) continue;
      auto& theirs = boundary[static_cast<std::size_t>(u)];
      theirs.erase(s);
      theirs[t] += length;
      boundary[ti][u] += length;
    }
    boundary[ti].erase(s);
    boundary[si].clear();
    area[ti] += area[si];
    value_sum[ti] += value_sum[si];
    faces[ti] += faces[si];
    into[si] = t;
  }

  int root(int s) {
    while (into[static_cast<std::size_t>(s)] != s) {
      const int next = into[static_cast<std::size_t>(s)];
      into[static_cast<std::size_t>(s)] = into[static_cast<std::size_t>(next)];
      s = next;
    }
    return s;
  }
};

}  // namespace

std::size_t join_small_segments(const FaceGraph& graph, const double* vertices,
                                const std::int64_t* triangles, const double* areas,
                                const double* values, std::size_t n, double min_share,
                                int* segments, std::size_t count) {
  if (!(min_share > 0.0) || count < 2) return count;
  Parts parts(graph, vertices, triangles, areas, values, n, segments, count);
  double total = 0.0;
  for (double a : parts.area) total += a;
  const double least = min_share * total;
  // Smallest first; an entry whose area is no longer the segment's is stale.
  using Entry = std::pair<double, int>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> queue;
  for (std::size_t s = 0; s < count; ++s) queue.emplace(parts.area[s], static_cast<int>(s));
  std::size_t joined = 0;
  while (!queue.empty()) {
    const auto [area, s] = queue.top();
    queue.pop();
    const auto si = static_cast<std::size_t>(s);
    if (parts.into[si] != s || area != parts.area[si]) continue;
    if (!(area < least)) break;  // every segment left is at least this large
    const int t = parts.best_neighbour(s);
    if (t < 0) continue;  // a separate solid: nothing to join
    parts.join(s, t);
    ++joined;
    queue.emplace(parts.area[static_cast<std::size_t>(t)], t);
  }
  if (joined == 0) return count;
  std::vector<int> alive;
  for (std::size_t s = 0; s < count; ++s)
    if (parts.into[s] == static_cast<int>(s)) alive.push_back(static_cast<int>(s));
  auto mean = [&](int s) {
    const auto si = static_cast<std::size_t>(s);
    return parts.value_sum[si] / static_cast<double>(parts.faces[si]);
  };
  std::stable_sort(alive.begin(), alive.end(), [&](int a, int b) { return mean(a) < mean(b); });
  std::vector<int> rank(count, -1);
  for (std::size_t r = 0; r < alive.size(); ++r)
    rank[static_cast<std::size_t>(alive[r])] = static_cast<int>(r);
  for (std::size_t f = 0; f < n; ++f)
    segments[f] = rank[static_cast<std::size_t>(parts.root(segments[f]))];
  return alive.size();
}

}  // namespace sdf::segment
