// SPDX-License-Identifier: GPL-3.0-or-later
// shape_diameter.uv_layout()'s call (post/uv_plan.h): a UV map's islands and layout, found
// once, held by an opaque UvPlan that compute_field and smooth_field take back (as the
// texture options' "uv_layout") instead of finding them again.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <memory>
#include <vector>

#include "arrays.h"
#include "post/uv_plan.h"

namespace py = pybind11;

namespace {

using CornerUvs = py::array_t<float, py::array::c_style | py::array::forcecast>;

std::shared_ptr<sdf::UvPlan> uv_layout(const sdf::Doubles& vertices, const sdf::Int64s& triangles,
                                       const CornerUvs& uvs, double weld_tolerance,
                                       bool need_merged, unsigned threads) {
  const sdf::MeshArrays arrays = sdf::mesh_arrays(vertices, triangles);
  if (uvs.ndim() != 3 || static_cast<std::size_t>(uvs.shape(0)) != arrays.triangle_count ||
      uvs.shape(1) != 3 || uvs.shape(2) != 2)
    throw std::invalid_argument("uvs must have shape (m, 3, 2)");
  py::gil_scoped_release release;
  const sdf::Mesh mesh = sdf::make_mesh(arrays, threads);
  return std::make_shared<sdf::UvPlan>(
      sdf::plan_uvs(mesh, uvs.data(), weld_tolerance, need_merged, threads));
}

// Whether the plan was found for a mesh of these counts and these UVs (its own weld tolerance
// and merging): its islands index that mesh's vertices and faces.
bool fits(const sdf::UvPlan& plan, std::size_t vertex_count, const CornerUvs& uvs) {
  if (uvs.ndim() != 3 || uvs.shape(1) != 3 || uvs.shape(2) != 2) return false;
  const auto faces = static_cast<std::size_t>(uvs.shape(0));
  return sdf::plan_fits(plan, faces, vertex_count, uvs.data(), plan.islands.weld_tolerance, false);
}

std::vector<int> tiles(const sdf::UvPlan& plan) {
  std::vector<int> out;
  for (const sdf::UvPage& page : plan.layout.pages)
    if (out.empty() || out.back() != page.tile) out.push_back(page.tile);
  return out;
}

}  // namespace

void bind_uv_plan(py::module_& m) {
  py::class_<sdf::UvPlan, std::shared_ptr<sdf::UvPlan>>(m, "UvPlan")
      .def_property_readonly("face_count", [](const sdf::UvPlan& p) { return p.face_count; })
      .def_property_readonly("islands", [](const sdf::UvPlan& p) { return p.islands.count; })
      .def_property_readonly("faces_outside",
                             [](const sdf::UvPlan& p) { return p.layout.faces_outside; })
      .def_property_readonly("faces_spanning",
                             [](const sdf::UvPlan& p) { return p.layout.faces_spanning; })
      .def_property_readonly("faces_overlapping",
                             [](const sdf::UvPlan& p) { return p.layout.faces_overlapping; })
      .def_property_readonly("overlaps_unparted",
                             [](const sdf::UvPlan& p) { return p.layout.overlaps_unparted; })
      .def_property_readonly("pages", [](const sdf::UvPlan& p) { return p.layout.pages.size(); })
      .def_property_readonly("tiles", &tiles)
      .def("fits", &fits, py::arg("vertex_count"), py::arg("uvs"))
      .def_property_readonly("weld_tolerance",
                             [](const sdf::UvPlan& p) { return p.islands.weld_tolerance; })
      .def_property_readonly("for_vertices",
                             [](const sdf::UvPlan& p) { return p.islands.need_merged; })
      .def_property_readonly("seconds", [](const sdf::UvPlan& p) { return p.seconds; });
  m.def("uv_layout", &uv_layout, py::arg("vertices"), py::arg("triangles"), py::arg("uvs"),
        py::arg("weld_tolerance"), py::arg("need_merged"), py::arg("threads"));
}
