// SPDX-License-Identifier: GPL-3.0-or-later
#include "post/uv_islands.h"

#include <algorithm>
#include <atomic>
#include <cstring>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>

#include "mesh/mesh_weld.h"
#include "util/concurrent_union_find.h"
#include "util/parallel.h"
#include "util/radix_sort.h"
#include "util/uninitialized_vector.h"

namespace sdf {

namespace {

constexpr std::size_t kFaceGrain = 1 << 14;

// A distinct (key vertex, UV) pair, the UV's -0 folded into +0 (equal as floats, so the
// same UV).
struct KeyUv {
  std::uint32_t key;
  float u, v;
};

// A corner whose UV differs from its key vertex's representative UV (a UV seam runs through
// the vertex).
struct SeamCorner {
  std::uint32_t key;
  float u, v;
  std::uint32_t face;
};

bool key_uv_less(std::uint32_t ka, float ua, float va, std::uint32_t kb, float ub, float vb) {
  return ka < kb || (ka == kb && (ua < ub || (ua == ub && va < vb)));
}

std::uint32_t bits_of(float f) {
  std::uint32_t b;
  std::memcpy(&b, &f, sizeof b);
  return b;
}

std::uint32_t hash_uv(float u, float v) {
  // splitmix64's finaliser over the two bit patterns.
  std::uint64_t x = (std::uint64_t{bits_of(u)} << 32) | bits_of(v);
  x ^= x >> 30;
  x *= 0xBF58476D1CE4E5B9ull;
  x ^= x >> 27;
  x *= 0x94D049BB133111EBull;
  x ^= x >> 31;
  return static_cast<std::uint32_t>(x);
}

// Joins the faces whose corners share a key vertex and a UV. A face with several corners on
// one key counts once, through its first such corner (as faces_of_vertices lists it).
// Streaming passes over the faces (no per-vertex lists, whose gathers miss the cache on
// every corner): each key gets a representative corner, any one; corners with its UV join
// its face, the others (where a UV seam runs through the vertex, a few percent) are sorted
// by (key, UV) and join along equal runs. The sets do not depend on which corner represents
// a key, so neither on the threads. pairs: if not null, receives every distinct (key, UV).
void join_corners(const Mesh& mesh, const float* uvs, const std::uint32_t* key,
                  std::uint32_t key_count, ConcurrentUnionFind& sets, unsigned threads,
                  std::vector<KeyUv>* pairs) {
  const std::size_t m = mesh.triangles.size();
  constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
  auto key_of = [&](std::uint32_t vertex) { return key ? key[vertex] : vertex; };
  // Corner c of a face whose keys are k: counted unless an earlier corner has the same key.
  auto counted = [](const std::uint32_t* k, int c) {
    return c == 0 || (c == 1 && k[1] != k[0]) || (c == 2 && k[2] != k[0] && k[2] != k[1]);
  };
  std::unique_ptr<std::atomic<std::uint32_t>[]> rep(new std::atomic<std::uint32_t>[key_count]);
  parallel_for(key_count, kFaceGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t k = begin; k < end; ++k) rep[k].store(kNone, std::memory_order_relaxed);
  });
  parallel_for(m, kFaceGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t f = begin; f < end; ++f) {
      const glm::uvec3 t = mesh.triangles[f];
      const std::uint32_t k[3] = {key_of(t[0]), key_of(t[1]), key_of(t[2])};
      for (int c = 0; c < 3; ++c)
        if (counted(k, c))
          rep[k[c]].store(static_cast<std::uint32_t>(3 * f + c), std::memory_order_relaxed);
    }
  });
  UninitializedVector<float> rep_uv(2 * std::size_t{key_count});
  parallel_for(key_count, kFaceGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t k = begin; k < end; ++k) {
      const std::uint32_t corner = rep[k].load(std::memory_order_relaxed);
      if (corner == kNone) continue;
      rep_uv[2 * k] = uvs[2 * corner] + 0.0f;
      rep_uv[2 * k + 1] = uvs[2 * corner + 1] + 0.0f;
    }
  });
  const std::size_t chunks = (m + kFaceGrain - 1) / kFaceGrain;
  std::vector<std::vector<SeamCorner>> chunk_seams(chunks);
  parallel_for(m, kFaceGrain, threads, [&](std::size_t begin, std::size_t end) {
    std::vector<SeamCorner>& seams = chunk_seams[begin / kFaceGrain];
    for (std::size_t f = begin; f < end; ++f) {
      const glm::uvec3 t = mesh.triangles[f];
      const std::uint32_t k[3] = {key_of(t[0]), key_of(t[1]), key_of(t[2])};
      for (int c = 0; c < 3; ++c) {
        if (!counted(k, c)) continue;
        const float u = uvs[6 * f + 2 * c] + 0.0f, v = uvs[6 * f + 2 * c + 1] + 0.0f;
        if (u == rep_uv[2 * k[c]] && v == rep_uv[2 * k[c] + 1]) {
          const std::uint32_t r = rep[k[c]].load(std::memory_order_relaxed) / 3;
          if (r != f) sets.unite(static_cast<std::uint32_t>(f), r);
        } else {
          seams.push_back({k[c], u, v, static_cast<std::uint32_t>(f)});
        }
      }
    }
  });
  std::vector<SeamCorner> seams;
  for (const auto& c : chunk_seams) seams.insert(seams.end(), c.begin(), c.end());
  std::sort(seams.begin(), seams.end(), [](const SeamCorner& a, const SeamCorner& b) {
    return key_uv_less(a.key, a.u, a.v, b.key, b.u, b.v);
  });
  auto same = [](const SeamCorner& a, const SeamCorner& b) {
    return a.key == b.key && a.u == b.u && a.v == b.v;
  };
  for (std::size_t i = 1; i < seams.size(); ++i)
    if (same(seams[i], seams[i - 1])) sets.unite(seams[i].face, seams[i - 1].face);
  if (!pairs) return;
  pairs->clear();
  for (std::uint32_t k = 0; k < key_count; ++k)
    if (rep[k].load(std::memory_order_relaxed) != kNone)
      pairs->push_back({k, rep_uv[2 * k], rep_uv[2 * k + 1]});
  for (std::size_t i = 0; i < seams.size(); ++i)
    if (i == 0 || !same(seams[i], seams[i - 1]))
      pairs->push_back({seams[i].key, seams[i].u, seams[i].v});
}

bool within(const Mesh& mesh, std::uint32_t a, std::uint32_t b, double reach2) {
  const glm::dvec3 d = glm::dvec3(mesh.vertices[a]) - glm::dvec3(mesh.vertices[b]);
  return glm::dot(d, d) <= reach2;
}

// Whether merging vertices within `tolerance` could change the islands found with vertex
// indices: two distinct vertices that share a UV, or two corners of one face, lie within
// `reach` of each other. Two vertices merged into one both lie within a tolerance of the kept
// one, so within 2 of each other (plus float rounding in weld_vertices): reach = 4
// tolerances misses none, and a false alarm only costs the weld.
bool weld_can_join(const Mesh& mesh, const std::vector<KeyUv>& pairs, float tolerance,
                   unsigned threads) {
  const double reach = 4.0 * static_cast<double>(tolerance);
  const double reach2 = reach * reach;
  std::atomic<bool> found{false};
  parallel_for(mesh.triangles.size(), kFaceGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t f = begin; f < end && !found.load(std::memory_order_relaxed); ++f) {
      const glm::uvec3 t = mesh.triangles[f];
      if ((t.x != t.y && within(mesh, t.x, t.y, reach2)) ||
          (t.y != t.z && within(mesh, t.y, t.z, reach2)) ||
          (t.z != t.x && within(mesh, t.z, t.x, reach2)))
        found = true;
    }
  });
  if (found) return true;

  // Equal UVs of distinct vertices: sort the pairs by a hash of the UV, then compare within
  // runs of equal hashes.
  UninitializedVector<std::uint64_t> items(pairs.size());
  parallel_for(pairs.size(), kFaceGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i)
      items[i] = (std::uint64_t{hash_uv(pairs[i].u, pairs[i].v)} << 32) | i;
  });
  radix_sort_by_bits(items, 32, 32, threads);
  // More vertices than this on one UV (a degenerate layout): weld rather than compare them all.
  constexpr std::size_t kMostCompared = 64;
  parallel_for(items.size(), kFaceGrain, threads, [&](std::size_t begin, std::size_t end) {
    std::vector<KeyUv> run;
    for (std::size_t i = begin; i < end && !found.load(std::memory_order_relaxed); ++i) {
      const std::uint64_t hash = items[i] >> 32;
      if (i > 0 && items[i - 1] >> 32 == hash) continue;  // not the start of a run
      std::size_t j = i + 1;
      while (j < items.size() && items[j] >> 32 == hash) ++j;
      if (j - i == 1) continue;
      run.clear();
      for (std::size_t r = i; r < j; ++r)
        run.push_back(pairs[static_cast<std::uint32_t>(items[r])]);
      std::sort(run.begin(), run.end(), [](const KeyUv& a, const KeyUv& b) {
        return a.u < b.u || (a.u == b.u && a.v < b.v);
      });
      for (std::size_t a = 0; a < run.size();) {
        std::size_t b = a + 1;
        while (b < run.size() && run[b].u == run[a].u && run[b].v == run[a].v) ++b;
        if (b - a > kMostCompared) found = true;
        for (std::size_t x = a; x < b && !found; ++x)
          for (std::size_t y = x + 1; y < b; ++y)
            if (within(mesh, run[x].key, run[y].key, reach2)) found = true;
        a = b;
      }
    }
  });
  return found;
}

// Island ids from the sets: the roots (each set's smallest face) numbered in face order.
std::vector<std::int32_t> number_islands(const ConcurrentUnionFind& sets, std::size_t m,
                                         std::int32_t& count, unsigned threads) {
  std::vector<std::int32_t> island(m);
  UninitializedVector<std::uint32_t> root(m);
  const std::size_t chunks = (m + kFaceGrain - 1) / kFaceGrain;
  std::vector<std::int32_t> roots_before(chunks + 1, 0);
  parallel_for(m, kFaceGrain, threads, [&](std::size_t begin, std::size_t end) {
    std::int32_t roots = 0;
    for (std::size_t f = begin; f < end; ++f) {
      root[f] = sets.find(static_cast<std::uint32_t>(f));
      roots += root[f] == f;
    }
    roots_before[begin / kFaceGrain + 1] = roots;
  });
  for (std::size_t c = 0; c < chunks; ++c) roots_before[c + 1] += roots_before[c];
  count = roots_before[chunks];
  // Roots first (a root is at most its faces, possibly in an earlier chunk), then the rest.
  parallel_for(m, kFaceGrain, threads, [&](std::size_t begin, std::size_t end) {
    std::int32_t next = roots_before[begin / kFaceGrain];
    for (std::size_t f = begin; f < end; ++f)
      if (root[f] == f) island[f] = next++;
  });
  parallel_for(m, kFaceGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t f = begin; f < end; ++f)
      if (root[f] != f) island[f] = island[root[f]];
  });
  return island;
}

}  // namespace

UvIslands label_uv_islands(const Mesh& mesh, const float* uvs, double weld_tolerance,
                           bool need_merged, unsigned threads) {
  const std::size_t m = mesh.triangles.size();
  const std::uint32_t vertex_count = static_cast<std::uint32_t>(mesh.vertices.size());
  // Corners are numbered 3 f + c in 32 bits, one value kept free.
  if (m >= (std::size_t{1} << 32) / 3)
    throw std::invalid_argument("UV islands take at most " +
                                std::to_string((std::size_t{1} << 32) / 3 - 1) + " faces, got " +
                                std::to_string(m));
  const bool may_merge = weld_tolerance >= 0.0;
  const float tolerance = may_merge ? sdf::weld_tolerance(mesh, weld_tolerance) : 0.0f;
  UvIslands out;
  out.vertex_count = mesh.vertices.size();
  out.weld_tolerance = weld_tolerance;
  out.need_merged = need_merged;
  ConcurrentUnionFind sets(m, threads);
  if (!need_merged || !may_merge) {
    out.merged_count = vertex_count;
    std::vector<KeyUv> pairs;
    join_corners(mesh, uvs, nullptr, vertex_count, sets, threads, may_merge ? &pairs : nullptr);
    if (!may_merge || !weld_can_join(mesh, pairs, tolerance, threads)) {
      out.face_island = number_islands(sets, m, out.count, threads);
      return out;
    }
    sets = ConcurrentUnionFind(m, threads);  // start again on merged vertices
  }
  Weld weld = weld_vertices(mesh.vertices.data(), mesh.vertices.size(), tolerance, threads);
  out.merged = std::move(weld.merged);
  out.merged_count = weld.count;
  join_corners(mesh, uvs, out.merged.data(), weld.count, sets, threads, nullptr);
  out.face_island = number_islands(sets, m, out.count, threads);
  return out;
}

std::vector<std::int32_t> uv_islands(const Mesh& mesh, const float* uvs, double weld_tolerance,
                                     unsigned threads) {
  return label_uv_islands(mesh, uvs, weld_tolerance, false, threads).face_island;
}

}  // namespace sdf
