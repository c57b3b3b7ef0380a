// SPDX-License-Identifier: GPL-3.0-or-later
// Stage 5c: map per-point values to [0, 1] for display (Result.normalized).
#pragma once

#include <cstddef>

namespace sdf {

enum class Normalization { Linear, Log };

// 'Linear': (x - min) / (max - min); 'Log': Shapira et al.'s log(4 x + 1) / log(5) of the
// linear value, spreading the thin end. Computed in double and rounded once to float; a
// constant field, or one holding a NaN, maps to 0 (as numpy's min and max would make it).
// T is float or double. Parallel over `threads` (0 = every core).
template <class T>
void normalize(const T* values, std::size_t n, Normalization method, unsigned threads, float* out);

}  // namespace sdf
