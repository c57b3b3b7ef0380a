/* SPDX-License-Identifier: GPL-3.0-or-later */
/* Morton (z-order) codes, shared by the host (native/util/morton.h) and the device-built tree's
 * codes (sdf_lbvh_kernels.cl). */
#ifndef SDF_MORTON_H
#define SDF_MORTON_H

#include "common/sdf_compat.h"

SDF_KERNEL_BEGIN

/* The low 10 bits of x moved three apart (bit i to bit 3i): one axis of a 30-bit code. */
SDF_INLINE sdf_uint32 sdf_spread_bits_10(sdf_uint32 x) {
  x &= 0x3ffu;
  x = (x | x << 16) & 0x030000ffu;
  x = (x | x << 8) & 0x0300f00fu;
  x = (x | x << 4) & 0x030c30c3u;
  x = (x | x << 2) & 0x09249249u;
  return x;
}

/* The 30-bit Morton code of cell (x, y, z), each in [0, 1023]: x's bits at 3i, y's at 3i + 1,
 * z's at 3i + 2. */
SDF_INLINE sdf_uint32 sdf_morton_30(sdf_uint32 x, sdf_uint32 y, sdf_uint32 z) {
  return sdf_spread_bits_10(x) | (sdf_spread_bits_10(y) << 1) | (sdf_spread_bits_10(z) << 2);
}

SDF_KERNEL_END

#endif /* SDF_MORTON_H */
