// SPDX-License-Identifier: GPL-3.0-or-later
#include "mesh/mesh_weld.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <memory>
#include <mutex>
#include <utility>

#include "mesh/weld_cells.h"
#include "util/parallel.h"
#include "util/parallel_scan.h"
#include "util/radix_sort.h"
#include "util/uninitialized_vector.h"

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
// lie in one cell and a query looks up one cell, not 8. A position too large for the grid
// falls back to exact merging (a tolerance below float resolution merges only equal positions
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
    exact = !std::isfinite(cell);
  }
  // A position too far out for the grid's 64-bit cell indices. Each such position is its own
  // cell, keyed by its bits (merging only equal positions there), where the whole weld went
  // exact: a vertex no triangle uses may lie 1e30 mesh widths away (make_mesh), and one of
  // them turned k-ring's and texture smoothing's seams into walls (found by review).
  bool beyond(glm::vec3 p) const {
    return !(std::max(std::fabs(p.x), std::max(std::fabs(p.y), std::fabs(p.z))) / cell < 1e15);
  }
  CellKey home(glm::vec3 p) const {
    if (exact) return {float_bits(p.x), float_bits(p.y), float_bits(p.z)};
    // Bits offset past every grid index (below 1e15 < 2^50): no grid cell shares the key.
    if (beyond(p))
      return {float_bits(p.x) + (std::int64_t{1} << 62), float_bits(p.y), float_bits(p.z)};
    return {static_cast<std::int64_t>(std::floor(p.x / cell)),
            static_cast<std::int64_t>(std::floor(p.y / cell)),
            static_cast<std::int64_t>(std::floor(p.z / cell))};
  }
  // Calls visit(key) for every cell the ball around p meets (only the home cell when exact
  // or beyond the grid).
  template <class Visit>
  void for_each_cell(glm::vec3 p, Visit&& visit) const {
    if (exact || beyond(p)) {
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

// The vertices grouped by the hash of their home cell: sorted by the top `bits` bits of the
// hash (the bucket; about one vertex per bucket), with where each bucket starts and the
// positions in that order. A cell's vertices lie in its bucket, among those of the cells that
// share it: a look-up reads a cache line or two, where a binary search over all the vertices
// read twenty (it was most of the weld's time).
struct CellBuckets {
  int bits = 1;
  UninitializedVector<std::uint64_t> by_cell;  // (32-bit hash << 32) | vertex
  UninitializedVector<std::uint32_t> start;    // 2^bits + 1 bucket starts in by_cell
  UninitializedVector<glm::vec3> position;     // position[e] = positions[vertex of by_cell[e]]

  CellBuckets(const glm::vec3* positions, std::size_t count, const WeldGrid& grid, unsigned threads)
      : by_cell(count), position(count) {
    while ((std::size_t(1) << bits) < count && bits < 32) ++bits;
    parallel_for(count, kWeldGrain, threads, [&](std::size_t begin, std::size_t end) {
      for (std::size_t i = begin; i < end; ++i)
        by_cell[i] = (hash_key(grid.home(positions[i])) & 0xffffffffull) << 32 | i;
    });
    radix_sort_by_bits(by_cell, 64 - bits, bits, threads);
    const std::size_t buckets = std::size_t(1) << bits;
    start.resize(buckets + 1);
    run_starts(
        count, buckets, threads, [&](std::size_t e) { return bucket(by_cell[e] >> 32); },
        start.data());
    parallel_for(count, kWeldGrain, threads, [&](std::size_t begin, std::size_t end) {
      for (std::size_t e = begin; e < end; ++e) position[e] = positions[vertex(e)];
    });
  }
  std::size_t bucket(std::uint64_t hash32) const { return hash32 >> (32 - bits); }
  std::uint32_t vertex(std::size_t e) const { return static_cast<std::uint32_t>(by_cell[e]); }
  // Calls visit(e) for each entry whose home cell has the hash of `key` (its own cell and
  // any sharing the 32-bit hash, as the binary search found).
  template <class Visit>
  void for_each_in_cell(const CellKey& key, Visit&& visit) const {
    const std::uint64_t h = hash_key(key) & 0xffffffffull;
    const std::size_t b = bucket(h);
    for (std::uint32_t e = start[b]; e < start[b + 1]; ++e)
      if ((by_cell[e] >> 32) == h) visit(e);
  }
};

// The vertices that some other vertex merges with (a neighbour in the ball), increasing.
// Both vertices of a close pair are marked: when the tolerance's square underflows, `close`
// can accept a pair one of whose cell ranges misses the other, which the serial greedy still
// merges from the later side. Queries run in bucket order, so a vertex's own cell is read
// where the loop already is; the marks do not depend on the order.
std::vector<std::uint32_t> crowded_vertices(const glm::vec3* positions, std::size_t count,
                                            const WeldGrid& grid, float tolerance2,
                                            unsigned threads) {
  const CellBuckets cells(positions, count, grid, threads);
  std::unique_ptr<std::atomic<char>[]> marked(new std::atomic<char>[count]);
  parallel_for(count, kWeldGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) marked[i].store(0, std::memory_order_relaxed);
  });
  parallel_for(count, kWeldGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t e = begin; e < end; ++e) {
      const std::uint32_t i = cells.vertex(e);
      const glm::vec3 p = cells.position[e];
      grid.for_each_cell(p, [&](const CellKey& key) {
        cells.for_each_in_cell(key, [&](std::uint32_t other) {
          const std::uint32_t j = cells.vertex(other);
          if (j != i && close(cells.position[other], p, grid.exact, tolerance2)) {
            marked[i].store(1, std::memory_order_relaxed);
            marked[j].store(1, std::memory_order_relaxed);
          }
        });
      });
    }
  });
  return indices_where(count, threads,
                       [&](std::size_t i) { return marked[i].load(std::memory_order_relaxed); });
}

}  // namespace

Weld weld_vertices(const glm::vec3* positions, std::size_t count, float tolerance, unsigned threads,
                   StageTimings* timings) {
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
  const std::vector<std::uint32_t> crowded =
      crowded_vertices(positions, count, grid, tolerance2, threads);
  clock.lap("weld: neighbour test");
  constexpr std::uint32_t kKept = std::numeric_limits<std::uint32_t>::max();
  UninitializedVector<std::uint32_t> target(count);  // input index of the vertex it joins
  parallel_for(count, kWeldGrain, threads, [&](std::size_t begin, std::size_t end) {
    std::fill(target.begin() + begin, target.begin() + end, kKept);
  });
  {
    CellTable table(crowded.size());
    std::vector<std::uint32_t> next;  // per kept crowded vertex: the next one in its cell
    std::vector<std::uint32_t> kept;  // kept crowded vertices, in index order
    for (const std::uint32_t i : crowded) {
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
  weld.first.resize(block_first[blocks]);
  parallel_for(blocks, 1, threads, [&](std::size_t b0, std::size_t b1) {
    for (std::size_t b = b0; b < b1; ++b) {
      std::uint32_t id = block_first[b];
      for (std::size_t i = b * kWeldGrain; i < std::min(count, (b + 1) * kWeldGrain); ++i)
        if (target[i] == kKept) {
          weld.first[id] = static_cast<std::uint32_t>(i);
          weld.merged[i] = id++;
        }
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

Weld identity_weld(std::size_t count, unsigned threads) {
  Weld weld;
  weld.merged.resize(count);
  weld.first.resize(count);
  parallel_for(count, kWeldGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t v = begin; v < end; ++v)
      weld.merged[v] = weld.first[v] = static_cast<std::uint32_t>(v);
  });
  weld.count = static_cast<std::uint32_t>(count);
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

namespace {

// Whether corner k of t is the first with its vertex: a face whose corners merged is listed
// once per distinct vertex.
bool distinct_corner(const glm::uvec3& t, int k) {
  return (k == 0) || (k == 1 && t.y != t.x) || (k == 2 && t.z != t.x && t.z != t.y);
}

// Vertices per range of faces_of_vertices' second level: a range's counters (16 KiB) stay in
// L1.
constexpr int kRangeBits = 12;
constexpr std::uint32_t kRangeMask = (1u << kRangeBits) - 1;

// Blocks of faces of faces_of_vertices' first level: a few per thread (for balance), and not
// so many that the table of counts per block and range grows large.
std::size_t face_blocks(std::size_t faces, unsigned threads) {
  constexpr std::size_t kMinFaces = std::size_t(1) << 15;
  return std::max<std::size_t>(
      1, std::min<std::size_t>(faces / kMinFaces, 8 * std::size_t(resolve_threads(threads))));
}

}  // namespace

// A counting sort of the corners by vertex in two levels, so that both run in parallel: each
// block of faces counts its corners per range of 4096 vertices, then copies them to its place
// among the range's corners (ranges in order, within a range blocks in order, within a block
// faces in order); then each range sorts its corners by vertex with counters in L1. The sorts are
// stable, so each list comes out in increasing face order, as from the serial counting sort this
// replaced (tests/cpp/adjacency_reference.h).
Adjacency faces_of_vertices(const glm::uvec3* triangles, std::size_t m, std::uint32_t vertex_count,
                            unsigned threads) {
  const std::size_t ranges = (std::size_t(vertex_count) >> kRangeBits) + 1;
  const std::size_t blocks = face_blocks(m, threads);
  auto block_begin = [&](std::size_t b) { return m * b / blocks; };
  // at[r * blocks + b]: block b's corners in range r; then where block b writes them.
  std::vector<std::uint32_t> at(ranges * blocks + 1, 0u);  // the last entry: the total
  parallel_for(blocks, 1, threads, [&](std::size_t b0, std::size_t b1) {
    // Counted apart, then stored: the blocks' counts of a range share cache lines in `at`,
    // which counting there made threads fight over.
    std::vector<std::uint32_t> count(ranges);
    for (std::size_t b = b0; b < b1; ++b) {
      std::fill(count.begin(), count.end(), 0u);
      for (std::size_t f = block_begin(b); f < block_begin(b + 1); ++f)
        for (int k = 0; k < 3; ++k)
          if (distinct_corner(triangles[f], k)) ++count[triangles[f][k] >> kRangeBits];
      for (std::size_t r = 0; r < ranges; ++r) at[r * blocks + b] = count[r];
    }
  });
  std::uint32_t total = 0;
  for (std::uint32_t& c : at) total += std::exchange(c, total);
  // A range's corners take the same slots of `items` before and after its sort: the first
  // level writes each corner's face there, and its vertex's place in the range beside it (2
  // bytes: fresh memory costs its zeroing by the kernel, which 8-byte pairs made most of the
  // time); the second sorts each range's slots through a copy that stays in cache.
  Adjacency a;
  a.items.resize(total);
  UninitializedVector<std::uint16_t> local_vertex(total);
  parallel_for(blocks, 1, threads, [&](std::size_t b0, std::size_t b1) {
    std::vector<std::uint32_t> next(ranges);
    for (std::size_t b = b0; b < b1; ++b) {
      for (std::size_t r = 0; r < ranges; ++r) next[r] = at[r * blocks + b];
      for (std::size_t f = block_begin(b); f < block_begin(b + 1); ++f)
        for (int k = 0; k < 3; ++k)
          if (distinct_corner(triangles[f], k)) {
            const std::uint32_t v = triangles[f][k];
            const std::uint32_t i = next[v >> kRangeBits]++;
            a.items[i] = static_cast<std::uint32_t>(f);
            local_vertex[i] = static_cast<std::uint16_t>(v & kRangeMask);
          }
    }
  });
  a.offsets.resize(std::size_t(vertex_count) + 1);
  a.offsets[vertex_count] = total;
  parallel_for(ranges, 1, threads, [&](std::size_t r0, std::size_t r1) {
    std::vector<std::uint32_t> next(kRangeMask + 1), faces;
    for (std::size_t r = r0; r < r1; ++r) {
      const std::uint32_t first = at[r * blocks], last = at[(r + 1) * blocks];
      const std::size_t lo = r << kRangeBits;
      const std::size_t count = std::min<std::size_t>(vertex_count - lo, next.size());
      faces.assign(a.items.begin() + first, a.items.begin() + last);
      std::fill(next.begin(), next.end(), 0u);
      for (std::uint32_t i = first; i < last; ++i) ++next[local_vertex[i]];
      std::uint32_t offset = first;
      for (std::size_t v = 0; v < count; ++v) {
        a.offsets[lo + v] = offset;
        offset += std::exchange(next[v], offset);
      }
      for (std::uint32_t i = first; i < last; ++i)
        a.items[next[local_vertex[i]]++] = faces[i - first];
    }
  });
  return a;
}

namespace {

// Sorts a[0, 16) with Batcher's odd-even merge network: 63 compare-exchanges at fixed
// places, no branch on the data.
inline void sort16(std::uint32_t* a) {
  static constexpr std::uint8_t kPairs[63][2] = {
      {0, 1},   {2, 3},   {4, 5}, {6, 7},   {8, 9},   {10, 11}, {12, 13}, {14, 15}, {0, 2},
      {1, 3},   {4, 6},   {5, 7}, {8, 10},  {9, 11},  {12, 14}, {13, 15}, {1, 2},   {5, 6},
      {9, 10},  {13, 14}, {0, 4}, {1, 5},   {2, 6},   {3, 7},   {8, 12},  {9, 13},  {10, 14},
      {11, 15}, {2, 4},   {3, 5}, {10, 12}, {11, 13}, {1, 2},   {3, 4},   {5, 6},   {9, 10},
      {11, 12}, {13, 14}, {0, 8}, {1, 9},   {2, 10},  {3, 11},  {4, 12},  {5, 13},  {6, 14},
      {7, 15},  {4, 8},   {5, 9}, {6, 10},  {7, 11},  {2, 4},   {3, 5},   {6, 8},   {7, 9},
      {10, 12}, {11, 13}, {1, 2}, {3, 4},   {5, 6},   {7, 8},   {9, 10},  {11, 12}, {13, 14}};
#pragma GCC unroll 63
  for (const auto& pair : kPairs) {
    const std::uint32_t x = a[pair[0]], y = a[pair[1]];
    a[pair[0]] = std::min(x, y);
    a[pair[1]] = std::max(x, y);
  }
}

// The distinct neighbours of vertex v, increasing and without v, written to `out` (room for
// 2 per face around v: a face adds at most its 2 other corners); returns how many.
std::uint32_t list_neighbours(std::uint32_t v, const glm::uvec3* triangles,
                              const Adjacency& faces_of_vertices, std::uint32_t* out) {
  const std::uint32_t begin = faces_of_vertices.offsets[v], end = faces_of_vertices.offsets[v + 1];
  std::uint32_t n = 0;
  if (end - begin <= 8) {
    // Up to 16 corners (valence 8): gathered without a branch on them, sorted by a network
    // (the insertion sort's mispredicted branches were most of the stage), repeats dropped.
    std::uint32_t c[17];
    for (std::uint32_t i = begin; i < end; ++i) {
      const glm::uvec3 t = triangles[faces_of_vertices.items[i]];
      for (int k = 0; k < 3; ++k) {
        c[n] = t[k];
        n += t[k] != v;
      }
    }
    std::fill(c + n, c + 16, std::numeric_limits<std::uint32_t>::max());
    sort16(c);
    std::uint32_t count = 0;
    for (std::uint32_t i = 0; i < n; ++i) {
      out[count] = c[i];
      count += i == 0 || c[i] != c[i - 1];
    }
    return count;
  }
  for (std::uint32_t i = begin; i < end; ++i) {
    const glm::uvec3 t = triangles[faces_of_vertices.items[i]];
    for (int k = 0; k < 3; ++k)
      if (t[k] != v) out[n++] = t[k];
  }
  // Valences above 8 are rare but unbounded (a fan-triangulated cap, a pole): a sort that
  // stays n log n there (an insertion sort took 15 s for a 200k-face fan).
  std::sort(out, out + n);
  return static_cast<std::uint32_t>(std::unique(out, out + n) - out);
}

}  // namespace

// Each vertex lists its neighbours in its own slots of a scratch array (2 per face around
// it), then they are copied into place after the prefix sum of the counts: no serial pass,
// and the result does not depend on threads.
Adjacency vertex_neighbours(const glm::uvec3* triangles, const Adjacency& faces_of_vertices,
                            unsigned threads) {
  const std::size_t n = faces_of_vertices.size();
  constexpr std::size_t kGrain = 1 << 13;
  UninitializedVector<std::uint32_t> scratch(2 * faces_of_vertices.items.size());
  // Pointer arithmetic, not operator[]: the slots of vertices at the end with no faces start
  // at the end of the array.
  auto slots = [&](std::size_t v) {
    return scratch.data() + 2 * std::size_t(faces_of_vertices.offsets[v]);
  };
  Adjacency a;
  a.offsets.resize(n + 1);
  a.offsets[0] = 0;
  parallel_for(n, kGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t v = begin; v < end; ++v)
      a.offsets[v + 1] =
          list_neighbours(static_cast<std::uint32_t>(v), triangles, faces_of_vertices, slots(v));
  });
  inclusive_scan(a.offsets.data(), n + 1, threads);
  a.items.resize(a.offsets[n]);
  parallel_for(n, kGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t v = begin; v < end; ++v)
      std::copy(slots(v), slots(v) + (a.offsets[v + 1] - a.offsets[v]),
                a.items.data() + a.offsets[v]);
  });
  return a;
}

}  // namespace sdf
