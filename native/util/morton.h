// SPDX-License-Identifier: GPL-3.0-or-later
// Bit spreading for Morton codes (z-order): the point orders of sampling, the k-ring's
// batches, the projected points' octree and the Morton-split BVH nodes.
#pragma once

#include <cstdint>

#include "common/sdf_morton.h"

namespace sdf {

// The low 10 bits of x moved three apart (bit i to bit 3i): one axis of a 30-bit code.
inline std::uint32_t spread_bits_10(std::uint32_t x) { return kern::sdf_spread_bits_10(x); }

// The 30-bit code of cell c (each axis in [0, 1023]).
inline std::uint32_t morton_30(glm::uvec3 c) { return kern::sdf_morton_30(c.x, c.y, c.z); }

// The low 21 bits of x moved three apart: one axis of a 63-bit code.
inline std::uint64_t spread_bits_21(std::uint64_t x) {
  x &= 0x1fffffull;
  x = (x | x << 32) & 0x1f00000000ffffull;
  x = (x | x << 16) & 0x1f0000ff0000ffull;
  x = (x | x << 8) & 0x100f00f00f00f00full;
  x = (x | x << 4) & 0x10c30c30c30c30c3ull;
  x = (x | x << 2) & 0x1249249249249249ull;
  return x;
}

}  // namespace sdf
