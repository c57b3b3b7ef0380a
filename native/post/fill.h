// SPDX-License-Identifier: GPL-3.0-or-later
// Stage 5a: points where no ray was kept take a value from their mesh neighbours.
#pragma once

#include <cstdint>

#include "mesh/mesh.h"
#include "prepare/sampling.h"

namespace sdf {

enum class FillResult { NothingToFill, Filled, NoValueAnywhere };

// Points with valid_rays == 0 get, layer by layer outward from the points that have a value
// (a breadth-first search), the mean of their neighbours that already have one. Neighbours:
// faces that share a vertex (faces), or vertices that share an edge (vertices). Points in a
// part of the mesh where no point has a value take the median of all values. When no point of
// the mesh has a value, every point gets 0 and the result says so (the caller warns).
FillResult fill_missing(const Mesh& mesh, PointKind kind, float* raw,
                        const std::int32_t* valid_rays);

}  // namespace sdf
