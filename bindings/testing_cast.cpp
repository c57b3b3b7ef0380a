// SPDX-License-Identifier: GPL-3.0-or-later
// The cast stage alone (sdf::compute), with its beside-cast hook, for the tests and
// benchmarks (shape_diameter._testing.compute): shape_diameter.compute() runs the whole call
// (field.cpp).
#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <memory>
#include <string>
#include <utility>

#include "arrays.h"
#include "cast_points.h"
#include "options.h"
#include "pipeline/sdf.h"
#include "progress.h"
#include "timings.h"

namespace py = pybind11;

namespace {

using sdf::Doubles;
using sdf::fill_name;
using sdf::Int64s;
using sdf::parse_accel;
using sdf::parse_bvh_quality;
using sdf::parse_orientation;
using sdf::parse_points;
using sdf::parse_sampling;
using sdf::to_array;
using sdf::to_mesh;

py::dict compute(const Doubles& vertices, const Int64s& triangles, int rays, double cone_angle,
                 const std::string& sampling, std::uint32_t seed, const std::string& points,
                 unsigned threads, const py::object& progress, const std::string& engine,
                 const std::string& accel, int octree_max_depth, int octree_leaf_size,
                 const std::string& orientation, const std::string& bvh_quality,
                 const py::object& beside_cast, bool find_twins) {
  sdf::Options options;
  options.rays = rays;
  options.cone_angle = cone_angle;
  options.sampling = parse_sampling(sampling);
  options.seed = seed;
  options.points = parse_points(points);
  options.threads = threads;
  options.engine = engine;
  options.accel = parse_accel(accel);
  options.octree.max_depth = octree_max_depth;
  options.octree.leaf_size = octree_leaf_size;
  options.orientation = parse_orientation(orientation);
  options.bvh_quality = parse_bvh_quality(bvh_quality);
  options.find_twins = find_twins;

  const sdf::ProgressFn report = sdf::python_progress(progress);
  // Also on the calling thread, taking the GIL for its Python code; it gets the cast's points
  // (sdf::CastPoints) for the length of the call.
  sdf::BesideCast beside;
  if (!beside_cast.is_none()) {
    beside = [&beside_cast](const sdf::SamplePoints& points) {
      py::gil_scoped_acquire gil;
      auto lent = std::make_shared<sdf::CastPoints>(sdf::CastPoints{&points});
      struct Return {
        sdf::CastPoints& lent;
        ~Return() { lent.points = nullptr; }
      } give_back{*lent};
      beside_cast(lent);
    };
  }
  sdf::Output out;
  {
    sdf::Mesh mesh = to_mesh(vertices, triangles, threads);
    py::gil_scoped_release release;
    out = sdf::compute(std::move(mesh), options, report, beside);  // moved: no copy of a large mesh
  }
  py::dict result;
  result["raw"] = py::array_t<float>(out.raw.size(), out.raw.data());
  result["valid_rays"] = py::array_t<std::int32_t>(out.valid_rays.size(), out.valid_rays.data());
  result["timings"] = sdf::timings_dict(out.timings);
  result["fill"] = fill_name(out.fill);
  result["engine"] = out.engine;
  result["device_bytes"] = out.device_bytes;
  result["near_cutoff"] = out.near_cutoff;
  result["flipped_faces"] = out.orientation.flipped_faces;
  result["parts"] = out.orientation.parts;
  // Which faces were reversed (None when none was): what runs on the caller's arrays after
  // the cast and depends on the winding (projected smoothing) reverses them too.
  if (out.orientation.reversed.empty()) {
    result["reversed"] = py::none();
  } else {
    py::array_t<bool> reversed(static_cast<py::ssize_t>(out.orientation.reversed.size()));
    std::copy(out.orientation.reversed.begin(), out.orientation.reversed.end(),
              reversed.mutable_data());
    result["reversed"] = reversed;
  }
  // Faces with a reversed twin (the computation stopped on finding them): (dropped, twin,
  // corner) as mesh_twins.h describes them; None when there are none.
  if (out.twins.empty()) {
    result["twins"] = py::none();
  } else {
    result["twins"] = py::make_tuple(to_array(out.twins.dropped), to_array(out.twins.twin),
                                     to_array(out.twins.corner));
  }
  return result;
}

}  // namespace

void bind_cast(py::module_& m) {
  m.def("compute", &compute, py::arg("vertices"), py::arg("triangles"), py::arg("rays"),
        py::arg("cone_angle"), py::arg("sampling"), py::arg("seed"), py::arg("points"),
        py::arg("threads"), py::arg("progress"), py::arg("engine") = "cpu",
        py::arg("accel") = "bvh", py::arg("octree_max_depth") = 10, py::arg("octree_leaf_size") = 8,
        py::arg("orientation") = "auto", py::arg("bvh_quality") = "auto",
        py::arg("beside_cast") = py::none(), py::arg("find_twins") = true);
}
