// SPDX-License-Identifier: GPL-3.0-or-later
// Which part lies inside which (orient(Auto), step 3 in orientation.h): the inner wall of a
// hollow solid is a part of its own, wound inward on purpose, and must not be judged alone.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "mesh.h"
#include "orientation_parts.h"

namespace sdf {

struct PartBox {
  glm::dvec3 lo{1e300}, hi{-1e300};
};

// Per part, the innermost other part that encloses it, or kNoPart. Only parts of at least 4
// faces whose signed volume is clearly non-zero (`encloser[p]`) can enclose. P lies inside Q
// when Q's box holds P's and each of three rays from a point of P crosses Q's faces an odd
// number of times (a closed surface is crossed an odd number of times by any ray from a
// point inside it; rays that disagree, as from inside an open bowl, or that graze an edge,
// say no). Innermost: the encloser with the smallest box. Parallel over `threads`; the result
// does not depend on the thread count.
std::vector<std::uint32_t> enclosing_parts(const Mesh& mesh, const Parts& parts,
                                           const std::vector<PartBox>& boxes,
                                           const std::vector<char>& encloser, unsigned threads);

}  // namespace sdf
