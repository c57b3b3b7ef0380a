// SPDX-License-Identifier: GPL-3.0-or-later
#include "prepare/orientation_parts.h"

#include <algorithm>
#include <atomic>
#include <cstring>

#include <glm/glm.hpp>

#include "util/concurrent_union_find.h"
#include "util/parallel.h"
#include "util/prefetch.h"

namespace sdf {

namespace {

constexpr std::size_t kGrain = 1 << 14;

// Float bits of a position, with -0 read as +0 (they are the same place).
std::uint32_t bits_of(float x) {
  if (x == 0.0f) x = 0.0f;
  std::uint32_t b;
  std::memcpy(&b, &x, sizeof b);
  return b;
}

// Items handled per batch of prefetches.
constexpr std::size_t kBatch = 16;

std::uint64_t position_hash(glm::vec3 p) {
  std::uint64_t h = bits_of(p.x) * 0x9E3779B97F4A7C15ull;
  h = (h ^ bits_of(p.y)) * 0xC2B2AE3D27D4EB4Full;
  h = (h ^ bits_of(p.z)) * 0x165667B19E3779F9ull;
  return h ^ (h >> 31);
}

}  // namespace

// A lock-free open-addressing table: equal positions probe the same slots, and the first to
// claim an empty one stands for them. A slot holds the hash's high half beside the vertex, so
// that a probe past another position rarely has to load that vertex (a cache miss on a mesh
// whose vertex order is scattered).
UninitializedVector<std::uint32_t> weld_exact(const Mesh& mesh, unsigned threads) {
  const std::size_t nv = mesh.vertices.size();
  std::size_t size = 16;
  while (2 * size < 3 * nv) size *= 2;  // at most 2/3 full: short probe runs, a small table
  const std::size_t mask = size - 1;
  // hash high << 32 | vertex + 1; 0 = empty
  UninitializedVector<std::atomic<std::uint64_t>> slot(size);
  parallel_for(size, kGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t s = begin; s < end; ++s) slot[s].store(0, std::memory_order_relaxed);
  });
  UninitializedVector<std::uint32_t> rep(nv);
  parallel_for(nv, kGrain, threads, [&](std::size_t begin, std::size_t end) {
    std::uint64_t hash[kBatch];
    for (std::size_t first = begin; first < end; first += kBatch) {
      const std::size_t count = std::min(kBatch, end - first);
      for (std::size_t i = 0; i < count; ++i) {
        hash[i] = position_hash(mesh.vertices[first + i]);
        prefetch(&slot[hash[i] & mask]);
      }
      for (std::size_t i = 0; i < count; ++i) {
        const std::size_t v = first + i;
        const glm::vec3 p = mesh.vertices[v];
        const std::uint64_t mine = (hash[i] & 0xffffffff00000000ull) | (v + 1);
        for (std::size_t s = hash[i] & mask;; s = (s + 1) & mask) {
          std::uint64_t held = slot[s].load(std::memory_order_acquire);
          if (held == 0 && slot[s].compare_exchange_strong(held, mine, std::memory_order_acq_rel)) {
            rep[v] = static_cast<std::uint32_t>(v);
            break;
          }
          const std::uint32_t other = static_cast<std::uint32_t>(held) - 1;
          // == reads -0 and +0 as equal, as the sort this replaced did.
          if ((held >> 32) == (hash[i] >> 32) && mesh.vertices[other] == p) {
            rep[v] = other;
            break;
          }
        }
      }
    }
  });
  return rep;
}

bool any_shared_place(const UninitializedVector<std::uint32_t>& same_place, unsigned threads) {
  std::atomic<bool> any{false};
  parallel_for(same_place.size(), kGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t v = begin; v < end; ++v)
      if (same_place[v] != v) {
        any.store(true, std::memory_order_relaxed);
        return;
      }
  });
  return any.load();
}

Parts find_parts(const Mesh& mesh, unsigned threads) {
  return find_parts(mesh, weld_exact(mesh, threads), threads);
}

Parts find_parts(const Mesh& mesh, UninitializedVector<std::uint32_t> same_place,
                 unsigned threads) {
  const std::size_t n = mesh.triangles.size(), nv = mesh.vertices.size();
  // Vertices at one position start in one set (each points at the one standing for them).
  ConcurrentUnionFind sets(std::move(same_place), threads);
  parallel_for(n, kGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t first = begin; first < end; first += kBatch) {
      const std::size_t last = std::min(end, first + kBatch);
      for (std::size_t f = first; f < last; ++f)
        for (int k = 0; k < 3; ++k) sets.prefetch_parent(mesh.triangles[f][k]);
      for (std::size_t f = first; f < last; ++f) {
        const glm::uvec3 t = mesh.triangles[f];
        sets.unite(t.x, t.y);
        sets.unite(t.x, t.z);
      }
    }
  });
  Parts parts;
  parts.root_of_vertex.resize(nv);
  parallel_for(nv, kGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t v = begin; v < end; ++v)
      parts.root_of_vertex[v] = sets.find(static_cast<std::uint32_t>(v));
  });
  parts.part_of.resize(n);
  parallel_for(n, kGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t f = begin; f < end; ++f)
      parts.part_of[f] = parts.root_of_vertex[mesh.triangles[f].x];
  });
  // Roots to part numbers in order of first face: serial, but light (a sequential read and
  // mostly one compare per face).
  parts.part_of_root.assign(nv, kNoPart);
  std::uint32_t previous_root = kNoPart, previous_part = 0;
  for (std::size_t f = 0; f < n; ++f) {
    const std::uint32_t root = parts.part_of[f];
    if (root != previous_root) {
      std::uint32_t& part = parts.part_of_root[root];
      if (part == kNoPart) part = static_cast<std::uint32_t>(parts.count++);
      previous_root = root;
      previous_part = part;
    }
    parts.part_of[f] = previous_part;
  }
  return parts;
}

std::vector<PartBox> part_boxes(const Mesh& mesh, const Parts& parts, unsigned threads) {
  const std::size_t nv = mesh.vertices.size();
  auto add_vertices = [&](std::vector<PartBox>& boxes, std::size_t begin, std::size_t end) {
    for (std::size_t v = begin; v < end; ++v) {
      const std::uint32_t part = parts.part_of_root[parts.root_of_vertex[v]];
      if (part == kNoPart) continue;
      const glm::dvec3 p(mesh.vertices[v]);
      boxes[part].lo = glm::min(boxes[part].lo, p);
      boxes[part].hi = glm::max(boxes[part].hi, p);
    }
  };
  const std::size_t chunks = (nv + kGrain - 1) / kGrain;
  std::vector<PartBox> boxes(parts.count);
  if (parts.count > 64 || chunks < 2) {
    add_vertices(boxes, 0, nv);
    return boxes;
  }
  std::vector<std::vector<PartBox>> chunk_boxes(chunks);
  parallel_for(nv, kGrain, threads, [&](std::size_t begin, std::size_t end) {
    std::vector<PartBox>& mine = chunk_boxes[begin / kGrain];
    mine.resize(parts.count);
    add_vertices(mine, begin, end);
  });
  for (const std::vector<PartBox>& chunk : chunk_boxes)
    for (std::size_t p = 0; p < parts.count; ++p) {
      boxes[p].lo = glm::min(boxes[p].lo, chunk[p].lo);
      boxes[p].hi = glm::max(boxes[p].hi, chunk[p].hi);
    }
  return boxes;
}

}  // namespace sdf
