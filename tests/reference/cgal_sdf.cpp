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
// The mesh is built with add_vertex/add_face in file order rather than with
// CGAL's OFF reader, so that face i of the file is face i of the output even when
// some faces are refused (the reader would fail on the whole file instead).
// With Surface_mesh::add_face(v0, v1, v2), halfedge(f) points to v0, so CGAL's
// SDF code sees p1 = v0, p2 = v1, p3 = v2 and uses the inward normal
// normal(p2, p1, p3) = cross(v0 - v1, v2 - v1).
//
// stderr gets one line "cgal_sdf: sdf_values took <seconds> s ..." with the wall
// time of the sdf_values() call alone (no I/O, no mesh building).

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/mesh_segmentation.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <fstream>
#include <iostream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

typedef CGAL::Exact_predicates_inexact_constructions_kernel Kernel;
typedef Kernel::Point_3 Point;
typedef CGAL::Surface_mesh<Point> Mesh;
typedef Mesh::Vertex_index Vertex_index;
typedef Mesh::Face_index Face_index;

namespace {

// Reads whitespace-separated tokens from an OFF file, dropping '#' comments.
class Token_reader {
 public:
  explicit Token_reader(std::istream& in) : in_(in) {}

  // Next token of the file; false at end of file.
  bool next(std::string& tok) {
    while (true) {
      if (line_.good()) {
        if (line_ >> tok) return true;
      }
      std::string raw;
      if (!std::getline(in_, raw)) return false;
      ++line_number_;
      std::string::size_type hash = raw.find('#');
      if (hash != std::string::npos) raw.erase(hash);
      line_.clear();
      line_.str(raw);
    }
  }

  // Rest of the current line (used to skip per-face/per-vertex colours).
  void skip_line() {
    line_.clear();
    line_.str(std::string());
  }

  long line_number() const { return line_number_; }

 private:
  std::istream& in_;
  std::istringstream line_;
  long line_number_ = 0;
};

[[noreturn]] void fail(const std::string& msg) {
  std::cerr << "cgal_sdf: error: " << msg << "\n";
  std::exit(2);
}

double to_double(const std::string& tok, const Token_reader& r) {
  char* end = nullptr;
  double v = std::strtod(tok.c_str(), &end);
  if (end == tok.c_str() || *end != '\0')
    fail("bad number '" + tok + "' on line " + std::to_string(r.line_number()));
  return v;
}

long long to_integer(const std::string& tok, const Token_reader& r) {
  char* end = nullptr;
  long long v = std::strtoll(tok.c_str(), &end, 10);
  if (end == tok.c_str() || *end != '\0')
    fail("bad integer '" + tok + "' on line " + std::to_string(r.line_number()));
  return v;
}

struct Off_mesh {
  std::vector<double> xyz;                  // 3 per vertex
  std::vector<std::vector<long long>> faces;  // indices as written in the file
};

Off_mesh read_off(const char* path) {
  std::ifstream in(path);
  if (!in) fail(std::string("cannot open ") + path);
  Token_reader r(in);
  std::string tok;
  if (!r.next(tok)) fail(std::string(path) + ": empty file");
  // Accept "OFF" and its plain variants; the counts may follow on the same line.
  if (tok.size() < 3 || tok.compare(tok.size() - 3, 3, "OFF") != 0)
    fail(std::string(path) + ": not an OFF file (header '" + tok + "')");
  if (tok != "OFF" && tok != "COFF" && tok != "NOFF" && tok != "CNOFF")
    fail(std::string(path) + ": unsupported OFF variant '" + tok + "'");
  std::string a, b, c;
  if (!r.next(a) || !r.next(b) || !r.next(c)) fail(std::string(path) + ": missing counts");
  const long long nv = to_integer(a, r), nf = to_integer(b, r);
  (void)to_integer(c, r);
  if (nv < 0 || nf < 0) fail(std::string(path) + ": negative counts");

  Off_mesh m;
  m.xyz.reserve(3 * static_cast<size_t>(nv));
  for (long long i = 0; i < nv; ++i) {
    for (int k = 0; k < 3; ++k) {
      if (!r.next(tok)) fail(std::string(path) + ": file ends inside the vertex list");
      m.xyz.push_back(to_double(tok, r));
    }
    r.skip_line();  // normals / colours, if any
  }
  m.faces.resize(static_cast<size_t>(nf));
  for (long long i = 0; i < nf; ++i) {
    if (!r.next(tok)) fail(std::string(path) + ": file ends inside the face list");
    const long long n = to_integer(tok, r);
    if (n < 0) fail(std::string(path) + ": negative face size");
    std::vector<long long>& f = m.faces[static_cast<size_t>(i)];
    f.reserve(static_cast<size_t>(n));
    for (long long k = 0; k < n; ++k) {
      if (!r.next(tok)) fail(std::string(path) + ": file ends inside the face list");
      f.push_back(to_integer(tok, r));
    }
    r.skip_line();  // colours, if any
  }
  return m;
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

  const Off_mesh off = read_off(pos[0].c_str());
  const size_t nv = off.xyz.size() / 3;

  Mesh mesh;
  mesh.reserve(static_cast<Mesh::size_type>(nv), static_cast<Mesh::size_type>(3 * off.faces.size()),
               static_cast<Mesh::size_type>(off.faces.size()));
  for (size_t i = 0; i < nv; ++i)
    mesh.add_vertex(Point(off.xyz[3 * i], off.xyz[3 * i + 1], off.xyz[3 * i + 2]));

  // file face index -> Surface_mesh face (null_face() where refused)
  std::vector<Face_index> face_of(off.faces.size(), Mesh::null_face());
  size_t refused = 0, split = 0;
  for (size_t i = 0; i < off.faces.size(); ++i) {
    const std::vector<long long>& f = off.faces[i];
    bool ok = f.size() == 3;
    for (size_t k = 0; ok && k < 3; ++k) ok = f[k] >= 0 && static_cast<size_t>(f[k]) < nv;
    ok = ok && f[0] != f[1] && f[1] != f[2] && f[0] != f[2];
    if (ok) {
      face_of[i] = mesh.add_face(Vertex_index(static_cast<Mesh::size_type>(f[0])),
                                 Vertex_index(static_cast<Mesh::size_type>(f[1])),
                                 Vertex_index(static_cast<Mesh::size_type>(f[2])));
      if (face_of[i] == Mesh::null_face() && split_nonmanifold) {
        Vertex_index copy[3];
        for (int k = 0; k < 3; ++k)
          copy[k] = mesh.add_vertex(mesh.point(Vertex_index(static_cast<Mesh::size_type>(f[k]))));
        face_of[i] = mesh.add_face(copy[0], copy[1], copy[2]);
        if (face_of[i] != Mesh::null_face()) ++split;
      }
    }
    if (face_of[i] == Mesh::null_face()) ++refused;
  }
  if (split)
    std::cerr << "cgal_sdf: " << split << " of " << off.faces.size()
              << " faces were non-manifold and were added as detached triangles\n";
  if (refused)
    std::cerr << "cgal_sdf: " << refused << " of " << off.faces.size()
              << " faces could not be added to the Surface_mesh; written as nan\n";

  std::vector<double> out(off.faces.size(), std::numeric_limits<double>::quiet_NaN());
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
    for (size_t i = 0; i < off.faces.size(); ++i)
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

  std::fprintf(stderr,
               "cgal_sdf: sdf_values took %.6f s (faces=%zu rays=%ld postprocess=%d, %.3f Mrays/s)\n",
               seconds, static_cast<size_t>(mesh.number_of_faces()), rays, postprocess ? 1 : 0,
               seconds > 0 ? mesh.number_of_faces() * static_cast<double>(rays) / seconds / 1e6 : 0.0);
  return 0;
}
