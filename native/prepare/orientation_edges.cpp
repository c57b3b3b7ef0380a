// SPDX-License-Identifier: GPL-3.0-or-later
#include "prepare/orientation_edges.h"

#include <algorithm>
#include <atomic>

#include "util/parallel.h"
#include "util/uninitialized_vector.h"

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
// Pairs of faces joined per batch of prefetches (EdgeUses::join_patches).
constexpr std::size_t kJoinBatch = 16;

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
  std::vector<std::size_t> offsets;   // bucket b: uses[offsets[b] .. offsets[b + 1])
  int shift = 0;                      // bucket of vertex v: v >> shift
};

// Level one: parallel over blocks of faces, each writing its own ranges (bucket-major,
// block-minor offsets).
UseBuckets uses_by_bucket(const Mesh& mesh, unsigned threads, const std::uint32_t* same_place) {
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
    glm::uvec3 t = mesh.triangles[f];
    if (same_place) t = glm::uvec3(same_place[t.x], same_place[t.y], same_place[t.z]);
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

// Calls visit(edge, edge_end) for each edge's run of uses in [first, last), a bucket sorted
// by lower vertex, then higher vertex, then face.
template <class Visit>
void for_each_edge(const EdgeUse* first, const EdgeUse* last, Visit&& visit) {
  for (const EdgeUse* edge = first; edge != last;) {
    const EdgeUse* edge_end = edge;
    while (edge_end != last && edge_end->low() == edge->low() && edge_end->high == edge->high)
      ++edge_end;
    visit(edge, edge_end);
    edge = edge_end;
  }
}

// Calls link(use, other) for each use of the edge [edge, edge_end) that exactly one use of
// another face shares. Within the edge's run of s uses (by face), a use of face g has
// s - (uses of g) uses of other faces; when that is one, it is the one outside g's run.
template <class Link>
void match_uses(const EdgeUse* edge, const EdgeUse* edge_end, Link&& link) {
  const std::ptrdiff_t s = edge_end - edge;
  for (const EdgeUse* run = edge; run != edge_end;) {
    const EdgeUse* run_end = run;
    while (run_end != edge_end && run_end->face == run->face) ++run_end;
    if (s - (run_end - run) == 1) {
      const EdgeUse& other = run == edge ? *run_end : *edge;
      for (const EdgeUse* u = run; u != run_end; ++u) link(*u, other);
    }
    run = run_end;
  }
}

// Level two: one bucket's uses ordered by lower vertex (a stable counting sort), then each
// lower vertex's by higher vertex and face; visit(list, list_end) is called on each lower
// vertex's uses once sorted, while they are in cache (no edge spans two lower vertices).
template <class Visit>
void sort_bucket(EdgeUse* first, EdgeUse* last, std::size_t vertices,
                 std::vector<std::uint32_t>& counts, std::vector<EdgeUse>& scratch, Visit&& visit) {
  counts.assign(vertices + 1, 0);
  for (EdgeUse* u = first; u != last; ++u) ++counts[u->low() + 1];
  for (std::size_t v = 0; v < vertices; ++v) counts[v + 1] += counts[v];
  scratch.resize(static_cast<std::size_t>(last - first));
  for (EdgeUse* u = first; u != last; ++u) scratch[counts[u->low()]++] = *u;
  std::copy(scratch.begin(), scratch.end(), first);
  for (EdgeUse* list = first; list != last;) {
    EdgeUse* list_end = list;
    while (list_end != last && list_end->low() == list->low()) ++list_end;
    // One 64-bit compare: these lists are short (a vertex's edges), sorted by insertion.
    std::sort(list, list_end, [](const EdgeUse& a, const EdgeUse& b) {
      return (std::uint64_t{a.high} << 32 | a.face) < (std::uint64_t{b.high} << 32 | b.face);
    });
    visit(static_cast<const EdgeUse*>(list), static_cast<const EdgeUse*>(list_end));
    list = list_end;
  }
}

// Calls visit(first, last) for each bucket's uses, in parallel.
template <class Visit>
void for_each_bucket(const UseBuckets& buckets, unsigned threads, Visit&& visit) {
  if (buckets.offsets.empty()) return;
  parallel_for(buckets.offsets.size() - 1, 4, threads, [&](std::size_t b0, std::size_t b1) {
    for (std::size_t b = b0; b < b1; ++b)
      visit(buckets.uses.data() + buckets.offsets[b], buckets.uses.data() + buckets.offsets[b + 1]);
  });
}

}  // namespace

struct EdgeUses::Buckets : UseBuckets {};

EdgeUses::EdgeUses(const Mesh& mesh, unsigned threads, const std::uint32_t* same_place)
    : buckets_(std::make_unique<Buckets>()), faces_(mesh.triangles.size()) {
  const std::size_t nv = mesh.vertices.size();
  if (faces_ == 0 || nv == 0) return;
  static_cast<UseBuckets&>(*buckets_) = uses_by_bucket(mesh, threads, same_place);
  const std::size_t bucket_count = buckets_->offsets.size() - 1;
  // Sorted, and at once whether some pair disagrees: no scattered writes per face in the
  // common case.
  std::atomic<bool> any_same{false};
  parallel_for(bucket_count, 4, threads, [&](std::size_t b0, std::size_t b1) {
    std::vector<std::uint32_t> counts;
    std::vector<EdgeUse> scratch;
    bool mine = false;
    for (std::size_t b = b0; b < b1; ++b) {
      EdgeUse* first = buckets_->uses.data() + buckets_->offsets[b];
      EdgeUse* last = buckets_->uses.data() + buckets_->offsets[b + 1];
      const std::size_t vertices =
          std::min(nv, (b + 1) << buckets_->shift) - (b << buckets_->shift);
      sort_bucket(first, last, vertices, counts, scratch,
                  [&](const EdgeUse* list, const EdgeUse* list_end) {
                    for_each_edge(list, list_end, [&](const EdgeUse* edge, const EdgeUse* end) {
                      match_uses(edge, end, [&](const EdgeUse& use, const EdgeUse& other) {
                        mine |= use.forward() == other.forward();
                      });
                    });
                  });
    }
    if (mine) any_same.store(true, std::memory_order_relaxed);
  });
  any_same_ = any_same.load();
}

EdgeUses::~EdgeUses() = default;

EdgeNeighbours EdgeUses::neighbours(unsigned threads) const {
  EdgeNeighbours out;
  out.face.resize(3 * faces_);
  out.same.resize(3 * faces_);
  parallel_for(3 * faces_, std::size_t{1} << 16, threads, [&](std::size_t begin, std::size_t end) {
    std::fill(out.face.begin() + begin, out.face.begin() + end, kNoNeighbour);
    std::fill(out.same.begin() + begin, out.same.begin() + end, 0);
  });
  // Each use belongs to one edge, so no two tasks write the same slot.
  for_each_bucket(*buckets_, threads, [&](const EdgeUse* first, const EdgeUse* last) {
    for_each_edge(first, last, [&](const EdgeUse* edge, const EdgeUse* edge_end) {
      match_uses(edge, edge_end, [&](const EdgeUse& use, const EdgeUse& other) {
        const std::size_t slot = 3 * std::size_t{use.face} + use.corner();
        out.face[slot] = other.face;
        out.same[slot] = use.forward() == other.forward();
      });
    });
  });
  return out;
}

bool EdgeUses::join_patches(ConcurrentParityUnionFind& sets, unsigned threads) const {
  std::atomic<bool> ok{true};
  for_each_bucket(*buckets_, threads, [&](const EdgeUse* first, const EdgeUse* last) {
    if (!ok.load(std::memory_order_relaxed)) return;  // refused elsewhere
    bool mine = true;
    // Pairs are joined in batches, their faces' words prefetched as they are found: the
    // faces of a vertex's edges lie anywhere in the face order.
    struct Pair {
      std::uint32_t a, b, differ;
    };
    Pair batch[kJoinBatch];
    std::size_t held = 0;
    auto join_held = [&] {
      for (std::size_t i = 0; i < held; ++i)
        mine &= sets.unite(batch[i].a, batch[i].b, batch[i].differ);
      held = 0;
    };
    for_each_edge(first, last, [&](const EdgeUse* edge, const EdgeUse* edge_end) {
      const std::ptrdiff_t s = edge_end - edge;
      if (s == 2 && edge[0].face != edge[1].face) {  // the lists' mutual pair
        sets.prefetch_word(edge[0].face);
        sets.prefetch_word(edge[1].face);
        batch[held++] = {edge[0].face, edge[1].face, edge[0].forward() == edge[1].forward()};
        if (held == kJoinBatch) join_held();
      } else if (s > 2) {  // any link here is one-sided (a run of s - 1 uses of one face)
        match_uses(edge, edge_end, [&](const EdgeUse&, const EdgeUse&) { mine = false; });
      }
    });
    join_held();
    if (!mine) ok.store(false, std::memory_order_relaxed);
  });
  return ok.load();
}

}  // namespace sdf
