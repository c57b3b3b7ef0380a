// SPDX-License-Identifier: GPL-3.0-or-later
// The segmentation functions of shape_diameter._core. The Python layer (segmentation.py)
// validates and documents; this file converts arrays and releases the GIL around native work.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cstring>
#include <stdexcept>
#include <string>

#include "arrays.h"
#include "progress.h"
#include "segment/postprocess.h"
#include "segment/segment_count.h"
#include "segment/segmentation.h"
#include "timings.h"

namespace py = pybind11;

namespace {

using sdf::Doubles;
using sdf::Int64s;
using Ints = py::array_t<int, py::array::c_style | py::array::forcecast>;

// The arrays' shapes and every corner index in range: the core trusts them.
void check_mesh(const Doubles& vertices, const Int64s& triangles, const Doubles& values) {
  if (vertices.ndim() != 2 || vertices.shape(1) != 3)
    throw std::invalid_argument("vertices must have shape (n, 3)");
  if (triangles.ndim() != 2 || triangles.shape(1) != 3)
    throw std::invalid_argument("triangles must have shape (m, 3)");
  if (values.ndim() != 1 || values.shape(0) != triangles.shape(0))
    throw std::invalid_argument("values must have one entry per face");
  const std::int64_t n = vertices.shape(0);
  const std::int64_t* t = triangles.data();
  for (py::ssize_t i = 0; i < triangles.size(); ++i)
    if (t[i] < 0 || t[i] >= n) throw std::invalid_argument("a triangle index is out of range");
}

template <class T>
py::array_t<T> array_of(const std::vector<T>& v) {
  py::array_t<T> out(static_cast<py::ssize_t>(v.size()));
  if (!v.empty()) std::memcpy(out.mutable_data(), v.data(), v.size() * sizeof(T));
  return out;
}

sdf::segment::SegmentOptions options_of(std::size_t clusters, double smoothness, bool filter,
                                        bool ties_move, bool first_move_only,
                                        std::size_t weight_rings, unsigned threads,
                                        double min_segment_area = 0.0) {
  sdf::segment::SegmentOptions o;
  o.clusters = clusters;
  o.smoothness = smoothness;
  o.filter = filter;
  o.expansion.ties_move = ties_move;
  o.expansion.first_move_only = first_move_only;
  o.weight_rings = weight_rings;
  o.threads = threads;
  o.min_segment_area = min_segment_area;
  return o;
}

py::dict boundaries_dict(const std::vector<sdf::segment::Boundary>& loops) {
  const auto b = static_cast<py::ssize_t>(loops.size());
  py::array_t<int> pairs({b, py::ssize_t{2}});
  py::array_t<double> centroids({b, py::ssize_t{3}});
  py::array_t<double> lengths(b);
  py::array_t<std::int64_t> edges(b);
  for (py::ssize_t i = 0; i < b; ++i) {
    const auto& l = loops[static_cast<std::size_t>(i)];
    pairs.mutable_at(i, 0) = l.a;
    pairs.mutable_at(i, 1) = l.b;
    for (py::ssize_t c = 0; c < 3; ++c) centroids.mutable_at(i, c) = l.centroid[c];
    lengths.mutable_at(i) = l.length;
    edges.mutable_at(i) = static_cast<std::int64_t>(l.edges);
  }
  py::dict out;
  out["segments"] = pairs;
  out["centroid"] = centroids;
  out["length"] = lengths;
  out["edges"] = edges;
  return out;
}

py::dict to_dict(const sdf::segment::Segmentation& s) {
  py::dict out;
  out["values"] = array_of(s.values);
  out["clusters"] = array_of(s.clusters);
  out["labels"] = array_of(s.segments);
  out["segment_count"] = s.segment_count;
  py::array_t<double> mixture({static_cast<py::ssize_t>(s.mixture.size()), py::ssize_t{3}});
  for (std::size_t c = 0; c < s.mixture.size(); ++c) {
    const auto i = static_cast<py::ssize_t>(c);
    mixture.mutable_at(i, 0) = s.mixture[c].mean;
    mixture.mutable_at(i, 1) = s.mixture[c].deviation;
    mixture.mutable_at(i, 2) = s.mixture[c].weight;
  }
  out["mixture"] = mixture;
  out["energy"] = s.energy;
  out["smoothness"] = s.smoothness;
  out["segment_area"] = array_of(s.stats.area);
  out["segment_mean"] = array_of(s.stats.mean_value);
  out["vertex_labels"] = array_of(s.vertex_labels);
  out["weight_offsets"] = array_of(s.vertex_weights.offsets);
  out["weight_segments"] = array_of(s.vertex_weights.segment);
  out["weight_values"] = array_of(s.vertex_weights.weight);
  out["boundaries"] = boundaries_dict(s.boundaries);
  out["timings"] = sdf::timings_dict(s.timings);
  return out;
}

py::dict segment(const Doubles& vertices, const Int64s& triangles, const Doubles& values,
                 std::size_t clusters, double smoothness, bool filter, bool ties_move,
                 bool first_move_only, std::size_t weight_rings, unsigned threads,
                 double min_segment_area, std::size_t segments, const py::object& progress) {
  check_mesh(vertices, triangles, values);
  const auto o = options_of(clusters, smoothness, filter, ties_move, first_move_only, weight_rings,
                            threads, min_segment_area);
  // Called on this thread with the GIL taken (python_progress): Ctrl-C, or an exception the
  // callback raises, stops the segmentation and comes back to Python.
  const sdf::ProgressFn report = sdf::python_progress(progress);
  sdf::segment::Segmentation s;
  {
    py::gil_scoped_release release;
    const auto nv = static_cast<std::size_t>(vertices.shape(0));
    const auto nf = static_cast<std::size_t>(triangles.shape(0));
    // segments = 0: the clusters as asked; else searched for that many segments.
    s = segments == 0 ? sdf::segment::segment_mesh(vertices.data(), nv, triangles.data(), nf,
                                                   values.data(), o, report)
                      : sdf::segment::segment_to_count(vertices.data(), nv, triangles.data(), nf,
                                                       values.data(), o, segments, report);
  }
  return to_dict(s);
}

double segmentation_energy(const Doubles& vertices, const Int64s& triangles, const Doubles& values,
                           const Ints& labels, std::size_t clusters, double smoothness, bool filter,
                           unsigned threads) {
  check_mesh(vertices, triangles, values);
  if (labels.ndim() != 1 || labels.shape(0) != triangles.shape(0))
    throw std::invalid_argument("labels must have one entry per face");
  const auto o = options_of(clusters, smoothness, filter, true, true, 0, threads);
  py::gil_scoped_release release;
  return sdf::segment::segmentation_energy(
      vertices.data(), static_cast<std::size_t>(vertices.shape(0)), triangles.data(),
      static_cast<std::size_t>(triangles.shape(0)), values.data(), o, labels.data());
}

}  // namespace

void bind_segmentation(py::module_& m) {
  m.def("segment", &segment, py::arg("vertices"), py::arg("triangles"), py::arg("values"),
        py::arg("clusters"), py::arg("smoothness"), py::arg("filter"), py::arg("ties_move"),
        py::arg("first_move_only"), py::arg("weight_rings"), py::arg("threads"),
        py::arg("min_segment_area") = 0.0, py::arg("segments") = 0,
        py::arg("progress") = py::none());
  m.def("segmentation_energy", &segmentation_energy, py::arg("vertices"), py::arg("triangles"),
        py::arg("values"), py::arg("labels"), py::arg("clusters"), py::arg("smoothness"),
        py::arg("filter"), py::arg("threads"));
}
