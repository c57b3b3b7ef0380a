// SPDX-License-Identifier: GPL-3.0-or-later
// The cast's points (sampling.h), lent to compute()'s beside-cast callback in Python for the
// length of that call: module.cpp makes one around the call and empties it after, so a
// Python object kept past the call refers to nothing (smoothing.cpp reads it). Only the
// callback's own thread may use it: another thread still reading it when the callback returns
// would read freed points (compute()'s callbacks are internal; nothing does that).
#pragma once

#include "prepare/sampling.h"

namespace sdf {

struct CastPoints {
  const SamplePoints* points = nullptr;  // null once the call has returned
};

}  // namespace sdf
