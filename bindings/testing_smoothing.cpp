// SPDX-License-Identifier: GPL-3.0-or-later
// Each smoothing method alone, and its preparation apart from its run, for the tests and
// benchmarks (shape_diameter._testing): shape_diameter.smooth() and compute() run them
// through the core's smoothing stage (field.cpp). Converts arrays, releases the GIL.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <memory>
#include <stdexcept>
#include <string>

#include "arrays.h"
#include "cast_points.h"
#include "mesh/mesh_weld.h"
#include "post/smoothing_kring.h"
#include "post/smoothing_projected.h"
#include "post/smoothing_texture.h"
#include "progress.h"
#include "timings.h"
#include "util/parallel.h"
#ifdef SDF_HAVE_OPENCL
#include "opencl/devices.h"
#include "opencl/opencl_projected.h"
#include "opencl/opencl_smoothing.h"
#endif

namespace py = pybind11;

namespace {

using sdf::Doubles;
using sdf::Floats;
using sdf::Int64s;

sdf::Mesh mesh_from(const Doubles& vertices, const Int64s& triangles, unsigned threads = 0) {
  return sdf::to_mesh(vertices, triangles, threads);
}

sdf::PointKind kind_from(const std::string& points) {
  if (points == "faces") return sdf::PointKind::Faces;
  if (points == "vertices") return sdf::PointKind::Vertices;
  throw std::invalid_argument("points must be 'faces' or 'vertices', got '" + points + "'");
}

// values must hold one float for each of n points.
const float* values_of(const Floats& values, std::size_t n) {
  if (values.ndim() != 1 || static_cast<std::size_t>(values.shape(0)) != n)
    throw std::invalid_argument("values must have one entry per point (" + std::to_string(n) + ")");
  return values.data();
}

// ... one per point of the kind.
const float* point_values(const sdf::Mesh& mesh, sdf::PointKind kind, const Floats& values) {
  return values_of(values,
                   kind == sdf::PointKind::Faces ? mesh.triangles.size() : mesh.vertices.size());
}

// A new array of n floats that fill(into) writes with the GIL released: the smoothing
// functions write their results in place, no copy of them is made.
template <class Fill>
py::array_t<float> filled_array(py::ssize_t n, const Fill& fill) {
  py::array_t<float> array(n);
  float* into = array.mutable_data();
  {
    py::gil_scoped_release release;
    fill(into);
  }
  return array;
}

// The OpenCL device an engine string names ("opencl", "opencl:N", "opencl:<name>"; the first
// of "opencl:all"), or null for "cpu". Throws std::invalid_argument naming the devices there
// are when nothing matches.
#ifdef SDF_HAVE_OPENCL
const sdf::cl::Device* device_for(const std::string& engine) {
  if (engine == "cpu") return nullptr;
  if (engine.compare(0, 6, "opencl") != 0)
    throw std::invalid_argument("engine must be 'cpu' or 'opencl...', got '" + engine + "'");
  return sdf::cl::select_devices(engine).front();
}
#else
const void* device_for(const std::string& engine) {
  if (engine == "cpu") return nullptr;
  throw std::invalid_argument("this build of shape_diameter has no OpenCL engine (engine '" +
                              engine + "')");
}
#endif

void require_corner_uvs(const Floats& uvs, const sdf::Mesh& mesh) {
  if (uvs.ndim() != 3 || static_cast<std::size_t>(uvs.shape(0)) != mesh.triangles.size() ||
      uvs.shape(1) != 3 || uvs.shape(2) != 2)
    throw std::invalid_argument("uvs must have shape (m, 3, 2)");
}

// Returns {"values": the smoothed values, "timings": seconds per stage}.
py::dict smooth_kring(const Doubles& vertices, const Int64s& triangles, const Floats& values,
                      const std::string& points, int k, double sigma, double corner_angle,
                      double weld_tolerance, unsigned threads, const py::object& progress) {
  sdf::StageTimings stages;
  sdf::StageClock clock(&stages);
  const sdf::Mesh mesh = mesh_from(vertices, triangles, threads);
  clock.lap("mesh");
  const sdf::PointKind kind = kind_from(points);
  const float* v = point_values(mesh, kind, values);
  sdf::KringOptions options;
  options.k = k;
  options.sigma = sigma;
  options.corner_angle = corner_angle;
  options.weld_tolerance = weld_tolerance;
  options.threads = threads;
  const sdf::ProgressFn report = sdf::python_progress(progress);
  const py::array_t<float> out = filled_array(values.shape(0), [&](float* into) {
    sdf::smooth_kring_into(mesh, kind, v, options, into, report, 0.0, 1.0, &stages);
  });
  py::dict result;
  result["values"] = out;
  result["timings"] = sdf::timings_dict(stages);
  return result;
}

sdf::ProjectedOptions projected_options(int iterations, int max_depth, double min_points,
                                        double node_size_ratio, const std::string& branch_on,
                                        unsigned threads) {
  sdf::ProjectedOptions options;
  options.iterations = iterations;
  options.max_depth = max_depth;
  options.min_points = min_points;
  options.node_size_ratio = node_size_ratio;
  if (branch_on == "mean")
    options.branch_on = sdf::ProjectedOptions::Branch::Mean;
  else if (branch_on == "min")
    options.branch_on = sdf::ProjectedOptions::Branch::Min;
  else
    throw std::invalid_argument("branch_on must be 'mean' or 'min', got '" + branch_on + "'");
  options.threads = threads;
  return options;
}

py::array_t<float> smooth_projected(const Doubles& vertices, const Int64s& triangles,
                                    const Floats& values, const std::string& points, int iterations,
                                    int max_depth, double min_points, double node_size_ratio,
                                    const std::string& branch_on, unsigned threads,
                                    const py::object& progress, const std::string& engine,
                                    const py::object& timings) {
  const sdf::Mesh mesh = mesh_from(vertices, triangles, threads);
  const sdf::PointKind kind = kind_from(points);
  const float* v = point_values(mesh, kind, values);
  const sdf::ProjectedOptions options =
      projected_options(iterations, max_depth, min_points, node_size_ratio, branch_on, threads);
  const auto* device = device_for(engine);
  (void)device;  // unused without OpenCL
  const sdf::ProgressFn report = sdf::python_progress(progress);
  sdf::StageTimings stages;
  py::array_t<float> out = filled_array(values.shape(0), [&](float* into) {
#ifdef SDF_HAVE_OPENCL
    if (device)
      return sdf::cl::smooth_projected_opencl(*device, mesh, kind, v, options, into, report,
                                              &stages);
#endif
    sdf::smooth_projected_into(mesh, kind, v, options, into, report, 0.0, 1.0, &stages);
  });
  if (!timings.is_none()) timings.attr("update")(sdf::timings_dict(stages));
  return out;
}

#ifdef SDF_HAVE_OPENCL
// compute(smoothing='projected') on an OpenCL engine, while the device casts: the cast's
// points' frames uploaded for smooth_projected_prepared. None where they were not (an OpenCL
// failure, or too large: smooth_projected then makes and uploads them itself).
py::object prepare_projected(const sdf::CastPoints& cast, unsigned threads,
                             const std::string& engine) {
  if (!cast.points)
    throw std::invalid_argument("the cast's points are lent only during compute()'s callback");
  const auto* device = device_for(engine);
  if (!device) throw std::invalid_argument("prepare_projected needs an OpenCL engine");
  std::shared_ptr<sdf::cl::PreparedProjected> prepared;
  {
    py::gil_scoped_release release;
    try {
      prepared = std::make_shared<sdf::cl::PreparedProjected>(
          sdf::cl::prepare_projected(*device, *cast.points, threads));
    } catch (const sdf::cl::Error&) {
    }
  }
  if (!prepared || !prepared->on_device) return py::none();
  return py::cast(prepared);
}

// smooth_projected on the frames prepare_projected uploaded (the engine must name the same
// device; else a device error, after which compute() falls back to the CPU).
py::array_t<float> smooth_projected_prepared(const sdf::cl::PreparedProjected& prepared,
                                             const Floats& values, int iterations, int max_depth,
                                             double min_points, double node_size_ratio,
                                             const std::string& branch_on, unsigned threads,
                                             const py::object& progress, const std::string& engine,
                                             const py::object& timings) {
  const float* v = values_of(values, prepared.count);
  const sdf::ProjectedOptions options =
      projected_options(iterations, max_depth, min_points, node_size_ratio, branch_on, threads);
  const auto* device = device_for(engine);
  if (!device) throw std::invalid_argument("smooth_projected_prepared needs an OpenCL engine");
  const sdf::ProgressFn report = sdf::python_progress(progress);
  sdf::StageTimings stages;
  py::array_t<float> out = filled_array(values.shape(0), [&](float* into) {
    sdf::cl::smooth_projected_opencl(*device, prepared, v, options, into, report, &stages);
  });
  if (!timings.is_none()) timings.attr("update")(sdf::timings_dict(stages));
  return out;
}
#endif

sdf::TextureOptions texture_options(int width, int height, double radius, bool bilateral,
                                    double range_sigma, int margin, double weld_tolerance,
                                    unsigned threads) {
  sdf::TextureOptions options;
  options.width = width;
  options.height = height;
  options.radius = radius;
  options.bilateral = bilateral;
  options.range_sigma = range_sigma;
  options.margin = margin;
  options.weld_tolerance = weld_tolerance;
  options.threads = threads;
  return options;
}

// smooth_texture's results as the Python layer takes them: values (the smoothing writes them
// into the array: `smooth(into)`), timings, image and mask.
template <class Smooth>
py::dict texture_result(py::ssize_t n, bool return_image, const Smooth& smooth) {
  sdf::TextureSmoothing out;
  py::dict result;
  result["values"] = filled_array(n, [&](float* into) { out = smooth(into); });
  result["timings"] = sdf::timings_dict(out.timings);
  result["faces_outside"] = out.faces_outside;
  result["kept_off_device"] = out.kept_off_device;
  if (return_image) {
    py::array_t<float> image({py::ssize_t(out.height), py::ssize_t(out.width)});
    py::array_t<bool> mask({py::ssize_t(out.height), py::ssize_t(out.width)});
    std::copy(out.image.begin(), out.image.end(), image.mutable_data());
    bool* m = mask.mutable_data();
    for (std::size_t t = 0; t < out.mask.size(); ++t) m[t] = out.mask[t] != 0;
    result["image"] = image;
    result["mask"] = mask;
  }
  return result;
}

py::dict smooth_texture(const Doubles& vertices, const Int64s& triangles, const Floats& values,
                        const std::string& points, const Floats& uvs, int width, int height,
                        double radius, bool bilateral, double range_sigma, int margin,
                        double weld_tolerance, bool return_image, unsigned threads,
                        const py::object& progress, const std::string& engine) {
  const sdf::Mesh mesh = mesh_from(vertices, triangles, threads);
  const sdf::PointKind kind = kind_from(points);
  const float* v = point_values(mesh, kind, values);
  require_corner_uvs(uvs, mesh);
  const sdf::TextureOptions options = texture_options(width, height, radius, bilateral, range_sigma,
                                                      margin, weld_tolerance, threads);
  const auto* device = device_for(engine);
  (void)device;  // unused without OpenCL
  const sdf::ProgressFn report = sdf::python_progress(progress);
  return texture_result(values.shape(0), return_image, [&](float* into) {
#ifdef SDF_HAVE_OPENCL
    if (device)
      return sdf::cl::smooth_texture_opencl(*device, mesh, kind, v, uvs.data(), options,
                                            return_image, report, into);
#endif
    return sdf::smooth_texture(mesh, kind, v, uvs.data(), options, return_image, report, 0.0, 1.0,
                               nullptr, into);
  });
}

// Texture smoothing's mesh-and-UV half (sdf::prepare_texture), and on an OpenCL engine the
// UVs and islands uploaded on the device's side queue: compute() runs it while the device
// casts. An upload that fails is left to smooth_texture_prepared to make (and report).
std::shared_ptr<sdf::PreparedTexture> prepare_texture(const Doubles& vertices,
                                                      const Int64s& triangles, const Floats& uvs,
                                                      int width, int height, double weld_tolerance,
                                                      bool need_merged, unsigned threads,
                                                      const std::string& engine) {
  sdf::Stopwatch clock;
  sdf::Mesh mesh = mesh_from(vertices, triangles, threads);
  require_corner_uvs(uvs, mesh);
  const double converted = clock.lap();
  sdf::TextureOptions options;
  options.width = width;
  options.height = height;
  options.weld_tolerance = weld_tolerance;
  options.threads = threads;
  const auto* device = device_for(engine);
  (void)device;  // unused without OpenCL
  // The UVs are not copied: the prepared texture keeps their array (the caller's, or the
  // float32 copy `uvs` converted it to) alive. Made here, under the GIL; let go of under it.
  std::shared_ptr<const void> keep(new py::object(uvs), [](const void* p) {
    py::gil_scoped_acquire gil;
    delete static_cast<const py::object*>(p);
  });
  py::gil_scoped_release release;
  auto prepared = std::make_shared<sdf::PreparedTexture>(
      sdf::prepare_texture(std::move(mesh), uvs.data(), options, need_merged));
  prepared->keep = std::move(keep);
  prepared->timings.insert(prepared->timings.begin(), {"mesh", converted});
#ifdef SDF_HAVE_OPENCL
  if (device) {
    try {
      sdf::cl::upload_prepared_texture(*device, *prepared, threads);
    } catch (const sdf::cl::Error&) {
    }
  }
#endif
  return prepared;
}

py::dict smooth_texture_prepared(const sdf::PreparedTexture& prepared, const Floats& values,
                                 const std::string& points, double radius, bool bilateral,
                                 double range_sigma, int margin, bool return_image,
                                 unsigned threads, const py::object& progress,
                                 const std::string& engine) {
  const sdf::PointKind kind = kind_from(points);
  const float* v = point_values(prepared.mesh, kind, values);
  const sdf::TextureOptions options =
      texture_options(prepared.width, prepared.height, radius, bilateral, range_sigma, margin,
                      prepared.islands.weld_tolerance, threads);
  const auto* device = device_for(engine);
  (void)device;  // unused without OpenCL
  const sdf::ProgressFn report = sdf::python_progress(progress);
  return texture_result(values.shape(0), return_image, [&](float* into) {
#ifdef SDF_HAVE_OPENCL
    if (device)
      return sdf::cl::smooth_texture_opencl(*device, prepared, kind, v, options, return_image,
                                            report, into);
#endif
    return sdf::smooth_texture(prepared, kind, v, options, return_image, report, 0.0, 1.0, nullptr,
                               into);
  });
}

}  // namespace

void bind_smoothing(py::module_& m) {
  m.def("smooth_kring", &smooth_kring, py::arg("vertices"), py::arg("triangles"), py::arg("values"),
        py::arg("points"), py::arg("k"), py::arg("sigma"), py::arg("corner_angle"),
        py::arg("weld_tolerance"), py::arg("threads"), py::arg("progress"));
  m.def("smooth_projected", &smooth_projected, py::arg("vertices"), py::arg("triangles"),
        py::arg("values"), py::arg("points"), py::arg("iterations"), py::arg("max_depth"),
        py::arg("min_points"), py::arg("node_size_ratio"), py::arg("branch_on"), py::arg("threads"),
        py::arg("progress"), py::arg("engine") = "cpu", py::arg("timings") = py::none());
  py::class_<sdf::CastPoints, std::shared_ptr<sdf::CastPoints>>(
      m, "CastPoints", "The points compute() casts from, lent to its beside-cast callback, opaque");
#ifdef SDF_HAVE_OPENCL
  py::class_<sdf::cl::PreparedProjected, std::shared_ptr<sdf::cl::PreparedProjected>>(
      m, "PreparedProjected",
      "Projected smoothing's point frames on an OpenCL device (prepare_projected), opaque")
      .def_property_readonly("timings", [](const sdf::cl::PreparedProjected& p) {
        return sdf::timings_dict(p.timings);
      });
  m.def("prepare_projected", &prepare_projected, py::arg("cast_points"), py::arg("threads"),
        py::arg("engine"));
  m.def("smooth_projected_prepared", &smooth_projected_prepared, py::arg("prepared"),
        py::arg("values"), py::arg("iterations"), py::arg("max_depth"), py::arg("min_points"),
        py::arg("node_size_ratio"), py::arg("branch_on"), py::arg("threads"), py::arg("progress"),
        py::arg("engine"), py::arg("timings") = py::none());
#endif
  m.def("smooth_texture", &smooth_texture, py::arg("vertices"), py::arg("triangles"),
        py::arg("values"), py::arg("points"), py::arg("uvs"), py::arg("width"), py::arg("height"),
        py::arg("radius"), py::arg("bilateral"), py::arg("range_sigma"), py::arg("margin"),
        py::arg("weld_tolerance"), py::arg("return_image"), py::arg("threads"), py::arg("progress"),
        py::arg("engine") = "cpu");
  py::class_<sdf::PreparedTexture, std::shared_ptr<sdf::PreparedTexture>>(
      m, "PreparedTexture",
      "Texture smoothing's mesh, UVs and UV islands made ready (prepare_texture), opaque")
      .def_property_readonly(
          "timings", [](const sdf::PreparedTexture& p) { return sdf::timings_dict(p.timings); });
  m.def("prepare_texture", &prepare_texture, py::arg("vertices"), py::arg("triangles"),
        py::arg("uvs"), py::arg("width"), py::arg("height"), py::arg("weld_tolerance"),
        py::arg("need_merged"), py::arg("threads"), py::arg("engine") = "cpu");
  m.def("smooth_texture_prepared", &smooth_texture_prepared, py::arg("prepared"), py::arg("values"),
        py::arg("points"), py::arg("radius"), py::arg("bilateral"), py::arg("range_sigma"),
        py::arg("margin"), py::arg("return_image"), py::arg("threads"), py::arg("progress"),
        py::arg("engine") = "cpu");
}
