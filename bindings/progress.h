// SPDX-License-Identifier: GPL-3.0-or-later
// The core's progress callback for a call from Python.
#pragma once

#include <pybind11/pybind11.h>

#include "util/parallel.h"

namespace sdf {

// Runs on the thread that called into the core (which holds no GIL while native code runs):
// Python's signal handlers first, so that Ctrl-C stops native work (it waited for the whole
// computation when no callback was given), then `progress` when given. An exception either
// raises travels out through the native code and back to Python.
inline ProgressFn python_progress(const pybind11::object& progress) {
  return [&progress](double fraction) {
    pybind11::gil_scoped_acquire gil;
    if (PyErr_CheckSignals() != 0) throw pybind11::error_already_set();
    if (!progress.is_none()) progress(fraction);
    return true;
  };
}

}  // namespace sdf
