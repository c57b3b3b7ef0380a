// SPDX-License-Identifier: GPL-3.0-or-later
// The manifold-edge adjacency orient() propagates windings over (orientation.h, step 1).
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "mesh/mesh.h"
#include "util/concurrent_parity_union_find.h"

namespace sdf {

constexpr std::uint32_t kNoNeighbour = 0xffffffffu;

// Per edge slot 3 f + k (the edge from corner k to corner k + 1 of face f).
struct EdgeNeighbours {
  // The face across the edge when exactly one other face uses it (counting a face once per
  // time it uses the edge, so a face that uses it twice makes it non-manifold for the others);
  // kNoNeighbour otherwise, and for an edge whose two ends are the same vertex.
  std::vector<std::uint32_t> face;
  // 1 when that face runs the edge the same way (a -> b in both): the two disagree.
  std::vector<char> same;
};

// The mesh's edge uses (each face's three edges), grouped by edge once; the passes below read
// them. Linear time and parallel over `threads` (0 = every core); no result depends on the
// thread count. same_place, when given, holds per vertex one vertex at exactly its position
// (weld_exact, orientation_parts.h): edges are then told apart by their ends' positions, so
// that faces on either side of an unwelded seam (a CAD export's sides, a UV seam's split
// vertices, a triangle soup) are neighbours too.
class EdgeUses {
 public:
  EdgeUses(const Mesh& mesh, unsigned threads, const std::uint32_t* same_place = nullptr);
  ~EdgeUses();
  EdgeUses(const EdgeUses&) = delete;
  EdgeUses& operator=(const EdgeUses&) = delete;

  // Some manifold edge runs the same way in its two faces. When none does, every patch
  // already agrees and orient() needs no propagation (the common case: a consistently wound
  // mesh), so nothing else is made.
  bool any_same() const { return any_same_; }

  // The adjacency as per-slot lists (the serial walk's input).
  EdgeNeighbours neighbours(unsigned threads) const;

  // Joins in `sets` the two faces of every edge that exactly two faces use once each, their
  // bits differing where the edge runs the same way in both: the patches, without lists.
  // False (`sets` then partly joined) where the lists would not be mutual (a face using an
  // edge twice lists the face across it, which lists nothing back) or a patch cannot be
  // oriented (an odd cycle, a Moebius strip): only the serial walk's order defines those.
  bool join_patches(ConcurrentParityUnionFind& sets, unsigned threads) const;

 private:
  struct Buckets;
  std::unique_ptr<Buckets> buckets_;
  std::size_t faces_ = 0;
  bool any_same_ = false;
};

}  // namespace sdf
