// SPDX-License-Identifier: GPL-3.0-or-later
// Stage timings as the Python API reports them: a dict of stage -> seconds, in stage order.
#pragma once

#include <pybind11/pybind11.h>

#include "util/stopwatch.h"

namespace sdf {

inline pybind11::dict timings_dict(const StageTimings& times) {
  pybind11::dict out;
  for (const auto& [stage, seconds] : times) out[pybind11::str(stage)] = seconds;
  return out;
}

}  // namespace sdf
