// SPDX-License-Identifier: GPL-3.0-or-later
// compute()'s whole call (pipeline/field.h) and smooth()'s (pipeline/smoothing_step.h) for
// the Python layer, which has checked every argument: the options come as the dicts it
// resolved; this file converts them and the arrays, and releases the GIL around the work.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <string>
#include <utility>

#include "arrays.h"
#include "options.h"
#include "pipeline/fallback.h"
#include "pipeline/field.h"
#include "pipeline/smoothing_step.h"
#include "post/uv_plan.h"
#include "progress.h"
#include "timings.h"

namespace py = pybind11;

namespace {

using sdf::Doubles;
using sdf::Floats;
using sdf::Int64s;

template <class T>
T or_default(const py::dict& o, const char* key, T none) {
  return o[key].is_none() ? none : o[key].cast<T>();
}

// check_smoothing()'s options (every default filled in; None where the core chooses).
sdf::SmoothingOptions smoothing_options(const std::string& method, const py::dict& o) {
  sdf::SmoothingOptions s;
  if (method == "none") return s;
  if (method == "kring") {
    s.method = sdf::SmoothingMethod::Kring;
    s.kring.k = or_default(o, "k", -1);
    s.kring.sigma = or_default(o, "sigma", 0.0);
    s.kring.corner_angle = or_default(o, "corner_angle", 0.0);
    s.kring.weld_tolerance = or_default(o, "weld_tolerance", -1.0);
  } else if (method == "projected") {
    s.method = sdf::SmoothingMethod::Projected;
    s.projected.iterations = o["iterations"].cast<int>();
    s.projected.max_depth = o["max_depth"].cast<int>();
    s.projected.min_points = o["min_points"].cast<double>();
    s.projected.node_size_ratio = o["node_size_ratio"].cast<double>();
    s.projected.radius = o["radius"].cast<double>();
    const auto branch_on = o["branch_on"].cast<std::string>();
    if (branch_on != "mean" && branch_on != "min")
      throw std::invalid_argument("branch_on must be 'mean' or 'min', got '" + branch_on + "'");
    s.projected.branch_on = branch_on == "mean" ? sdf::ProjectedOptions::Branch::Mean
                                                : sdf::ProjectedOptions::Branch::Min;
  } else if (method == "bilateral") {
    s.method = sdf::SmoothingMethod::Bilateral;
    s.bilateral_window = or_default<std::size_t>(o, "window", 0);
  } else if (method == "texture") {
    s.method = sdf::SmoothingMethod::Texture;
    const auto size = o["texture_size"].cast<std::pair<int, int>>();
    s.texture.width = size.first;
    s.texture.height = size.second;
    s.texture.radius = o["radius"].cast<double>();
    s.texture.bilateral = o["bilateral"].cast<bool>();
    s.texture.range_sigma = o["range_sigma"].cast<double>();
    s.texture.margin = o["margin"].cast<int>();
    s.texture.weld_tolerance = or_default(o, "weld_tolerance", -1.0);
    s.return_image = o["return_image"].cast<bool>();
    // The islands and layout shape_diameter.uv_layout() found, when given.
    if (o.contains("uv_layout") && !o["uv_layout"].is_none())
      s.uv_plan = o["uv_layout"].cast<std::shared_ptr<sdf::UvPlan>>();
  } else {
    throw std::invalid_argument("unknown smoothing method '" + method + "'");
  }
  return s;
}

using CornerUvs = py::array_t<float, py::array::c_style | py::array::forcecast>;

// Texture smoothing's per-corner UVs, (m, 3, 2), or none (an empty array).
CornerUvs corner_uvs(const py::object& uvs, std::size_t faces) {
  if (uvs.is_none()) return CornerUvs();
  auto array = uvs.cast<CornerUvs>();
  if (array.ndim() != 3 || static_cast<std::size_t>(array.shape(0)) != faces ||
      array.shape(1) != 3 || array.shape(2) != 2)
    throw std::invalid_argument("uvs must have shape (m, 3, 2)");
  return array;
}

// A numpy array over `items`, which it keeps (no copy: copying a 4096^2 bake's images took
// 0.3 s after its last progress report, which a cancel waited for). Element types of one
// size: the mask's bytes (0 or 1) are numpy bools.
template <class To, class From>
py::array_t<To> adopted(std::vector<From>&& items, const std::vector<py::ssize_t>& shape) {
  static_assert(sizeof(To) == sizeof(From), "one element size");
  auto* owned = new std::vector<From>(std::move(items));
  py::capsule keep(owned, [](void* p) { delete static_cast<std::vector<From>*>(p); });
  return py::array_t<To>(shape, reinterpret_cast<const To*>(owned->data()), keep);
}

const float* data_or_null(const CornerUvs& uvs) { return uvs.size() ? uvs.data() : nullptr; }

sdf::Options cast_options(const py::dict& o) {
  sdf::Options options;
  options.rays = o["rays"].cast<int>();
  options.cone_angle = o["cone_angle"].cast<double>();
  options.sampling = sdf::parse_sampling(o["sampling"].cast<std::string>());
  options.seed = o["seed"].cast<std::uint32_t>();
  options.points = sdf::parse_points(o["points"].cast<std::string>());
  options.threads = o["threads"].cast<unsigned>();
  options.engine = o["engine"].cast<std::string>();
  options.accel = sdf::parse_accel(o["accel"].cast<std::string>());
  options.octree.max_depth = o["octree_depth"].cast<int>();
  options.octree.leaf_size = o["octree_leaf_size"].cast<int>();
  options.orientation = sdf::parse_orientation(o["orientation"].cast<std::string>());
  options.bvh_quality = sdf::parse_bvh_quality(o["bvh_quality"].cast<std::string>());
  return options;
}

py::object reversed_faces(const std::vector<std::uint8_t>& reversed) {
  if (reversed.empty()) return py::none();
  py::array_t<bool> out(static_cast<py::ssize_t>(reversed.size()));
  std::copy(reversed.begin(), reversed.end(), out.mutable_data());
  return out;
}

// cast: compute()'s checked options by name (rays, cone_angle, sampling, seed, points,
// threads, engine, accel, octree_depth, octree_leaf_size, orientation, bvh_quality).
py::dict compute_field(const Doubles& vertices, const Int64s& triangles, const py::dict& cast,
                       bool fall_back_to_cpu, const std::string& smoothing,
                       const py::dict& smoothing_dict, const py::object& uvs,
                       const std::string& normalize, const py::object& progress) {
  const sdf::MeshArrays mesh = sdf::mesh_arrays(vertices, triangles);
  sdf::FieldOptions options;
  options.cast = cast_options(cast);
  options.fall_back_to_cpu = fall_back_to_cpu;
  options.smoothing = smoothing_options(smoothing, smoothing_dict);
  const CornerUvs corners = corner_uvs(uvs, mesh.triangle_count);
  options.uvs = data_or_null(corners);
  options.normalize = sdf::parse_normalization(normalize);
  const sdf::ProgressFn report = sdf::python_progress(progress);
  sdf::Field field;
  {
    py::gil_scoped_release release;
    field = sdf::compute_field(mesh, options, report);
  }
  const sdf::Output& out = field.cast;
  py::dict result;
  result["raw"] = sdf::to_array(out.raw);
  result["values"] = sdf::to_array(field.values);
  result["normalized"] = sdf::to_array(field.normalized);
  result["valid_rays"] = sdf::to_array(out.valid_rays);
  result["timings"] = sdf::timings_dict(out.timings);
  result["fill"] = sdf::fill_name(out.fill);
  result["engine"] = out.engine;
  result["fallback"] = field.fallback;
  result["device_bytes"] = out.device_bytes;
  result["near_cutoff"] = out.near_cutoff;
  result["flipped_faces"] = out.orientation.flipped_faces;
  result["reversed"] = reversed_faces(out.orientation.reversed);
  result["twin_faces"] = field.twin_faces;
  result["smoothed_faces"] = field.smoothed_faces;
  result["faces_outside"] = field.texture_faces_outside;
  result["faces_overlapping"] = field.texture_faces_overlapping;
  result["overlaps_unparted"] = field.texture_overlaps_unparted;
  result["pages"] = field.texture_pages;
  result["kept_off_device"] = field.texture_kept_off_device;
  return result;
}

// smooth()'s work on one field: the mesh as given (its winding trusted), on `engine`; with
// fall_back_to_cpu, a device's failure runs on the CPU and 'failure' says why.
py::dict smooth_field(const Doubles& vertices, const Int64s& triangles, const Floats& values,
                      const std::string& points, const std::string& method,
                      const py::dict& options_dict, const py::object& uvs, unsigned threads,
                      const py::object& progress, const std::string& engine,
                      bool fall_back_to_cpu) {
  const sdf::MeshArrays arrays = sdf::mesh_arrays(vertices, triangles);
  sdf::SmoothingOptions options = smoothing_options(method, options_dict);
  options.threads = threads;
  const sdf::PointKind kind = sdf::parse_points(points);
  const std::size_t n = kind == sdf::PointKind::Faces ? arrays.triangle_count : arrays.vertex_count;
  if (values.ndim() != 1 || static_cast<std::size_t>(values.shape(0)) != n)
    throw std::invalid_argument("values must have one entry per point (" + std::to_string(n) + ")");
  const CornerUvs corners = corner_uvs(uvs, arrays.triangle_count);
  const sdf::ProgressFn report = sdf::python_progress(progress);
  sdf::Smoothed done;
  std::string on = engine, failure;
  {
    py::gil_scoped_release release;
    const sdf::Mesh mesh = sdf::make_mesh(arrays, threads);
    const sdf::SmoothingMesh m{&mesh,
                               &mesh,
                               data_or_null(corners),
                               arrays.triangles,
                               arrays.triangle_count,
                               arrays.vertex_count};
    done = sdf::with_fallback(on, fall_back_to_cpu, failure, [&](const std::string& e) {
      return sdf::smooth_values(m, kind, values.data(), options, e, nullptr, report);
    });
  }
  py::dict result;
  result["values"] = sdf::to_array(done.values);
  result["timings"] = sdf::timings_dict(done.timings);
  result["failure"] = failure;
  result["faces_outside"] = done.faces_outside;
  result["faces_spanning"] = done.faces_spanning;
  result["faces_overlapping"] = done.faces_overlapping;
  result["overlaps_unparted"] = done.overlaps_unparted;
  result["pages"] = done.pages;
  result["kept_off_device"] = done.kept_off_device;
  if (options.return_image) {
    // Per UDIM tile: its number -> (image, mask), rows from v = 0.
    py::dict tiles;
    for (sdf::TextureTile& tile : done.tiles) {
      const std::vector<py::ssize_t> shape{tile.height, tile.width};
      tiles[py::int_(tile.tile)] = py::make_tuple(adopted<float>(std::move(tile.image), shape),
                                                  adopted<bool>(std::move(tile.mask), shape));
    }
    result["tiles"] = tiles;
  }
  return result;
}

}  // namespace

void bind_field(py::module_& m) {
  m.def("compute_field", &compute_field, py::arg("vertices"), py::arg("triangles"), py::arg("cast"),
        py::arg("fall_back_to_cpu"), py::arg("smoothing"), py::arg("smoothing_options"),
        py::arg("uvs"), py::arg("normalize"), py::arg("progress"));
  m.def("smooth_field", &smooth_field, py::arg("vertices"), py::arg("triangles"), py::arg("values"),
        py::arg("points"), py::arg("method"), py::arg("options"), py::arg("uvs"),
        py::arg("threads"), py::arg("progress"), py::arg("engine"), py::arg("fall_back_to_cpu"));
}
