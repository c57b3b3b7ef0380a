// SPDX-License-Identifier: GPL-3.0-or-later
#include "orientation_edges.h"

#include <algorithm>
#include <atomic>
#include <tuple>

#include "parallel.h"
#include "uninitialized_vector.h"

namespace sdf {

namespace {

// Edge uses are grouped by the edge's lower vertex with a two-level counting sort, because
// vertex-indexed counters or lists scattered over the whole mesh miss the cache on every
// access when face order and vertex order differ (a subdivided mesh: 3x slower measured).
// Level one splits the uses, read in face order, into 2^kBucketBits buckets of consecutive
// lower vertices: few enough write streams for the TLB and the write buffers. Level two sorts
// one bucket (tens of KiB for a million faces: it stays in cache) and matches its edges.
constexpr int kBucketBits = 9;
constexpr std::size_t kFacesPerBlock = 1 << 15;

// One use of an edge by a face, in the bucket of the edge's lower vertex.
struct EdgeUse {
  std::uint32_t high;  // the edge's higher vertex
  std::uint32_t face;
  // (lower vertex - bucket's first vertex) << 3 | corner k << 1 | forward, where the edge
  // runs from corner k to corner k + 1, and forward means it runs lower -> higher (two uses
  // agree when it differs).
  std::uint32_t bits;
  std::uint32_t low() const { return bits >> 3; }
  std::uint32_t corner() const { return (bits >> 1) & 3; }
  bool forward() const { return bits & 1; }
};

struct UseBuckets {
  UninitializedVector<EdgeUse> uses;  // every element written by the scatter
  std::vector<std::size_t> offsets;  // bucket b: uses[offsets[b] .. offsets[b + 1])
  int shift = 0;                     // bucket of vertex v: v >> shift
};

// Level one: parallel over blocks of faces, each writing its own ranges (bucket-major,
// block-minor offsets).
UseBuckets uses_by_bucket(const Mesh& mesh, unsigned threads) {
  const std::size_t n = mesh.triangles.size(), nv = mesh.vertices.size();
  UseBuckets out;
  int vertex_bits = 0;
  while ((std::size_t{1} << vertex_bits) < nv) ++vertex_bits;
  out.shift = std::max(0, vertex_bits - kBucketBits);
  const std::size_t buckets = ((nv - 1) >> out.shift) + 1;
  const std::size_t blocks =
      std::max<std::size_t>(1, std::min<std::size_t>(resolve_threads(threads), n / kFacesPerBlock));
  auto block_begin = [&](std::size_t b) { return n * b / blocks; };
  auto for_each_use = [&](std::size_t f, auto&& visit) {
    const glm::uvec3 t = mesh.triangles[f];
    for (std::uint32_t k = 0; k < 3; ++k) {
      const std::uint32_t a = t[k], b = t[(k + 1) % 3];
      if (a != b) visit(a, b, k);
    }
  };

  std::vector<std::size_t> at(blocks * buckets, 0);
  parallel_for(blocks, 1, threads, [&](std::size_t b0, std::size_t b1) {
    for (std::size_t b = b0; b < b1; ++b)
      for (std::size_t f = block_begin(b); f < block_begin(b + 1); ++f)
        for_each_use(f, [&](std::uint32_t a, std::uint32_t c, std::uint32_t) {
          ++at[b * buckets + (std::min(a, c) >> out.shift)];
        });
  });
  out.offsets.assign(buckets + 1, 0);
  std::size_t total = 0;
  for (std::size_t bucket = 0; bucket < buckets; ++bucket) {
    out.offsets[bucket] = total;
    for (std::size_t b = 0; b < blocks; ++b) {
      const std::size_t count = at[b * buckets + bucket];
      at[b * buckets + bucket] = total;
      total += count;
    }
  }
  out.offsets[buckets] = total;
  out.uses.resize(total);
  const std::uint32_t local_mask = (std::uint32_t{1} << out.shift) - 1;
  parallel_for(blocks, 1, threads, [&](std::size_t b0, std::size_t b1) {
    for (std::size_t b = b0; b < b1; ++b)
      for (std::size_t f = block_begin(b); f < block_begin(b + 1); ++f)
        for_each_use(f, [&](std::uint32_t a, std::uint32_t c, std::uint32_t k) {
          const std::uint32_t low = std::min(a, c);
          out.uses[at[b * buckets + (low >> out.shift)]++] =
              EdgeUse{std::max(a, c), static_cast<std::uint32_t>(f),
                      (low & local_mask) << 3 | k << 1 | std::uint32_t{a < c}};
        });
  });
  return out;
}

// Level two, first half: one bucket's uses ordered by lower vertex (a stable counting sort).
void sort_by_low(EdgeUse* first, EdgeUse* last, std::size_t vertices,
                 std::vector<std::uint32_t>& counts, std::vector<EdgeUse>& scratch) {
  counts.assign(vertices + 1, 0);
  for (EdgeUse* u = first; u != last; ++u) ++counts[u->low() + 1];
  for (std::size_t v = 0; v < vertices; ++v) counts[v + 1] += counts[v];
  scratch.resize(static_cast<std::size_t>(last - first));
  for (EdgeUse* u = first; u != last; ++u) scratch[counts[u->low()]++] = *u;
  std::copy(scratch.begin(), scratch.end(), first);
}

// Level two, second half: calls link(use, other) for each use of an edge in [first, last)
// (the uses of one lower vertex) that exactly one use of another face shares. Sorted by edge,
// then face: within an edge's run of s uses, a use of face g has s - (uses of g) uses of
// other faces; when that is one, it is the one outside g's run.
template <class Link>
void match_uses(EdgeUse* first, EdgeUse* last, Link&& link) {
  std::sort(first, last, [](const EdgeUse& a, const EdgeUse& b) {
    return std::tie(a.high, a.face) < std::tie(b.high, b.face);
  });
  for (EdgeUse* edge = first; edge != last;) {
    EdgeUse* edge_end = edge;
    while (edge_end != last && edge_end->high == edge->high) ++edge_end;
    const std::ptrdiff_t s = edge_end - edge;
    for (EdgeUse* run = edge; run != edge_end;) {
      EdgeUse* run_end = run;
      while (run_end != edge_end && run_end->face == run->face) ++run_end;
      if (s - (run_end - run) == 1) {
        const EdgeUse& other = run == edge ? *run_end : *edge;
        for (EdgeUse* u = run; u != run_end; ++u) link(*u, other);
      }
      run = run_end;
    }
    edge = edge_end;
  }
}

// match_uses over every lower vertex, in parallel by bucket; sorts the buckets first when
// asked (the first pass).
template <class Link>
void match_all(UseBuckets& buckets, std::size_t vertex_count, bool sort_first, unsigned threads,
               Link&& link) {
  parallel_for(buckets.offsets.size() - 1, 4, threads, [&](std::size_t b0, std::size_t b1) {
    std::vector<std::uint32_t> counts;
    std::vector<EdgeUse> scratch;
    for (std::size_t b = b0; b < b1; ++b) {
      EdgeUse* first = buckets.uses.data() + buckets.offsets[b];
      EdgeUse* last = buckets.uses.data() + buckets.offsets[b + 1];
      if (sort_first) {
        const std::size_t vertices =
            std::min(vertex_count, (b + 1) << buckets.shift) - (b << buckets.shift);
        sort_by_low(first, last, vertices, counts, scratch);
      }
      for (EdgeUse* list = first; list != last;) {
        EdgeUse* list_end = list;
        while (list_end != last && list_end->low() == list->low()) ++list_end;
        match_uses(list, list_end, link);
        list = list_end;
      }
    }
  });
}

}  // namespace

EdgeNeighbours manifold_edge_neighbours(const Mesh& mesh, unsigned threads, bool always_list) {
  const std::size_t n = mesh.triangles.size(), nv = mesh.vertices.size();
  EdgeNeighbours out;
  if (n == 0 || nv == 0) return out;
  UseBuckets buckets = uses_by_bucket(mesh, threads);
  // First only whether some pair disagrees: no scattered writes per face in the common case.
  std::atomic<bool> any_same{false};
  match_all(buckets, nv, true, threads, [&](const EdgeUse& use, const EdgeUse& other) {
    if (use.forward() == other.forward()) any_same.store(true, std::memory_order_relaxed);
  });
  out.any_same = any_same.load();
  if (!out.any_same && !always_list) return out;
  out.face.assign(3 * n, kNoNeighbour);
  out.same.assign(3 * n, 0);
  // Each use belongs to one lower vertex, so no two tasks write the same slot.
  match_all(buckets, nv, false, threads, [&](const EdgeUse& use, const EdgeUse& other) {
    const std::size_t slot = 3 * std::size_t{use.face} + use.corner();
    out.face[slot] = other.face;
    out.same[slot] = use.forward() == other.forward();
  });
  return out;
}

}  // namespace sdf
