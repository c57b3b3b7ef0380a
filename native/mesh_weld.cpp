// SPDX-License-Identifier: GPL-3.0-or-later
#include "mesh_weld.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <memory>
#include <mutex>

#include "parallel.h"
#include "radix_sort.h"
#include "uninitialized_vector.h"
#include "weld_cells.h"

namespace sdf {

namespace {

using weld_cells::CellKey;
using weld_cells::CellTable;
using weld_cells::float_bits;
using weld_cells::hash_key;

// Vertices per chunk of the parallel passes.
constexpr std::size_t kWeldGrain = 1 << 14;

// The cell grid of a weld: cells at least twice the tolerance wide, so the ball of radius
// `tolerance` around a point meets at most 2 cells per axis; up to 64 times wider while that
// keeps about one vertex per cell on a surface (side extent / sqrt(count)): then most balls
// lie in one cell and a query looks up one cell, not 8. Coordinates too large for the grid
// fall back to exact merging (a tolerance below float resolution merges only equal positions
// anyway), where a cell is one exact position.
struct WeldGrid {
  bool exact = true;
  double cell = 0.0;
  // The ball's cell range per axis, from p - reach to p + reach: a hair wider than the
  // tolerance, so that rounding in the division cannot drop a cell holding a point at
  // exactly the tolerance.
  double reach = 0.0;

  WeldGrid(const glm::vec3* positions, std::size_t count, float tolerance, unsigned threads) {
    exact = !(tolerance > 0.0f);
    cell = 2.0 * static_cast<double>(tolerance);
    reach = static_cast<double>(tolerance) * (1.0 + 1e-6);
    if (exact) return;
    glm::vec3 lo(std::numeric_limits<float>::infinity()), hi(-lo);
    std::mutex merge;
    parallel_for(count, kWeldGrain, threads, [&](std::size_t begin, std::size_t end) {
      glm::vec3 l(std::numeric_limits<float>::infinity()), h(-l);
      for (std::size_t i = begin; i < end; ++i) {
        l = glm::min(l, positions[i]);
        h = glm::max(h, positions[i]);
      }
      std::lock_guard<std::mutex> lock(merge);
      lo = glm::min(lo, l);
      hi = glm::max(hi, h);
    });
    const glm::vec3 size = hi - lo;
    const double extent = std::max(size.x, std::max(size.y, size.z));
    cell = std::max(cell, std::min(64.0 * tolerance, extent / std::sqrt(double(count))));
    const double largest = std::max(glm::length(lo), glm::length(hi));
    exact = !(largest / cell < 1e15) || !std::isfinite(cell);
  }
  CellKey home(glm::vec3 p) const {
    if (exact) return {float_bits(p.x), float_bits(p.y), float_bits(p.z)};
    return {static_cast<std::int64_t>(std::floor(p.x / cell)),
            static_cast<std::int64_t>(std::floor(p.y / cell)),
            static_cast<std::int64_t>(std::floor(p.z / cell))};
  }
  // Calls visit(key) for every cell the ball around p meets (only the home cell when exact).
  template <class Visit>
  void for_each_cell(glm::vec3 p, Visit&& visit) const {
    if (exact) {
      visit(home(p));
      return;
    }
    std::int64_t first[3], last[3];
    for (int a = 0; a < 3; ++a) {
      first[a] = static_cast<std::int64_t>(std::floor((p[a] - reach) / cell));
      last[a] = static_cast<std::int64_t>(std::floor((p[a] + reach) / cell));
    }
    for (std::int64_t x = first[0]; x <= last[0]; ++x)
      for (std::int64_t y = first[1]; y <= last[1]; ++y)
        for (std::int64_t z = first[2]; z <= last[2]; ++z) visit(CellKey{x, y, z});
  }
};

// Whether two positions merge: equal (+0 and -0 alike) when exact, else within tolerance.
bool close(glm::vec3 a, glm::vec3 b, bool exact, float tolerance2) {
  if (exact) return a == b;
  const glm::vec3 d = a - b;
  return glm::dot(d, d) <= tolerance2;
}

// Per vertex, whether any other vertex merges with it (it has a neighbour in the ball).
// Vertices sorted by the hash of their home cell: a cell's vertices are one run (with those
// of cells sharing the hash), found by binary search. Both vertices of a close pair are
// marked: when the tolerance's square underflows, `close` can accept a pair one of whose
// cell ranges misses the other, which the serial greedy still merges from the later side.
std::vector<char> has_neighbour(const glm::vec3* positions, std::size_t count,
                                const WeldGrid& grid, float tolerance2, unsigned threads) {
  UninitializedVector<std::uint64_t> by_cell(count);
  parallel_for(count, kWeldGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i)
      by_cell[i] = (hash_key(grid.home(positions[i])) & 0xffffffffull) << 32 | i;
  });
  radix_sort_by_bits(by_cell, 32, 32, threads);
  std::unique_ptr<std::atomic<char>[]> marked(new std::atomic<char>[count]);
  parallel_for(count, kWeldGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) marked[i].store(0, std::memory_order_relaxed);
  });
  parallel_for(count, kWeldGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      const glm::vec3 p = positions[i];
      grid.for_each_cell(p, [&](const CellKey& key) {
        const std::uint64_t h = (hash_key(key) & 0xffffffffull) << 32;
        for (auto it = std::lower_bound(by_cell.begin(), by_cell.end(), h);
             it != by_cell.end() && (*it >> 32) == (h >> 32); ++it) {
          const std::size_t j = static_cast<std::uint32_t>(*it);
          if (j != i && close(positions[j], p, grid.exact, tolerance2)) {
            marked[i].store(1, std::memory_order_relaxed);
            marked[j].store(1, std::memory_order_relaxed);
          }
        }
      });
    }
  });
  std::vector<char> found(count);
  parallel_for(count, kWeldGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) found[i] = marked[i].load(std::memory_order_relaxed);
  });
  return found;
}

}  // namespace

Weld weld_vertices(const glm::vec3* positions, std::size_t count, float tolerance,
                   unsigned threads, StageTimings* timings) {
  StageClock clock(timings);
  Weld weld;
  weld.merged.resize(count);
  if (count == 0) return weld;
  const WeldGrid grid(positions, count, tolerance, threads);
  const float tolerance2 = tolerance * tolerance;
  clock.lap("weld: grid");

  // A vertex with no other vertex in its ball is kept whatever happens to the others, and is
  // in no one else's ball: the greedy pass in index order needs only the vertices that have
  // a neighbour (usually a few percent: seams, duplicated corners), and the rest is parallel.
  const std::vector<char> crowded = has_neighbour(positions, count, grid, tolerance2, threads);
  clock.lap("weld: neighbour test");
  constexpr std::uint32_t kKept = std::numeric_limits<std::uint32_t>::max();
  std::vector<std::uint32_t> target(count, kKept);  // input index of the vertex it joins
  {
    CellTable table(static_cast<std::size_t>(std::count(crowded.begin(), crowded.end(), 1)));
    std::vector<std::uint32_t> next;  // per kept crowded vertex: the next one in its cell
    std::vector<std::uint32_t> kept;  // kept crowded vertices, in index order
    for (std::size_t i = 0; i < count; ++i) {
      if (!crowded[i]) continue;
      const glm::vec3 p = positions[i];
      std::uint32_t best = CellTable::kEmpty;  // among kept: the lowest, so the first kept
      grid.for_each_cell(p, [&](const CellKey& key) {
        for (std::uint32_t m = table.find(key); m != CellTable::kEmpty; m = next[m])
          if (close(positions[kept[m]], p, grid.exact, tolerance2) && m < best) best = m;
      });
      if (best != CellTable::kEmpty) {
        target[i] = kept[best];
        continue;
      }
      const std::uint32_t id = static_cast<std::uint32_t>(kept.size());
      kept.push_back(static_cast<std::uint32_t>(i));
      std::uint32_t& head = table.slot(grid.home(p));
      next.push_back(head);
      head = id;
    }
  }
  clock.lap("weld: greedy");
  // Merged ids: kept vertices numbered in index order, a block of vertices at a time.
  const std::size_t blocks = (count + kWeldGrain - 1) / kWeldGrain;
  std::vector<std::uint32_t> block_first(blocks + 1, 0);
  parallel_for(blocks, 1, threads, [&](std::size_t b0, std::size_t b1) {
    for (std::size_t b = b0; b < b1; ++b) {
      std::uint32_t n = 0;
      for (std::size_t i = b * kWeldGrain; i < std::min(count, (b + 1) * kWeldGrain); ++i)
        n += target[i] == kKept;
      block_first[b + 1] = n;
    }
  });
  for (std::size_t b = 0; b < blocks; ++b) block_first[b + 1] += block_first[b];
  parallel_for(blocks, 1, threads, [&](std::size_t b0, std::size_t b1) {
    for (std::size_t b = b0; b < b1; ++b) {
      std::uint32_t id = block_first[b];
      for (std::size_t i = b * kWeldGrain; i < std::min(count, (b + 1) * kWeldGrain); ++i)
        if (target[i] == kKept) weld.merged[i] = id++;
    }
  });
  // A target is kept and earlier than its vertex: its id is final.
  parallel_for(count, kWeldGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i)
      if (target[i] != kKept) weld.merged[i] = weld.merged[target[i]];
  });
  weld.count = block_first[blocks];
  clock.lap("weld: numbering");
  return weld;
}

float weld_tolerance(const Mesh& mesh, double relative) {
  return static_cast<float>(relative * mesh.max_extent);
}

std::vector<glm::uvec3> welded_triangles(const Mesh& mesh, const Weld& weld) {
  std::vector<glm::uvec3> out(mesh.triangles.size());
  for (std::size_t f = 0; f < out.size(); ++f) {
    const glm::uvec3 t = mesh.triangles[f];
    out[f] = glm::uvec3(weld.merged[t.x], weld.merged[t.y], weld.merged[t.z]);
  }
  return out;
}

Adjacency faces_of_vertices(const std::vector<glm::uvec3>& triangles, std::uint32_t vertex_count) {
  Adjacency a;
  a.offsets.assign(static_cast<std::size_t>(vertex_count) + 1, 0);
  auto distinct = [](const glm::uvec3& t, int k) {
    return (k == 0) || (k == 1 && t.y != t.x) || (k == 2 && t.z != t.x && t.z != t.y);
  };
  for (const glm::uvec3& t : triangles)
    for (int k = 0; k < 3; ++k)
      if (distinct(t, k)) ++a.offsets[t[k] + 1];
  for (std::size_t v = 0; v < vertex_count; ++v) a.offsets[v + 1] += a.offsets[v];
  a.items.resize(a.offsets.back());
  std::vector<std::uint32_t> cursor(a.offsets.begin(), a.offsets.end() - 1);
  for (std::size_t f = 0; f < triangles.size(); ++f)
    for (int k = 0; k < 3; ++k)
      if (distinct(triangles[f], k)) a.items[cursor[triangles[f][k]]++] = static_cast<std::uint32_t>(f);
  return a;
}

namespace {

// The distinct neighbours of vertex v (sorted, without v) appended to `out`.
void append_neighbours(std::uint32_t v, const std::vector<glm::uvec3>& triangles,
                       const Adjacency& faces_of_vertices, std::vector<std::uint32_t>& out) {
  const std::size_t begin = out.size();
  for (std::uint32_t i = faces_of_vertices.offsets[v]; i < faces_of_vertices.offsets[v + 1]; ++i) {
    const glm::uvec3 t = triangles[faces_of_vertices.items[i]];
    for (int k = 0; k < 3; ++k)
      if (t[k] != v) out.push_back(t[k]);
  }
  const auto first = out.begin() + static_cast<std::ptrdiff_t>(begin);
  std::sort(first, out.end());
  out.erase(std::unique(first, out.end()), out.end());
}

}  // namespace

Adjacency vertex_neighbours(const std::vector<glm::uvec3>& triangles,
                            const Adjacency& faces_of_vertices, unsigned threads) {
  const std::size_t n = faces_of_vertices.size();
  Adjacency a;
  a.offsets.assign(n + 1, 0);
  // Blocks of vertices list their neighbours into their own buffers (counts into offsets),
  // then copy them into place after the prefix sum: the result does not depend on threads.
  constexpr std::size_t kBlock = 1 << 14;
  const std::size_t blocks = (n + kBlock - 1) / kBlock;
  std::vector<std::vector<std::uint32_t>> lists(blocks);
  parallel_for(blocks, 1, threads, [&](std::size_t b0, std::size_t b1) {
    for (std::size_t b = b0; b < b1; ++b) {
      std::vector<std::uint32_t>& list = lists[b];
      list.reserve(7 * kBlock);
      for (std::size_t v = b * kBlock; v < std::min(n, (b + 1) * kBlock); ++v) {
        const std::size_t before = list.size();
        append_neighbours(static_cast<std::uint32_t>(v), triangles, faces_of_vertices, list);
        a.offsets[v + 1] = static_cast<std::uint32_t>(list.size() - before);
      }
    }
  });
  for (std::size_t v = 0; v < n; ++v) a.offsets[v + 1] += a.offsets[v];
  a.items.resize(a.offsets.back());
  parallel_for(blocks, 1, threads, [&](std::size_t b0, std::size_t b1) {
    for (std::size_t b = b0; b < b1; ++b)
      std::copy(lists[b].begin(), lists[b].end(), a.items.begin() + a.offsets[b * kBlock]);
  });
  return a;
}

}  // namespace sdf
