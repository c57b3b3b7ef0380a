/* SPDX-License-Identifier: GPL-3.0-or-later */
/* Morton (z-order) codes' bit spreading, shared by the host (native/morton.h) and the
 * device-built tree's codes (sdf_lbvh_kernels.cl). */
#ifndef SDF_MORTON_H
#define SDF_MORTON_H

#include "sdf_compat.h"

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

SDF_KERNEL_END

#endif /* SDF_MORTON_H */
