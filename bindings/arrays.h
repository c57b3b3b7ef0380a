// SPDX-License-Identifier: GPL-3.0-or-later
// NumPy arrays as the core takes them: the argument types (C order, converted on the way in)
// and the mesh and vector conversions every binding uses.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <algorithm>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "mesh/mesh.h"

namespace sdf {

using Doubles = pybind11::array_t<double, pybind11::array::c_style | pybind11::array::forcecast>;
using Int64s =
    pybind11::array_t<std::int64_t, pybind11::array::c_style | pybind11::array::forcecast>;
using Floats = pybind11::array_t<float, pybind11::array::c_style | pybind11::array::forcecast>;

inline void require_rows_of_3(const pybind11::array& a, const char* what) {
  if (a.ndim() != 2 || a.shape(1) != 3)
    throw std::invalid_argument(std::string(what) + " must have shape (n, 3)");
}

// The caller's mesh arrays, their shapes checked.
inline MeshArrays mesh_arrays(const Doubles& vertices, const Int64s& triangles) {
  require_rows_of_3(vertices, "vertices");
  require_rows_of_3(triangles, "triangles");
  return {vertices.data(), static_cast<std::size_t>(vertices.shape(0)), triangles.data(),
          static_cast<std::size_t>(triangles.shape(0))};
}

inline Mesh to_mesh(const Doubles& vertices, const Int64s& triangles, unsigned threads = 0) {
  return make_mesh(mesh_arrays(vertices, triangles), threads);
}

// A vector as a new numpy array of its element type.
template <typename T>
pybind11::array_t<T> to_array(const std::vector<T>& items) {
  pybind11::array_t<T> out(static_cast<pybind11::ssize_t>(items.size()));
  std::copy(items.begin(), items.end(), out.mutable_data());
  return out;
}

}  // namespace sdf
