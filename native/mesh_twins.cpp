// SPDX-License-Identifier: GPL-3.0-or-later
#include "mesh_twins.h"

#include <algorithm>
#include <atomic>
#include <cstring>
#include <mutex>
#include <tuple>

#include "parallel.h"
#include "prefetch.h"
#include "uninitialized_vector.h"

namespace sdf {

namespace {

constexpr std::size_t kGrain = 1 << 14;
// Faces handled per batch of prefetches: their corners' hashes, then their table slots, are
// asked for together (a subdivided mesh's corners, and the table, are read out of order).
constexpr std::size_t kBatch = 16;

std::uint64_t mix(std::uint64_t h) {
  h = (h ^ (h >> 30)) * 0xBF58476D1CE4E5B9ull;
  h = (h ^ (h >> 27)) * 0x94D049BB133111EBull;
  return h ^ (h >> 31);
}

// Bits of a coordinate, -0 read as +0 (the same place).
std::uint32_t bits_of(float x) {
  if (x == 0.0f) x = 0.0f;
  std::uint32_t b;
  std::memcpy(&b, &x, sizeof b);
  return b;
}

std::uint64_t position_hash(glm::vec3 p) {
  return mix((std::uint64_t{bits_of(p.x)} << 32 | bits_of(p.y)) ^ mix(bits_of(p.z)));
}

// The corner of face `other` at the position of corner k of `face`, or -1.
int corner_at(const Mesh& mesh, std::size_t face, int k, std::size_t other) {
  const glm::vec3 p = mesh.vertices[mesh.triangles[face][k]];
  for (int j = 0; j < 3; ++j)
    if (mesh.vertices[mesh.triangles[other][j]] == p) return j;  // == : -0 equals +0
  return -1;
}

// Two faces of three distinct positions each: the same positions when each corner finds one.
bool same_positions(const Mesh& mesh, std::size_t face, std::size_t other) {
  return corner_at(mesh, face, 0, other) >= 0 && corner_at(mesh, face, 1, other) >= 0 &&
         corner_at(mesh, face, 2, other) >= 0;
}

// A face that found its positions' slot held by another face at the same positions.
struct Join {
  std::size_t slot;
  std::uint32_t face;
};

}  // namespace

ReversedTwins reversed_twins(const Mesh& mesh, unsigned threads) {
  ReversedTwins out;
  const std::size_t n = mesh.triangles.size(), nv = mesh.vertices.size();
  if (n < 2) return out;

  // Per vertex, a hash of its position: a face's key then reads 8 bytes a corner, not 12 and
  // a compare (measured 2x faster on a subdivided mesh, whose corners are misses).
  UninitializedVector<std::uint64_t> hash(nv);
  parallel_for(nv, kGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t v = begin; v < end; ++v) hash[v] = position_hash(mesh.vertices[v]);
  });
  // A face's key, the same for any order of its corners (a sum of their hashes); 0 for a face
  // with two corners at one position (equal hashes), which has no twin.
  auto key_of = [&](std::size_t face) -> std::uint64_t {
    const glm::uvec3 t = mesh.triangles[face];
    const std::uint64_t a = hash[t.x], b = hash[t.y], c = hash[t.z];
    if (a == b || b == c || a == c) return 0;
    const std::uint64_t key = mix(a + b + c);
    return key == 0 ? 1 : key;
  };

  std::size_t size = 16;
  while (2 * size < 3 * n) size *= 2;  // at most 2/3 full: short probe runs
  const std::size_t mask = size - 1;
  // Each slot: key's high half << 32 | face + 1, for the first face at a set of positions
  // (which one depends on thread timing: only the groups are used); 0 = empty.
  UninitializedVector<std::atomic<std::uint64_t>> slot(size);
  parallel_for(size, kGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t s = begin; s < end; ++s) slot[s].store(0, std::memory_order_relaxed);
  });

  std::vector<Join> joins;
  std::mutex joins_lock;
  parallel_for(n, kGrain, threads, [&](std::size_t begin, std::size_t end) {
    std::vector<Join> mine;
    std::uint64_t key[kBatch];
    for (std::size_t first = begin; first < end; first += kBatch) {
      const std::size_t count = std::min(kBatch, end - first);
      for (std::size_t i = 0; i < count; ++i)
        for (int k = 0; k < 3; ++k) prefetch(&hash[mesh.triangles[first + i][k]]);
      for (std::size_t i = 0; i < count; ++i) {
        key[i] = key_of(first + i);
        prefetch(&slot[key[i] & mask]);
      }
      for (std::size_t i = 0; i < count; ++i) {
        if (key[i] == 0) continue;
        const std::size_t face = first + i;
        const std::uint64_t entry = (key[i] & 0xffffffff00000000ull) | (face + 1);
        for (std::size_t s = key[i] & mask;; s = (s + 1) & mask) {
          std::uint64_t held = slot[s].load(std::memory_order_relaxed);
          if (held == 0 &&
              slot[s].compare_exchange_strong(held, entry, std::memory_order_relaxed))
            break;
          const std::size_t other = static_cast<std::uint32_t>(held) - 1;
          if ((held >> 32) == (key[i] >> 32) && same_positions(mesh, face, other)) {
            mine.push_back({s, static_cast<std::uint32_t>(face)});
            break;
          }
        }
      }
    }
    if (mine.empty()) return;
    std::lock_guard<std::mutex> hold(joins_lock);
    joins.insert(joins.end(), mine.begin(), mine.end());
  });
  if (joins.empty()) return out;  // the common case: no two faces at the same positions

  // The groups: every face that joined a slot, and the face that holds it. Few for most
  // meshes; half the faces for a double-sided one, where the cast that follows costs far more.
  const std::size_t joined = joins.size();
  for (std::size_t i = 0; i < joined; ++i) {
    const std::size_t s = joins[i].slot;
    joins.push_back({s, static_cast<std::uint32_t>(slot[s].load(std::memory_order_relaxed)) - 1});
  }
  auto order = [](const Join& a, const Join& b) {
    return std::tie(a.slot, a.face) < std::tie(b.slot, b.face);
  };
  auto equal = [](const Join& a, const Join& b) { return a.slot == b.slot && a.face == b.face; };
  std::sort(joins.begin(), joins.end(), order);
  joins.erase(std::unique(joins.begin(), joins.end(), equal), joins.end());
  std::vector<std::tuple<std::uint32_t, std::uint32_t, std::uint8_t>> found;
  for (std::size_t i = 0; i < joins.size();) {
    const std::uint32_t lowest = joins[i].face;
    std::size_t j = i + 1;
    for (; j < joins.size() && joins[j].slot == joins[i].slot; ++j) {
      const std::uint32_t face = joins[j].face;
      const int c0 = corner_at(mesh, face, 0, lowest), c1 = corner_at(mesh, face, 1, lowest);
      if (c1 == (c0 + 2) % 3)  // its next corner is the twin's previous: opposite windings
        found.emplace_back(face, lowest, static_cast<std::uint8_t>(c0));
    }
    i = j;
  }
  std::sort(found.begin(), found.end());
  for (const auto& [face, twin, corner] : found) {
    out.dropped.push_back(face);
    out.twin.push_back(twin);
    out.corner.push_back(corner);
  }
  return out;
}

}  // namespace sdf
