// SPDX-License-Identifier: GPL-3.0-or-later
//
// cgal_segment -- reference mesh segmentation from CGAL's segmentation_from_sdf_values().
//
// This program is a TEST/BENCHMARK REFERENCE ONLY. It is never linked into the
// Shape Diameter product; the Python tests and bench/segmentation.py run it as a
// separate executable and compare its output with shape_diameter.segment(). It
// links CGAL (GPL, with the Boykov-Kolmogorov max-flow CGAL uses by default),
// hence the licence above.
//
// Usage:  cgal_segment IN.off OUT.txt [--clusters K] [--lambda L] [--rays N]
//                      [--values VALUES.txt [--postprocess]] [--split-nonmanifold]
//
//   IN.off     triangle mesh in OFF format (vertices, then faces "3 a b c").
//   OUT.txt    the result (below), one line per face of IN.off, in file order.
//   --clusters K   number of clusters of the soft clustering (CGAL's default 5).
//   --lambda L     smoothing lambda of the graph cut (CGAL's default 0.26).
//   --rays N       rays per face for sdf_values (CGAL's default 25).
//   --values VALUES.txt  one SDF value per line, one line per face, in file order:
//                  used as they are instead of computing sdf_values (CGAL expects
//                  them linearly normalised to [0, 1], as postprocess leaves them).
//   --postprocess  with --values: first run CGAL's sdf_values_postprocessing on the
//                  given values (-1 marks a face without a value; then bilateral
//                  smoothing and linear normalisation to [0, 1]).
//   --split-nonmanifold  a triangle that Surface_mesh::add_face refuses as
//                  non-manifold is added as a detached triangle on copies of its
//                  vertices (see off_mesh.h); otherwise such a file is an error.
//
// Without --values the SDF is CGAL's sdf_values(mesh, map, 2/3*pi, N, true): the
// cone angle and post-processing are CGAL's defaults. Every face of the file must
// become a face of the mesh (a segmentation labels every face), so a face that is
// not a triangle, or that add_face refuses, is an error (exit status 2).
//
// OUT.txt starts with one line "# {json}" holding
//   faces, clusters, lambda, segments (CGAL's returned count), source ("sdf_values" or
//   "values"), and wall times in seconds of the CGAL calls alone (no I/O, no mesh
//   building): sdf_seconds (sdf_values, post-processing included; 0 with --values),
//   postprocess_seconds (sdf_values_postprocessing; 0 unless --postprocess),
//   cluster_seconds (segmentation_from_sdf_values with output_cluster_ids=true),
//   segmentation_seconds (segmentation_from_sdf_values with output_cluster_ids=false,
//   which is CGAL's segmentation as users call it), and segmentation_cpu_seconds, the
//   processor time of that call (std::clock; CGAL's segmentation runs on one thread, so
//   this is its wall time on an idle machine, whatever else the machine runs).
// Then one line per face: "SDF CLUSTER SEGMENT", the SDF value the segmentation used
// (%.17g), the face's cluster id (0 = thinnest cluster) and its segment id (segments
// numbered by increasing mean SDF). numpy.loadtxt(OUT.txt) reads the table.
//
// Face order: Surface_mesh numbers faces in the order add_face created them, and
// every face is added in file order, so mesh face i is file face i (checked).

#include <CGAL/mesh_segmentation.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <exception>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include "off_mesh.h"

using reference::Face_index;
using reference::Mesh;

namespace {

[[noreturn]] void fail(const std::string& msg) {
  std::cerr << "cgal_segment: error: " << msg << "\n";
  std::exit(2);
}

const char* kUsage =
    "usage: cgal_segment IN.off OUT.txt [--clusters K] [--lambda L] [--rays N]\n"
    "                    [--values VALUES.txt [--postprocess]] [--split-nonmanifold]\n";

struct Options {
  std::string input, output, values;
  long clusters = 5;
  double lambda = 0.26;
  long rays = 25;
  bool postprocess = false;
  bool split_nonmanifold = false;
};

long positive_integer(const char* text, const char* what) {
  char* end = nullptr;
  const long v = std::strtol(text, &end, 10);
  if (end == text || *end != '\0' || v < 1) fail(std::string(what) + " must be a positive integer");
  return v;
}

Options parse_options(int argc, char** argv) {
  Options o;
  std::vector<std::string> pos;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    const bool has_value = i + 1 < argc;
    if (arg == "--postprocess") {
      o.postprocess = true;
    } else if (arg == "--split-nonmanifold") {
      o.split_nonmanifold = true;
    } else if (arg == "--clusters" && has_value) {
      o.clusters = positive_integer(argv[++i], "--clusters");
    } else if (arg == "--rays" && has_value) {
      o.rays = positive_integer(argv[++i], "--rays");
    } else if (arg == "--values" && has_value) {
      o.values = argv[++i];
    } else if (arg == "--lambda" && has_value) {
      char* end = nullptr;
      o.lambda = std::strtod(argv[++i], &end);
      if (end == argv[i] || *end != '\0' || !std::isfinite(o.lambda) || o.lambda < 0)
        fail("--lambda must be a finite number >= 0");
    } else if (arg.rfind("--", 0) == 0) {
      std::cerr << kUsage;
      fail("unknown option or missing value: " + arg);
    } else {
      pos.push_back(arg);
    }
  }
  if (pos.size() != 2) {
    std::cerr << kUsage;
    std::exit(2);
  }
  if (o.postprocess && o.values.empty()) fail("--postprocess needs --values");
  o.input = pos[0];
  o.output = pos[1];
  return o;
}

// One finite value per line (-1 allowed, and meant, with --postprocess), `faces` lines.
std::vector<double> read_values(const std::string& path, size_t faces) {
  std::ifstream in(path);
  if (!in) fail("cannot open " + path);
  std::vector<double> values;
  values.reserve(faces);
  std::string line;
  while (std::getline(in, line)) {
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    char* end = nullptr;
    const double v = std::strtod(line.c_str(), &end);
    if (end == line.c_str() || !std::isfinite(v))
      fail(path + ": line " + std::to_string(values.size() + 1) + " is not a finite number");
    values.push_back(v);
  }
  if (values.size() != faces)
    fail(path + " has " + std::to_string(values.size()) + " values for " + std::to_string(faces) +
         " faces");
  return values;
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

int main(int argc, char** argv) {
  const Options opt = parse_options(argc, argv);

  reference::Built_mesh built;
  try {
    built = reference::build_surface_mesh(reference::read_off(opt.input), opt.split_nonmanifold);
  } catch (const std::exception& e) {
    fail(e.what());
  }
  Mesh& mesh = built.mesh;
  const size_t faces = built.face_of.size();
  if (built.refused)
    fail(std::to_string(built.refused) + " of " + std::to_string(faces) +
         " faces are not triangles or could not be added to the Surface_mesh" +
         (opt.split_nonmanifold ? "" : " (try --split-nonmanifold)"));
  if (faces == 0) fail(opt.input + " has no faces");
  for (size_t i = 0; i < faces; ++i)
    if (built.face_of[i] != Face_index(static_cast<Mesh::size_type>(i)))
      fail("face order: file face " + std::to_string(i) + " is not mesh face " + std::to_string(i));
  if (built.split)
    std::cerr << "cgal_segment: " << built.split << " of " << faces
              << " faces were non-manifold and were added as detached triangles\n";

  typedef Mesh::Property_map<Face_index, double> Sdf_map;
  typedef Mesh::Property_map<Face_index, std::size_t> Id_map;
  Sdf_map sdf = mesh.add_property_map<Face_index, double>("f:sdf", -1.0).first;
  Id_map cluster = mesh.add_property_map<Face_index, std::size_t>("f:cluster", 0).first;
  Id_map segment = mesh.add_property_map<Face_index, std::size_t>("f:segment", 0).first;

  double sdf_seconds = 0.0, postprocess_seconds = 0.0;
  std::size_t segments = 0;
  double cluster_seconds = 0.0, segmentation_seconds = 0.0, segmentation_cpu_seconds = 0.0;
  try {
    if (opt.values.empty()) {
      const auto t0 = std::chrono::steady_clock::now();
      CGAL::sdf_values(mesh, sdf, 2.0 / 3.0 * CGAL_PI, static_cast<std::size_t>(opt.rays), true);
      sdf_seconds = seconds_since(t0);
    } else {
      const std::vector<double> given = read_values(opt.values, faces);
      for (size_t i = 0; i < faces; ++i)
        sdf[Face_index(static_cast<Mesh::size_type>(i))] = given[i];
      if (opt.postprocess) {
        const auto t0 = std::chrono::steady_clock::now();
        CGAL::sdf_values_postprocessing(mesh, sdf);
        postprocess_seconds = seconds_since(t0);
      }
    }
    const std::size_t k = static_cast<std::size_t>(opt.clusters);
    auto t0 = std::chrono::steady_clock::now();
    CGAL::segmentation_from_sdf_values(mesh, sdf, cluster, k, opt.lambda, true);
    cluster_seconds = seconds_since(t0);
    t0 = std::chrono::steady_clock::now();
    const std::clock_t cpu0 = std::clock();
    segments = CGAL::segmentation_from_sdf_values(mesh, sdf, segment, k, opt.lambda, false);
    segmentation_cpu_seconds = static_cast<double>(std::clock() - cpu0) / CLOCKS_PER_SEC;
    segmentation_seconds = seconds_since(t0);
  } catch (const std::exception& e) {
    fail(std::string("CGAL failed: ") + e.what());
  }

  FILE* fo = std::fopen(opt.output.c_str(), "w");
  if (!fo) fail("cannot write " + opt.output);
  std::fprintf(fo,
               "# {\"faces\": %zu, \"clusters\": %ld, \"lambda\": %.17g, \"segments\": %zu, "
               "\"source\": \"%s\", \"sdf_seconds\": %.6f, \"postprocess_seconds\": %.6f, "
               "\"cluster_seconds\": %.6f, \"segmentation_seconds\": %.6f, "
               "\"segmentation_cpu_seconds\": %.6f}\n",
               faces, opt.clusters, opt.lambda, segments,
               opt.values.empty() ? "sdf_values" : "values", sdf_seconds, postprocess_seconds,
               cluster_seconds, segmentation_seconds, segmentation_cpu_seconds);
  for (size_t i = 0; i < faces; ++i) {
    const Face_index f(static_cast<Mesh::size_type>(i));
    std::fprintf(fo, "%.17g %zu %zu\n", sdf[f], cluster[f], segment[f]);
  }
  if (std::fclose(fo) != 0) fail("error writing " + opt.output);
  return 0;
}
