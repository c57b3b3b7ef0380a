// SPDX-License-Identifier: GPL-3.0-or-later
// The engines compute in 32-bit floats, and the triangle test's products reach a length
// cubed: on a mesh far wider than ~1e12 units they overflow, on one far narrower than ~1e-6
// units they underflow, and rays are lost (every value 0). compute() scales such a mesh by a
// power of two to a width of 1 to 2 units and its lengths back: exact, since every float
// operation scales with a power of two (short of overflow and underflow). Meshes 2^-20 to 2^30
// units wide (~1e-6 to ~1e9, where results were checked) are left exactly as they are.
#pragma once

#include <cstddef>

#include "mesh/mesh.h"
#include "prepare/sampling.h"

namespace sdf {

// The power of two to scale a mesh of this width by: 0 inside [2^-20, 2^30] (and for a width
// of 0), otherwise what brings the width into [1, 2).
int unit_scale_exponent(double max_extent);

// Vertices and max_extent times 2^exponent.
void scale_mesh(Mesh& mesh, int exponent, unsigned threads);

// Values times 2^exponent.
void scale_lengths(float* values, std::size_t count, int exponent);

// A copy whose origins are times 2^exponent (axes and tangents are unit vectors).
SamplePoints scaled_points(const SamplePoints& points, int exponent);

}  // namespace sdf
