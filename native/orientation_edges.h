// SPDX-License-Identifier: GPL-3.0-or-later
// The manifold-edge adjacency orient() propagates windings over (orientation.h, step 1).
#pragma once

#include <cstdint>
#include <vector>

#include "mesh.h"

namespace sdf {

constexpr std::uint32_t kNoNeighbour = 0xffffffffu;

// Per edge slot 3 f + k (the edge from corner k to corner k + 1 of face f). `face` and `same`
// are filled only when any_same is true or the caller asked for them (otherwise they are
// empty: nothing needs them).
struct EdgeNeighbours {
  // The face across the edge when exactly one other face uses it (counting a face once per
  // time it uses the edge, so a face that uses it twice makes it non-manifold for the others);
  // kNoNeighbour otherwise, and for an edge whose two ends are the same vertex.
  std::vector<std::uint32_t> face;
  // 1 when that face runs the edge the same way (a -> b in both): the two disagree.
  std::vector<char> same;
  // Some neighbour runs its edge the same way. When none does, every patch already agrees
  // and orient() needs no propagation (the common case: a consistently wound mesh).
  bool any_same = false;
};

// Linear time and parallel over `threads` (0 = every core); the result does not depend on
// the thread count.
EdgeNeighbours manifold_edge_neighbours(const Mesh& mesh, unsigned threads,
                                        bool always_list = false);

}  // namespace sdf
