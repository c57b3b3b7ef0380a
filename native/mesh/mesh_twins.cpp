// SPDX-License-Identifier: GPL-3.0-or-later
#include "mesh/mesh_twins.h"

#include <algorithm>
#include <atomic>
#include <cstring>
#include <memory>
#include <mutex>

#include "util/concurrent_union_find.h"
#include "util/parallel.h"
#include "util/parallel_scan.h"
#include "util/prefetch.h"
#include "util/uninitialized_vector.h"

namespace sdf {

namespace {

constexpr std::size_t kGrain = 1 << 14;
// How far ahead of its use a read is asked for (faces): a subdivided mesh's corners, and the
// table, are read out of order.
constexpr std::size_t kAhead = 16;

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

// The faces as the caller wound them: corner k of a face the orientation reversed is the
// mesh's corner (3 - k) % 3 (orientation.cpp swaps corners 1 and 2).
struct CallerCorners {
  const Mesh& mesh;
  const std::uint8_t* reversed;  // per face, or null

  glm::vec3 position(std::size_t face, int k) const {
    const int stored = reversed && reversed[face] ? (3 - k) % 3 : k;
    return mesh.vertices[mesh.triangles[face][stored]];
  }

  // The corner of face `other` at the position of corner k of `face`, or -1.
  int corner_at(std::size_t face, int k, std::size_t other) const {
    const glm::vec3 p = position(face, k);
    for (int j = 0; j < 3; ++j)
      if (position(other, j) == p) return j;  // == : -0 equals +0
    return -1;
  }

  // Two faces of three distinct positions each: the same positions when each corner finds one.
  bool same_positions(std::size_t face, std::size_t other) const {
    return corner_at(face, 0, other) >= 0 && corner_at(face, 1, other) >= 0 &&
           corner_at(face, 2, other) >= 0;
  }
};

constexpr std::uint32_t kNone = 0xffffffffu;

// Keeps the twins (twin_of: per face, its twin or kNone) whose face lies in a doubled part: a
// set of faces joined by shared vertices, every one of which is `paired` (at positions where
// faces of both windings lie). A double-sided mesh is such parts (its back a part of its own,
// or both sides one part on shared vertices); two solids that meet at a wall are not (each has
// faces away from the wall): each wall face measures its own solid and keeps its own value (a
// review found the slab's 0.25 given to the cube's wall). Runs only where twins were found.
void keep_doubled_parts(const Mesh& mesh, const UninitializedVector<std::uint8_t>& paired,
                        UninitializedVector<std::uint32_t>& twin_of, unsigned threads) {
  const std::size_t n = mesh.triangles.size();
  ConcurrentUnionFind sets(mesh.vertices.size(), threads);
  parallel_for(n, kGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t f = begin; f < end; ++f) {
      const glm::uvec3 t = mesh.triangles[f];
      sets.unite(t.x, t.y);
      sets.unite(t.x, t.z);
    }
  });
  // A part is doubled until one of its faces with area has no twin (one without area casts
  // nothing and is never hit: a double-sided sphere with one zero-area face among its
  // faces was cast with both sides, values up to 19% off).
  std::unique_ptr<std::atomic<std::uint8_t>[]> single(
      new std::atomic<std::uint8_t>[mesh.vertices.size()]());
  parallel_for(n, kGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t f = begin; f < end; ++f)
      if (!paired[f] && face_area_normal(mesh, f) != glm::vec3(0.0f))
        single[sets.find(mesh.triangles[f].x)].store(1, std::memory_order_relaxed);
  });
  parallel_for(n, kGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t f = begin; f < end; ++f)
      if (twin_of[f] != kNone &&
          single[sets.find(mesh.triangles[f].x)].load(std::memory_order_relaxed))
        twin_of[f] = kNone;
  });
}

void lower_to(std::atomic<std::uint32_t>& at, std::uint32_t value) {
  std::uint32_t held = at.load(std::memory_order_relaxed);
  while (value < held && !at.compare_exchange_weak(held, value, std::memory_order_relaxed)) {
  }
}

// A face that found its positions' slot held by another face at the same positions.
struct Join {
  std::size_t slot;
  std::uint32_t face;
};

}  // namespace

ReversedTwins reversed_twins(const Mesh& mesh, unsigned threads, const std::uint8_t* reversed) {
  ReversedTwins out;
  const CallerCorners corners{mesh, reversed};
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
    auto insert = [&](std::size_t face, std::uint64_t key) {
      const std::uint64_t entry = (key & 0xffffffff00000000ull) | (face + 1);
      for (std::size_t s = key & mask;; s = (s + 1) & mask) {
        std::uint64_t held = slot[s].load(std::memory_order_relaxed);
        if (held == 0 && slot[s].compare_exchange_strong(held, entry, std::memory_order_relaxed))
          return;
        const std::size_t other = static_cast<std::uint32_t>(held) - 1;
        if ((held >> 32) == (key >> 32) && corners.same_positions(face, other)) {
          mine.push_back({s, static_cast<std::uint32_t>(face)});
          return;
        }
      }
    };
    // A pipeline over the faces: face f's corners' hashes are asked for, face f - kAhead's key
    // is made and its slot asked for, face f - 2 kAhead is inserted. Both reads are misses on
    // a large mesh; batches (ask for 16, then use them) left the table's miss exposed (measured
    // 1.6x slower on one thread).
    std::uint64_t key[kAhead];  // face g's at g % kAhead, from its making to its insertion
    for (std::size_t f = begin; f < end + 2 * kAhead; ++f) {
      if (f >= begin + 2 * kAhead && f - 2 * kAhead < end) {
        const std::size_t h = f - 2 * kAhead;
        if (key[h % kAhead] != 0) insert(h, key[h % kAhead]);
      }
      if (f >= begin + kAhead && f - kAhead < end) {
        const std::size_t g = f - kAhead;  // takes the place h left
        key[g % kAhead] = key_of(g);
        prefetch(&slot[key[g % kAhead] & mask]);
      }
      if (f < end)
        for (int k = 0; k < 3; ++k) prefetch(&hash[mesh.triangles[f][k]]);
    }
    if (mine.empty()) return;
    std::lock_guard<std::mutex> hold(joins_lock);
    joins.insert(joins.end(), mine.begin(), mine.end());
  });
  if (joins.empty()) return out;  // the common case: no two faces at the same positions

  // The groups, in parallel and without a sort: few faces for most meshes, but half the faces
  // of a double-sided one (a sort of them took 0.8 s at 2.4M faces). A face is in at most one
  // join, and a slot's holder is in none: per slot, the lowest face of its group (joiners and
  // holder), and its first joiner, which speaks for the holder.
  auto holder = [&](std::size_t s) {
    return static_cast<std::uint32_t>(slot[s].load(std::memory_order_relaxed)) - 1;
  };
  UninitializedVector<std::atomic<std::uint32_t>> lowest(size), first_join(size);
  std::unique_ptr<std::atomic<std::uint8_t>[]> mixed(new std::atomic<std::uint8_t>[size]());
  const std::size_t joined = joins.size();
  parallel_for(joined, kGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      lowest[joins[i].slot].store(kNone, std::memory_order_relaxed);
      first_join[joins[i].slot].store(kNone, std::memory_order_relaxed);
    }
  });
  parallel_for(joined, kGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      const std::size_t s = joins[i].slot;
      lower_to(lowest[s], joins[i].face);
      lower_to(lowest[s], holder(s));
      lower_to(first_join[s], joins[i].face);
    }
  });
  UninitializedVector<std::uint32_t> twin_of(n);
  UninitializedVector<std::uint8_t> corner_of(n), paired(n);
  parallel_for(n, kGrain, threads, [&](std::size_t begin, std::size_t end) {
    std::fill(twin_of.begin() + begin, twin_of.begin() + end, kNone);
    std::fill(paired.begin() + begin, paired.begin() + end, 0);
  });
  // Each member against its group's lowest face: wound the other way, it is that face's twin.
  auto members = [&](std::size_t i, auto&& visit) {
    const std::size_t s = joins[i].slot;
    visit(s, joins[i].face);
    if (joins[i].face == first_join[s].load(std::memory_order_relaxed)) visit(s, holder(s));
  };
  parallel_for(joined, kGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i)
      members(i, [&](std::size_t s, std::uint32_t face) {
        const std::uint32_t low = lowest[s].load(std::memory_order_relaxed);
        if (face == low) return;
        const int c0 = corners.corner_at(face, 0, low), c1 = corners.corner_at(face, 1, low);
        if (c1 != (c0 + 2) % 3) return;  // its next corner is not the twin's previous
        twin_of[face] = low;
        corner_of[face] = static_cast<std::uint8_t>(c0);
        mixed[s].store(1, std::memory_order_relaxed);
      });
  });
  parallel_for(joined, kGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i)
      members(i, [&](std::size_t s, std::uint32_t face) {
        paired[face] = mixed[s].load(std::memory_order_relaxed);
      });
  });
  keep_doubled_parts(mesh, paired, twin_of, threads);
  const std::vector<std::uint32_t> dropped =
      indices_where(n, threads, [&](std::size_t f) { return twin_of[f] != kNone; });
  out.dropped.assign(dropped.begin(), dropped.end());
  out.twin.resize(dropped.size());
  out.corner.resize(dropped.size());
  parallel_for(dropped.size(), kGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      out.twin[i] = twin_of[dropped[i]];
      out.corner[i] = corner_of[dropped[i]];
    }
  });
  return out;
}

}  // namespace sdf
