// SPDX-License-Identifier: GPL-3.0-or-later
// The parts orient() turns outward one by one (orientation.h, step 2): faces joined through
// shared vertex positions, so that unwelded seams do not split a part.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "mesh/mesh.h"
#include "util/uninitialized_vector.h"

namespace sdf {

constexpr std::uint32_t kNoPart = 0xffffffffu;

struct Parts {
  UninitializedVector<std::uint32_t> part_of;  // per face; parts numbered by their first face
  std::size_t count = 0;
  // Per vertex, the vertex standing for its set; per such root, its part, or kNoPart for a
  // set no face uses. A vertex's part is part_of_root[root_of_vertex[v]]: it lies at the
  // position of some corner of that part's faces, or is used by none (kNoPart).
  UninitializedVector<std::uint32_t> root_of_vertex;
  std::vector<std::uint32_t> part_of_root;
};

// Per vertex, one vertex at exactly the same position (-0 and +0 alike), the same for all of
// them and its own (which one depends on thread timing; only the grouping is meaningful).
// Linear expected time, parallel over `threads` (0 = every core).
UninitializedVector<std::uint32_t> weld_exact(const Mesh& mesh, unsigned threads);

// Whether some vertex shares its position with another (weld_exact's `same_place` is not the
// identity).
bool any_shared_place(const UninitializedVector<std::uint32_t>& same_place, unsigned threads);

// Linear expected time, parallel over `threads` (0 = every core); the result does not depend
// on the thread count. same_place: weld_exact(mesh), when made already.
Parts find_parts(const Mesh& mesh, unsigned threads);
Parts find_parts(const Mesh& mesh, UninitializedVector<std::uint32_t> same_place, unsigned threads);

struct PartBox {
  glm::dvec3 lo{1e300}, hi{-1e300};
};

// Bounding box of each part's face corners, from the vertices (read in order, where the
// corners would be read scattered): the vertices of a part lie at its corners' positions.
// Min and max are exact, so the chunks' boxes merge to the same box in any order; with many
// parts (more than a box per part per chunk would hold cheaply) one serial pass does it.
std::vector<PartBox> part_boxes(const Mesh& mesh, const Parts& parts, unsigned threads);

}  // namespace sdf
