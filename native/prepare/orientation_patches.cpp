// SPDX-License-Identifier: GPL-3.0-or-later
#include "prepare/orientation_patches.h"

#include <algorithm>
#include <cstdint>
#include <utility>

#include "util/concurrent_parity_union_find.h"
#include "util/parallel.h"
#include "util/prefetch.h"
#include "util/uninitialized_vector.h"

namespace sdf {

namespace {

constexpr std::size_t kGrain = 1 << 14;

}  // namespace

std::vector<char> patch_flips_serial(const Mesh& mesh, const EdgeNeighbours& edges) {
  const std::size_t n = mesh.triangles.size();
  std::vector<char> flip(n, 0), seen(n, 0);
  std::vector<std::uint32_t> patch, queue;
  for (std::uint32_t seed = 0; seed < n; ++seed) {
    if (seen[seed]) continue;
    patch.clear();
    queue.assign(1, seed);
    seen[seed] = 1;
    while (!queue.empty()) {
      const std::uint32_t f = queue.back();
      queue.pop_back();
      patch.push_back(f);
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t g = edges.face[3 * std::size_t{f} + k];
        if (g == kNoNeighbour || seen[g])
          continue;  // a non-orientable patch keeps its first choice
        seen[g] = 1;
        flip[g] = flip[f] ^ edges.same[3 * std::size_t{f} + k];
        queue.push_back(g);
      }
    }
    bool any_reversed = false;
    for (std::uint32_t f : patch) any_reversed |= flip[f] != 0;
    if (!any_reversed) continue;  // the common case: the patch already agrees
    // Keep the winding that most of the patch's area already has; summed in face order, the
    // order the parallel version sums in.
    std::sort(patch.begin(), patch.end());
    double kept = 0.0, reversed = 0.0;
    for (std::uint32_t f : patch)
      (flip[f] ? reversed : kept) += glm::length(face_area_normal(mesh, f));
    if (reversed > kept)
      for (std::uint32_t f : patch) flip[f] ^= 1;
  }
  return flip;
}

std::optional<std::vector<char>> patch_flips_parallel(const Mesh& mesh, const EdgeUses& edges,
                                                      unsigned threads) {
  const std::size_t n = mesh.triangles.size();
  ConcurrentParityUnionFind sets(n, threads);
  if (!edges.join_patches(sets, threads)) return std::nullopt;

  // Per face: its set's root (the set's smallest face, where the serial walk starts it), its
  // bit relative to the root (its flip) and its area.
  std::vector<char> flip(n);
  UninitializedVector<std::uint32_t> root(n);
  UninitializedVector<float> area(n);
  parallel_for(n, kGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t f = begin; f < end; ++f) {
      prefetch_corners(mesh, f + kPrefetchFacesAhead);
      const ConcurrentParityUnionFind::Found found = sets.find(static_cast<std::uint32_t>(f));
      root[f] = found.root;
      flip[f] = static_cast<char>(found.parity);
      area[f] = glm::length(face_area_normal(mesh, f));
    }
  });
  // Per set, the area that keeps its winding and the area that reverses it, summed in face
  // order (serial: one sequential pass; most faces lie in few sets). A set whose faces all
  // keep theirs sums 0 reversed and is left alone, as the walk leaves it.
  struct Sums {
    double kept = 0.0, reversed = 0.0;
  };
  std::vector<Sums> sums;
  UninitializedVector<std::uint32_t> slot(n);  // per root, its set's entry in sums
  for (std::size_t f = 0; f < n; ++f) {
    const std::uint32_t r = root[f];
    if (r == f) {  // the root comes first in face order
      slot[r] = static_cast<std::uint32_t>(sums.size());
      sums.emplace_back();
    }
    Sums& s = sums[slot[r]];
    (flip[f] ? s.reversed : s.kept) += area[f];
  }
  parallel_for(n, kGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t f = begin; f < end; ++f) {
      const Sums& s = sums[slot[root[f]]];
      if (s.reversed > s.kept) flip[f] ^= 1;
    }
  });
  return flip;
}

std::vector<char> patch_flips(const Mesh& mesh, const EdgeUses& edges, unsigned threads) {
  std::optional<std::vector<char>> flip = patch_flips_parallel(mesh, edges, threads);
  return flip ? std::move(*flip) : patch_flips_serial(mesh, edges.neighbours(threads));
}

}  // namespace sdf
