// SPDX-License-Identifier: GPL-3.0-or-later
// Double-sided meshes: faces present twice at the same three corner positions, once in each
// winding (game assets, "double-sided" exports, geometry duplicated and flipped). A ray that
// reaches such a wall meets two coincident faces, one facing it and one not, and which one it
// keeps is chance: values come out degraded (measured: up to 12.7x off), and
// the normals of shared vertices cancel. compute() finds such faces and stops (sdf.h); the
// caller casts the mesh without them and gives each its twin's values
// (pipeline/twins_step.h).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "mesh/mesh.h"

namespace sdf {

struct ReversedTwins {
  // Faces to leave out of the cast, increasing. twin[i]: the face whose values dropped[i]
  // takes, the lowest-index face at the same three positions (never left out itself).
  std::vector<std::uint32_t> dropped, twin;
  // corner[i]: the corner of twin[i] at the position of dropped[i]'s corner 0; the windings
  // being opposite, corner k of the dropped face lies at the twin's corner (corner[i] - k) mod 3.
  std::vector<std::uint8_t> corner;
  bool empty() const { return dropped.empty(); }
};

// Every face whose three corner positions (as the engines see them: the mesh's float
// positions, -0 equal to +0) are those of the lowest-index face there, wound the other way,
// and that face; only in doubled parts: sets of faces joined by shared vertices whose every
// face with area has such a twin (the back of a double-sided mesh, on vertices of its own or
// shared).
// Two solids meeting at a wall are no such part: each wall face keeps measuring its own
// solid. A face with two corners at one position has no twin; faces at the same positions
// wound the same way are left alone (they measure alike). Expected linear time: a
// lock-free hash table of faces keyed by their positions, on `threads` (0 = every core); the
// result does not depend on it. reversed: null, or per face 1 where the mesh holds the
// caller's face with corners 1 and 2 swapped (orientation.h's report): windings and corners
// are then told as the caller wound the faces.
ReversedTwins reversed_twins(const Mesh& mesh, unsigned threads = 0,
                             const std::uint8_t* reversed = nullptr);

}  // namespace sdf
