// SPDX-License-Identifier: GPL-3.0-or-later
// Which part lies inside which (orient(Auto), step 3 in orientation.h): the inner wall of a
// hollow solid is a part of its own, wound inward on purpose, and must not be judged alone.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "mesh/mesh.h"
#include "prepare/orientation_parts.h"

namespace sdf {

// Per part, the innermost other part that encloses it, or kNoPart. `volume` is each part's
// signed volume, `encloser[p]` whether part p can enclose (its volume clearly non-zero); it
// also needs 4 faces or more. P lies inside Q when Q encloses more volume than P (or as much,
// with a lower number), Q's box holds P's, and each of three rays from the centroid of P's
// first face crosses Q's faces an odd number of times (any ray from a point inside a closed
// surface crosses it an odd number of times; rays that disagree, as from inside an open
// bowl, say no). Innermost: the encloser of least volume.
// Each encloser's faces are read once for all the parts that may lie in it. With more than
// 2^25 grid filings of enclosers' boxes (thousands of large closed parts around each other)
// the step gives up and returns no nesting (parts are then judged alone, as before this step
// existed). Parallel over `threads`; the result does not depend on the thread count.
std::vector<std::uint32_t> enclosing_parts(const Mesh& mesh, const Parts& parts,
                                           const std::vector<PartBox>& boxes,
                                           const std::vector<double>& volume,
                                           const std::vector<char>& encloser, unsigned threads);

}  // namespace sdf
