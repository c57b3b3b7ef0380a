// SPDX-License-Identifier: GPL-3.0-or-later
// The private compiled module shape_diameter._core. The Python layer (api.py) validates and
// documents; this file only converts arrays and releases the GIL around native work.
#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <memory>
#include <stdexcept>
#include <string>
#include <utility>

#include <cstddef>

#include "accel/bvh.h"
#include "arrays.h"
#include "options.h"
#include "pipeline/sdf.h"
#include "post/normalize.h"
#include "post/smoothing_kring.h"
#include "prepare/orientation_parts.h"
#include "ray/sdf_reduce.h"
#include "smooth/sdf_smooth_projected.h"
#include "test_bridge.h"
#include "traverse/sdf_octree.h"
#include "util/parallel.h"
#ifdef SDF_HAVE_OPENCL
#include "opencl/devices.h"
#include "opencl/opencl_engine.h"
#include "opencl/program_cache.h"
#endif

namespace py = pybind11;

void bind_field(py::module_& m);         // field.cpp
void bind_segmentation(py::module_& m);  // segmentation.cpp
void bind_uv_plan(py::module_& m);       // uv_plan.cpp

namespace {

using sdf::Doubles;
using sdf::Floats;
using sdf::Int64s;
using sdf::mesh_arrays;
using sdf::MeshArrays;
using sdf::parse_points;
using sdf::parse_sampling;
using sdf::to_mesh;

// Every OpenCL device as a dict, in the order "opencl:N" counts them.
py::list opencl_devices() {
  py::list list;
#ifdef SDF_HAVE_OPENCL
  for (const sdf::cl::Device& d : sdf::cl::devices()) {
    py::dict e;
    e["index"] = d.index;
    e["device"] = d.name;
    e["platform"] = d.platform_name;
    e["vendor"] = d.vendor;
    e["driver"] = d.driver_version;
    e["version"] = d.device_version;
    e["type"] = d.gpu ? "GPU" : "CPU";
    e["memory"] = d.global_memory;
    e["max_allocation"] = d.max_allocation;
    e["compute_units"] = d.compute_units;
    e["clock_mhz"] = d.clock_mhz;
    e["double"] = d.fp64;
    list.append(e);
  }
#endif
  return list;
}

std::string opencl_unavailable_reason() {
#ifdef SDF_HAVE_OPENCL
  return sdf::cl::devices().empty() ? sdf::cl::unavailable_reason() : "";
#else
  return "this build has no OpenCL engine";
#endif
}

glm::vec3 unit_vector(const Floats& v, const char* what) {
  if (v.size() != 3) throw std::invalid_argument(std::string(what) + " must have 3 components");
  glm::vec3 n(v.data()[0], v.data()[1], v.data()[2]);
  const float len = glm::length(n);
  if (!(len > 0.0f) || !std::isfinite(len))
    throw std::invalid_argument(std::string(what) + " must be a finite, non-zero vector");
  return n / len;
}

py::tuple cone_rays(const Floats& axis, int rays, double cone_angle, const std::string& sampling,
                    std::uint32_t seed, std::uint32_t point, const py::object& tangent) {
  const glm::vec3 n = unit_vector(axis, "normal");
  glm::vec3 t = sdf::fallback_tangent(n);
  if (!tangent.is_none()) {
    const glm::vec3 given = unit_vector(tangent.cast<Floats>(), "tangent");
    const glm::vec3 perpendicular = given - glm::dot(given, n) * n;
    if (!(glm::length(perpendicular) > 1e-6f))
      throw std::invalid_argument("tangent must not be parallel to the normal");
    t = glm::normalize(perpendicular);
  }
  const sdf::Cone cone = sdf::make_cone(rays, cone_angle, parse_sampling(sampling), seed);
  py::array_t<float> directions({rays, 3});
  py::array_t<float> angles(rays);
  sdf::cone_rays(cone, n, t, point, reinterpret_cast<glm::vec3*>(directions.mutable_data()),
                 angles.mutable_data());
  return py::make_tuple(directions, angles);
}

float reduce_lengths(const Floats& lengths, const Floats& angles, const std::string& sampling,
                     int rays, double cone_angle) {
  if (lengths.ndim() != 1 || angles.ndim() != 1 || lengths.size() != angles.size())
    throw std::invalid_argument("lengths and angles must be 1-D arrays of the same length");
  const int n = static_cast<int>(lengths.size());
  if (n > sdf::kMaxRays) throw std::invalid_argument("more lengths than the most rays allowed");
  if (n == 0) return std::nanf("");
  const sdf::Cone cone =
      sdf::make_cone(rays > 0 ? rays : n, cone_angle, parse_sampling(sampling), 0);
  std::vector<float> l(lengths.data(), lengths.data() + n), a(angles.data(), angles.data() + n);
  return sdf::kern::sdf_reduce(static_cast<int>(cone.sampling), l.data(), a.data(), n,
                               cone.angle_floor);
}

py::tuple sample_points(const Doubles& vertices, const Int64s& triangles,
                        const std::string& points) {
  const sdf::Mesh mesh = to_mesh(vertices, triangles);
  const sdf::SamplePoints s = sdf::sample_points(mesh, parse_points(points));
  const py::ssize_t n = static_cast<py::ssize_t>(s.size());
  py::array_t<float> origins({n, py::ssize_t(3)}), axes({n, py::ssize_t(3)}),
      tangents({n, py::ssize_t(3)});
  float* o = origins.mutable_data();
  float* a = axes.mutable_data();
  float* t = tangents.mutable_data();
  for (py::ssize_t i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) {
      o[3 * i + k] = static_cast<float>(s.origins[i][k] + mesh.center[k]);
      a[3 * i + k] = s.axes[i][k];
      t[3 * i + k] = s.tangents[i][k];
    }
  }
  return py::make_tuple(origins, axes, tangents);
}

// Result.normalized from values of any shape (float32 or float64, C order), same shape out.
template <class T>
py::array_t<float> normalize(const py::array_t<T, py::array::c_style>& values,
                             const std::string& method, unsigned threads) {
  const sdf::Normalization how = sdf::parse_normalization(method);
  py::array_t<float> out(std::vector<py::ssize_t>(values.shape(), values.shape() + values.ndim()));
  const T* in = values.data();
  float* to = out.mutable_data();
  const std::size_t n = static_cast<std::size_t>(values.size());
  py::gil_scoped_release release;
  sdf::normalize(in, n, how, threads, to);
  return out;
}

// _core's OpenCL program counts, for shape_diameter._testing (test_bridge.h).
void core_program_stats(std::uint64_t* compiled, std::uint64_t* from_cache) {
#ifdef SDF_HAVE_OPENCL
  const sdf::cl::ProgramStats s = sdf::cl::program_stats();
  *compiled = s.compiled;
  *from_cache = s.from_cache;
#else
  *compiled = *from_cache = 0;
#endif
}

}  // namespace

PYBIND11_MODULE(_core, m) {
  m.doc() = "Shape Diameter native core (private; use the shape_diameter package)";
  py::register_exception<sdf::Cancelled>(m, "Cancelled");
  m.def("opencl_devices", &opencl_devices);
  m.def("normalize", &normalize<float>, py::arg("values"), py::arg("method"),
        py::arg("threads") = 0);
  m.def("normalize", &normalize<double>, py::arg("values"), py::arg("method"),
        py::arg("threads") = 0);
  m.def("opencl_unavailable_reason", &opencl_unavailable_reason);
  m.def("opencl_gpu_lost_to_fork", [] {
#ifdef SDF_HAVE_OPENCL
    return sdf::cl::gpu_lost_to_fork();
#else
    return false;
#endif
  });
  m.def(
      "opencl_select",
      [](const std::string& engine) {
#ifdef SDF_HAVE_OPENCL
        std::vector<int> indices;
        for (const sdf::cl::Device* d : sdf::cl::select_devices(engine))
          indices.push_back(d->index);
        return indices;
#else
        throw std::invalid_argument("this build of shape_diameter has no OpenCL engine (engine '" +
                                    engine + "')");
#endif
      },
      "The indices of the devices an OpenCL engine string selects; ValueError as compute() "
      "would raise it (OpenCL not available, no device matching).");
#ifdef SDF_HAVE_OPENCL
  m.def("opencl_cache_directory", &sdf::cl::cache_directory);
  py::register_exception<sdf::cl::Error>(m, "OpenCLError", PyExc_RuntimeError);
#endif
  m.def("cone_rays", &cone_rays, py::arg("normal"), py::arg("rays"), py::arg("cone_angle"),
        py::arg("sampling"), py::arg("seed"), py::arg("point_index"),
        py::arg("tangent") = py::none());
  m.def("reduce_lengths", &reduce_lengths, py::arg("lengths"), py::arg("angles"),
        py::arg("sampling"), py::arg("rays"), py::arg("cone_angle"));
  m.def("sample_points", &sample_points, py::arg("vertices"), py::arg("triangles"),
        py::arg("points"));
  m.def("hardware_threads", [] { return sdf::resolve_threads(0); });
  m.def(
      "mesh_values",
      [](const Doubles& vertices, const Int64s& triangles, unsigned threads) {
        const MeshArrays a = mesh_arrays(vertices, triangles);
        sdf::MeshValues values;
        {
          py::gil_scoped_release release;
          values =
              sdf::mesh_values(a.vertices, a.vertex_count, a.triangles, a.triangle_count, threads);
        }
        return py::make_tuple(values.not_finite, values.first_not_finite, values.min_index,
                              values.max_index);
      },
      py::arg("vertices"), py::arg("triangles"), py::arg("threads") = 0);
  // Per face its part (faces joined through shared vertex positions: orientation's parts,
  // orientation_parts.h) and per part the largest side of its bounding box: for compute()'s
  // check of parts the near-hit cutoff, set by the whole mesh, reaches.
  m.def(
      "mesh_parts",
      [](const Doubles& vertices, const Int64s& triangles, unsigned threads) {
        const sdf::Mesh mesh = to_mesh(vertices, triangles, threads);
        sdf::Parts parts;
        std::vector<double> extents;
        {
          py::gil_scoped_release release;
          parts = sdf::find_parts(mesh, threads);
          for (const sdf::PartBox& box : sdf::part_boxes(mesh, parts, threads)) {
            const glm::dvec3 side = box.hi - box.lo;
            extents.push_back(std::max({side.x, side.y, side.z}));
          }
        }
        return py::make_tuple(
            py::array_t<std::uint32_t>(parts.part_of.size(), parts.part_of.data()),
            py::array_t<double>(extents.size(), extents.data()));
      },
      py::arg("vertices"), py::arg("triangles"), py::arg("threads") = 0);
  m.def(
      "default_kring_k", [](std::size_t faces) { return sdf::default_kring_k(faces); },
      py::arg("faces"));
  m.attr("MAX_RAYS") = sdf::kMaxRays;
  m.attr("NEAR_CUTOFF_SHARE") = sdf::kNearCutoffShare;
  bind_field(m);
  bind_segmentation(m);
  bind_uv_plan(m);
  // For the test-only module shape_diameter._testing alone (test_bridge.h).
  static sdf::TestBridge bridge{
      [](const sdf::TestOverrides& overrides) { sdf::test_overrides() = overrides; },
      &core_program_stats};
  m.attr("_test_bridge") = py::capsule(&bridge, sdf::kTestBridgeName);
}
