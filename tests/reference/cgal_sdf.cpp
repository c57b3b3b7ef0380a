// SPDX-License-Identifier: GPL-3.0-or-later
//
// cgal_sdf -- reference Shape Diameter Function values from CGAL's sdf_values().
//
// This program is a TEST/BENCHMARK REFERENCE ONLY. It is never linked into the
// Shape Diameter product; the Python tests (tests/python/test_against_cgal.py) and
// the benchmarks run it as a separate executable and compare its output with
// shape_diameter.compute(). It links CGAL (GPL), hence the licence above.
//
// Usage:  cgal_sdf IN.off RAYS OUT.txt [--postprocess] [--split-nonmanifold]
//
//   IN.off   triangle mesh in OFF format (vertices, then faces "3 a b c").
//   RAYS     number of rays per facet (CGAL default is 25).
//   OUT.txt  one value per line, one line per face of IN.off, in file order:
//              the SDF value of that face (mesh units unless --postprocess),
//              -1   where CGAL found no valid ray (CGAL's own marker; degenerate
//                   facets get it too),
//              nan  where the face could not be put into the CGAL::Surface_mesh
//                   (not a triangle, repeated/out-of-range vertex index, or, without
//                   --split-nonmanifold, a non-manifold configuration that
//                   Surface_mesh::add_face refuses).
//   --postprocess  pass postprocess=true to sdf_values (fill -1 facets, bilateral
//                  smoothing, linear normalisation to [0,1]); default false.
//   --split-nonmanifold  a triangle that add_face refuses (it would make a
//                  non-manifold vertex or edge) is added instead as a detached
//                  triangle on its own copies of its three vertices. The geometry
//                  CGAL casts rays against is then the file's, so raw values are
//                  what CGAL computes on the whole surface (as after CGAL's own
//                  polygon-soup repair, which also duplicates such vertices);
//                  only postprocess, which smooths over edge neighbours, sees
//                  the detached faces differently. Without it, refused faces are
//                  missing from CGAL's geometry (holes) and written as nan.
//
// The cone angle is CGAL's default, 2/3*pi (120 degrees). The kernel is
// Exact_predicates_inexact_constructions_kernel.
//
// The mesh is built in file order (off_mesh.h), so that face i of the file is
// face i of the output even when some faces are refused.
// With Surface_mesh::add_face(v0, v1, v2), halfedge(f) points to v0, so CGAL's
// SDF code sees p1 = v0, p2 = v1, p3 = v2 and uses the inward normal
// normal(p2, p1, p3) = cross(v0 - v1, v2 - v1).
//
// stderr gets one line "cgal_sdf: sdf_values took <seconds> s ..." with the wall
// time of the sdf_values() call alone (no I/O, no mesh building).

#include <CGAL/mesh_segmentation.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <iostream>
#include <limits>
#include <string>
#include <vector>

#include "off_mesh.h"

using reference::Face_index;
using reference::Mesh;

namespace {

[[noreturn]] void fail(const std::string& msg) {
  std::cerr << "cgal_sdf: error: " << msg << "\n";
  std::exit(2);
}

}  // namespace

int main(int argc, char** argv) {
  bool postprocess = false;
  bool split_nonmanifold = false;
  std::vector<std::string> pos;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--postprocess") == 0)
      postprocess = true;
    else if (std::strcmp(argv[i], "--split-nonmanifold") == 0)
      split_nonmanifold = true;
    else
      pos.push_back(argv[i]);
  }
  if (pos.size() != 3) {
    std::cerr << "usage: cgal_sdf IN.off RAYS OUT.txt [--postprocess] [--split-nonmanifold]\n";
    return 2;
  }
  char* end = nullptr;
  const long rays = std::strtol(pos[1].c_str(), &end, 10);
  if (end == pos[1].c_str() || *end != '\0' || rays < 1) fail("RAYS must be a positive integer");

  reference::Built_mesh built;
  try {
    built = reference::build_surface_mesh(reference::read_off(pos[0]), split_nonmanifold);
  } catch (const std::exception& e) {
    fail(e.what());
  }
  Mesh& mesh = built.mesh;
  const std::vector<Face_index>& face_of = built.face_of;
  const size_t refused = built.refused, split = built.split;
  if (split)
    std::cerr << "cgal_sdf: " << split << " of " << face_of.size()
              << " faces were non-manifold and were added as detached triangles\n";
  if (refused)
    std::cerr << "cgal_sdf: " << refused << " of " << face_of.size()
              << " faces could not be added to the Surface_mesh; written as nan\n";

  std::vector<double> out(face_of.size(), std::numeric_limits<double>::quiet_NaN());
  double seconds = 0.0;
  if (mesh.number_of_faces() > 0) {
    typedef Mesh::Property_map<Face_index, double> Facet_double_map;
    Facet_double_map sdf = mesh.add_property_map<Face_index, double>("f:sdf", -1.0).first;
    try {
      const auto t0 = std::chrono::steady_clock::now();
      CGAL::sdf_values(mesh, sdf, 2.0 / 3.0 * CGAL_PI, static_cast<std::size_t>(rays), postprocess);
      const auto t1 = std::chrono::steady_clock::now();
      seconds = std::chrono::duration<double>(t1 - t0).count();
    } catch (const std::exception& e) {
      fail(std::string("sdf_values failed: ") + e.what());
    }
    for (size_t i = 0; i < face_of.size(); ++i)
      if (face_of[i] != Mesh::null_face()) out[i] = sdf[face_of[i]];
  }

  FILE* fo = std::fopen(pos[2].c_str(), "w");
  if (!fo) fail("cannot write " + pos[2]);
  for (double v : out) {
    if (std::isnan(v))
      std::fputs("nan\n", fo);
    else
      std::fprintf(fo, "%.17g\n", v);
  }
  if (std::fclose(fo) != 0) fail("error writing " + pos[2]);

  std::fprintf(
      stderr,
      "cgal_sdf: sdf_values took %.6f s (faces=%zu rays=%ld postprocess=%d, %.3f Mrays/s)\n",
      seconds, static_cast<size_t>(mesh.number_of_faces()), rays, postprocess ? 1 : 0,
      seconds > 0 ? mesh.number_of_faces() * static_cast<double>(rays) / seconds / 1e6 : 0.0);
  return 0;
}
