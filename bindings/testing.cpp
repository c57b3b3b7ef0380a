// SPDX-License-Identifier: GPL-3.0-or-later
// The test-only module shape_diameter._testing: the test overrides (util/test_overrides.h)
// and the functions only tests and benchmarks call (a tree's statistics, struct layouts, a
// device's sort keys, a kernel build, the program cache's counts). The package never imports
// it; docs/testing.md describes it. Its overrides are set in both copies of the core, its own
// and _core's (test_bridge.h).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <chrono>
#include <cstddef>
#include <stdexcept>
#include <string>
#include <vector>

#include "accel/bvh.h"
#include "accel/bvh_stats.h"
#include "accel/octree.h"
#include "arrays.h"
#include "common/sdf_layout.h"
#include "mesh/mesh_weld.h"
#include "post/uv_islands.h"
#include "smooth/sdf_smooth_projected.h"
#include "test_bridge.h"
#include "util/test_overrides.h"
#ifdef SDF_HAVE_OPENCL
#include "opencl/device_tree.h"
#include "opencl/opencl_engine.h"
#endif

namespace py = pybind11;

void bind_cast(py::module_& m);       // testing_cast.cpp
void bind_smoothing(py::module_& m);  // testing_smoothing.cpp

namespace {

using sdf::Doubles;
using sdf::Floats;
using sdf::Int64s;

sdf::Mesh to_mesh(const Doubles& vertices, const Int64s& triangles) {
  return sdf::to_mesh(vertices, triangles, 0);
}

// ---- The overrides ----

const sdf::TestBridge& core_bridge() {
  static const sdf::TestBridge* bridge = [] {
    const py::capsule capsule = py::module_::import("shape_diameter._core").attr("_test_bridge");
    if (capsule.name() == nullptr || std::string(capsule.name()) != sdf::kTestBridgeName)
      throw std::runtime_error("shape_diameter._core is not the build this module belongs to");
    return capsule.get_pointer<sdf::TestBridge>();
  }();
  return *bridge;
}

// Name <-> value of the two choices, as Python writes them.
template <class Choice>
using Names = std::vector<std::pair<const char*, Choice>>;

const Names<sdf::KernelChoice> kKernels = {{"engine", sdf::KernelChoice::Engine},
                                           {"bvh_per_point", sdf::KernelChoice::BvhPerPoint},
                                           {"bvh8_per_point", sdf::KernelChoice::Bvh8PerPoint},
                                           {"bvh_per_ray", sdf::KernelChoice::BvhPerRay}};
const Names<sdf::TreeChoice> kTrees = {{"engine", sdf::TreeChoice::Engine},
                                       {"host", sdf::TreeChoice::Host},
                                       {"device", sdf::TreeChoice::Device}};

template <class Choice>
Choice parse(const char* field, const std::string& name, const Names<Choice>& names) {
  std::string known;
  for (const auto& [text, choice] : names) {
    if (name == text) return choice;
    known += known.empty() ? std::string(text) : std::string(", ") + text;
  }
  throw std::invalid_argument(std::string(field) + "='" + name + "': use " + known);
}

template <class Choice>
const char* name_of(Choice choice, const Names<Choice>& names) {
  for (const auto& [text, c] : names)
    if (c == choice) return text;
  return "?";
}

// Sets field `name` of `o` to `value`; throws py::type_error for an unknown name.
void set_field(sdf::TestOverrides& o, const std::string& name, const py::handle& value) {
  if (name == "cpu_without_avx2") {
    o.cpu_without_avx2 = value.cast<bool>();
  } else if (name == "no_sliver_cutting") {
    o.no_sliver_cutting = value.cast<bool>();
  } else if (name == "opencl_kernel") {
    o.opencl_kernel = parse(name.c_str(), value.cast<std::string>(), kKernels);
  } else if (name == "opencl_tree") {
    o.opencl_tree = parse(name.c_str(), value.cast<std::string>(), kTrees);
  } else if (name == "opencl_extra_options") {
    o.opencl_extra_options = value.cast<std::string>();
  } else if (name == "opencl_staging_chunk") {
    o.opencl_staging_chunk = value.cast<std::size_t>();
  } else if (name == "opencl_lose_device_after") {
    o.opencl_lose_device_after = value.cast<long>();
  } else {
    throw py::type_error("no test override named '" + name + "' (docs/testing.md lists them)");
  }
}

// `o` with the fields named in `fields` changed. Unknown names and values of the wrong type
// are a TypeError, names of no choice a ValueError, before anything is set.
sdf::TestOverrides with_fields(sdf::TestOverrides o, const py::kwargs& fields) {
  for (const auto& [key, value] : fields) {
    const std::string name = py::str(key);
    try {
      set_field(o, name, value);
    } catch (const py::cast_error&) {
      throw py::type_error(name + "=" + std::string(py::repr(value)) +
                           ": a value of the wrong type (docs/testing.md lists the values)");
    }
  }
  return o;
}

py::dict as_dict(const sdf::TestOverrides& o) {
  py::dict d;
  d["cpu_without_avx2"] = o.cpu_without_avx2;
  d["no_sliver_cutting"] = o.no_sliver_cutting;
  d["opencl_kernel"] = name_of(o.opencl_kernel, kKernels);
  d["opencl_tree"] = name_of(o.opencl_tree, kTrees);
  d["opencl_extra_options"] = o.opencl_extra_options;
  d["opencl_staging_chunk"] = o.opencl_staging_chunk;
  d["opencl_lose_device_after"] = o.opencl_lose_device_after;
  return d;
}

// Both copies of the core get the same values (test_bridge.h says why there are two).
void apply(const sdf::TestOverrides& o) {
  core_bridge().set_overrides(o);
  sdf::test_overrides() = o;
}

// `with overrides(field=value, ...):` sets the fields on entry and puts back on exit what
// was there on entry.
class ScopedOverrides {
 public:
  explicit ScopedOverrides(py::kwargs fields) : fields_(std::move(fields)) {
    (void)with_fields(sdf::test_overrides(), fields_);  // refuses bad fields at once
  }
  void enter() {
    before_ = sdf::test_overrides();
    apply(with_fields(before_, fields_));
  }
  void exit() { apply(before_); }

 private:
  py::kwargs fields_;
  sdf::TestOverrides before_;
};

void bind_overrides(py::module_& m) {
  py::class_<ScopedOverrides>(m, "overrides",
                              "with overrides(field=value, ...): the fields set for the block, "
                              "then put back (docs/testing.md lists them)")
      .def(py::init<py::kwargs>())
      .def("__enter__", [](ScopedOverrides& s) { s.enter(); })
      .def("__exit__", [](ScopedOverrides& s, const py::args&) { s.exit(); });
  m.def(
      "set_overrides",
      [](const py::kwargs& fields) { apply(with_fields(sdf::test_overrides(), fields)); },
      "Sets the fields until changed again (a child process that keeps them to its end).");
  m.def(
      "current_overrides", [] { return as_dict(sdf::test_overrides()); },
      "Every override with its value now.");
}

// ---- The test-only functions ----

// The octree alone, for the benchmark's build-time table (paper's Table 2).
py::dict octree_stats(const Doubles& vertices, const Int64s& triangles, int max_depth,
                      int leaf_size) {
  const sdf::Mesh mesh = to_mesh(vertices, triangles);
  sdf::OctreeConfig config;
  config.max_depth = max_depth;
  config.leaf_size = leaf_size;
  sdf::Octree tree;
  double seconds = 0.0;
  {
    py::gil_scoped_release release;
    const auto start = std::chrono::steady_clock::now();
    tree = sdf::build_octree(mesh, config);
    seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  py::dict d;
  d["seconds"] = seconds;
  d["nodes"] = tree.nodes.size();
  d["leaf_words"] = tree.leaves.size();
  d["depth"] = tree.depth;
  return d;
}

// The BVH alone, for the build benchmark: its time, size and SAH cost (a tree quality figure).
py::dict bvh_stats(const Doubles& vertices, const Int64s& triangles, unsigned threads) {
  const sdf::Mesh mesh = to_mesh(vertices, triangles);
  sdf::BvhConfig config;
  config.threads = threads;
  sdf::Bvh bvh;
  double seconds = 0.0;
  {
    py::gil_scoped_release release;
    const auto start = std::chrono::steady_clock::now();
    bvh = sdf::build_bvh(mesh, config);
    seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  py::dict d;
  d["seconds"] = seconds;
  d["nodes"] = bvh.nodes.size();
  d["triangles"] = bvh.triangles.size();
  d["depth"] = sdf::bvh_depth(bvh);
  d["sah_cost"] = sdf::bvh_sah_cost(bvh);
  return d;
}

// Sizes and member offsets of the structs shared with the kernels, in the order the layout
// probe kernel writes them.
std::vector<std::uint32_t> host_layout() {
  using namespace sdf::kern;
  return {sizeof(SdfBvhNode),
          offsetof(SdfBvhNode, first),
          offsetof(SdfBvhNode, hi_x),
          offsetof(SdfBvhNode, count),
          sizeof(SdfTriangle),
          offsetof(SdfTriangle, id),
          offsetof(SdfTriangle, e1_x),
          offsetof(SdfTriangle, e2_x),
          sizeof(SdfOctreeRoot),
          offsetof(SdfOctreeRoot, size),
          sizeof(SdfCastParams),
          offsetof(SdfCastParams, tmin),
          offsetof(SdfCastParams, count),
          sizeof(SdfPointNode),
          offsetof(SdfPointNode, half_side),
          offsetof(SdfPointNode, count),
          offsetof(SdfPointNode, first_child),
          offsetof(SdfPointNode, child_count),
          sizeof(SdfBvh8Node),
          offsetof(SdfBvh8Node, hi_x),
          offsetof(SdfBvh8Node, child),
          offsetof(SdfBvh8Node, count),
          sizeof(SdfTrianglePacket4),
          offsetof(SdfTrianglePacket4, id)};
}

// Per vertex the vertex it welds to (tolerance relative to the largest bounding-box side, as
// smoothing uses it), and how many distinct vertices remain.
py::tuple weld_vertices(const Doubles& vertices, const Int64s& triangles, double tolerance) {
  const sdf::Mesh mesh = to_mesh(vertices, triangles);
  sdf::Weld weld;
  {
    py::gil_scoped_release release;
    weld = sdf::weld_vertices(mesh.vertices.data(), mesh.vertices.size(),
                              sdf::weld_tolerance(mesh, tolerance));
  }
  py::array_t<std::int64_t> merged(static_cast<py::ssize_t>(weld.merged.size()));
  std::copy(weld.merged.begin(), weld.merged.end(), merged.mutable_data());
  return py::make_tuple(merged, weld.count);
}

// Per face its UV island, as texture smoothing labels them.
py::array_t<std::int32_t> uv_islands(const Doubles& vertices, const Int64s& triangles,
                                     const Floats& uvs, double weld_tolerance) {
  const sdf::Mesh mesh = to_mesh(vertices, triangles);
  if (uvs.ndim() != 3 || static_cast<std::size_t>(uvs.shape(0)) != mesh.triangles.size() ||
      uvs.shape(1) != 3 || uvs.shape(2) != 2)
    throw std::invalid_argument("uvs must have shape (m, 3, 2)");
  std::vector<std::int32_t> islands;
  {
    py::gil_scoped_release release;
    islands = sdf::uv_islands(mesh, uvs.data(), weld_tolerance);
  }
  return py::array_t<std::int32_t>(static_cast<py::ssize_t>(islands.size()), islands.data());
}

void bind_opencl(py::module_& m) {
#ifdef SDF_HAVE_OPENCL
  m.def(
      "opencl_layout",
      [](int index) {
        py::gil_scoped_release release;
        return sdf::cl::probe_layout(index);
      },
      "What the layout probe kernel writes on device `index` (host_layout's order).");
  m.def(
      "opencl_tree_keys",
      [](const Doubles& vertices, const Int64s& triangles, int index) {
        const sdf::Mesh mesh = to_mesh(vertices, triangles);
        sdf::cl::TreeKeys keys;
        {
          py::gil_scoped_release release;
          keys = sdf::cl::device_tree_keys(index, mesh);
        }
        return py::make_tuple(py::array_t<std::uint32_t>(keys.order.size(), keys.order.data()),
                              py::array_t<std::uint32_t>(keys.codes.size(), keys.codes.data()),
                              keys.with_area, keys.margin);
      },
      "The device-built tree's keys (order, codes, faces with area, margin) as device `index` "
      "makes them.");
  m.def(
      "opencl_build_source",
      [](int index, const std::string& source) {
        py::gil_scoped_release release;
        sdf::cl::build_source_for_test(index, source);
      },
      "Builds an OpenCL source on device `index`; raises RuntimeError with the build log.");
#endif
  m.def(
      "opencl_program_stats",
      [] {
        std::uint64_t compiled = 0, from_cache = 0;
        core_bridge().program_stats(&compiled, &from_cache);
        py::dict d;
        d["compiled"] = compiled;
        d["from_cache"] = from_cache;
        return d;
      },
      "Programs the package's OpenCL engine built from source and loaded from the cache so far "
      "in this process.");
}

}  // namespace

PYBIND11_MODULE(_testing, m) {
  m.doc() = "Shape Diameter's test hooks: for the tests and benchmarks only (docs/testing.md)";
  bind_overrides(m);
  m.def("octree_stats", &octree_stats, py::arg("vertices"), py::arg("triangles"),
        py::arg("max_depth") = 10, py::arg("leaf_size") = 8);
  m.def("bvh_stats", &bvh_stats, py::arg("vertices"), py::arg("triangles"), py::arg("threads") = 0);
  m.def("host_layout", &host_layout);
  m.def("weld_vertices", &weld_vertices, py::arg("vertices"), py::arg("triangles"),
        py::arg("tolerance"));
  m.def("uv_islands", &uv_islands, py::arg("vertices"), py::arg("triangles"), py::arg("uvs"),
        py::arg("weld_tolerance"));
  bind_opencl(m);
  bind_cast(m);
  bind_smoothing(m);
}
