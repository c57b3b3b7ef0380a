// SPDX-License-Identifier: GPL-3.0-or-later
// A hint to start loading what a later step of a loop reads at a scattered address, so that a
// batch of such loads overlaps instead of waiting one after another (a no-op where the
// compiler has no such builtin).
#pragma once

namespace sdf {

inline void prefetch(const void* p) {
#if defined(__GNUC__) || defined(__clang__)
  __builtin_prefetch(p);
#else
  (void)p;
#endif
}

}  // namespace sdf
