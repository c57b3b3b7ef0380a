// SPDX-License-Identifier: GPL-3.0-or-later
//
// OFF reading and CGAL::Surface_mesh building shared by the CGAL reference programs
// (test/benchmark references only, never part of the product).
//
// The mesh is built with add_vertex/add_face in file order rather than with CGAL's
// OFF reader, so that face i of the file is face i of the Surface_mesh even when
// some faces are refused (the reader would fail on the whole file instead).
#pragma once

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace reference {

typedef CGAL::Exact_predicates_inexact_constructions_kernel Kernel;
typedef Kernel::Point_3 Point;
typedef CGAL::Surface_mesh<Point> Mesh;
typedef Mesh::Vertex_index Vertex_index;
typedef Mesh::Face_index Face_index;

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

inline double to_double(const std::string& tok, const Token_reader& r) {
  char* end = nullptr;
  double v = std::strtod(tok.c_str(), &end);
  if (end == tok.c_str() || *end != '\0')
    throw std::runtime_error("bad number '" + tok + "' on line " + std::to_string(r.line_number()));
  return v;
}

inline long long to_integer(const std::string& tok, const Token_reader& r) {
  char* end = nullptr;
  long long v = std::strtoll(tok.c_str(), &end, 10);
  if (end == tok.c_str() || *end != '\0')
    throw std::runtime_error("bad integer '" + tok + "' on line " +
                             std::to_string(r.line_number()));
  return v;
}

struct Off_mesh {
  std::vector<double> xyz;                    // 3 per vertex
  std::vector<std::vector<long long>> faces;  // indices as written in the file
};

// The OFF file's vertices and faces; throws std::runtime_error saying what is wrong.
inline Off_mesh read_off(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot open " + path);
  Token_reader r(in);
  std::string tok;
  if (!r.next(tok)) throw std::runtime_error(path + ": empty file");
  // Accept "OFF" and its plain variants; the counts may follow on the same line.
  if (tok.size() < 3 || tok.compare(tok.size() - 3, 3, "OFF") != 0)
    throw std::runtime_error(path + ": not an OFF file (header '" + tok + "')");
  if (tok != "OFF" && tok != "COFF" && tok != "NOFF" && tok != "CNOFF")
    throw std::runtime_error(path + ": unsupported OFF variant '" + tok + "'");
  std::string a, b, c;
  if (!r.next(a) || !r.next(b) || !r.next(c)) throw std::runtime_error(path + ": missing counts");
  const long long nv = to_integer(a, r), nf = to_integer(b, r);
  (void)to_integer(c, r);
  if (nv < 0 || nf < 0) throw std::runtime_error(path + ": negative counts");

  Off_mesh m;
  m.xyz.reserve(3 * static_cast<size_t>(nv));
  for (long long i = 0; i < nv; ++i) {
    for (int k = 0; k < 3; ++k) {
      if (!r.next(tok)) throw std::runtime_error(path + ": file ends inside the vertex list");
      m.xyz.push_back(to_double(tok, r));
    }
    r.skip_line();  // normals / colours, if any
  }
  m.faces.resize(static_cast<size_t>(nf));
  for (long long i = 0; i < nf; ++i) {
    if (!r.next(tok)) throw std::runtime_error(path + ": file ends inside the face list");
    const long long n = to_integer(tok, r);
    if (n < 0) throw std::runtime_error(path + ": negative face size");
    std::vector<long long>& f = m.faces[static_cast<size_t>(i)];
    f.reserve(static_cast<size_t>(n));
    for (long long k = 0; k < n; ++k) {
      if (!r.next(tok)) throw std::runtime_error(path + ": file ends inside the face list");
      f.push_back(to_integer(tok, r));
    }
    r.skip_line();  // colours, if any
  }
  return m;
}

// The Surface_mesh of an OFF mesh, built in file order.
struct Built_mesh {
  Mesh mesh;
  std::vector<Face_index> face_of;  // file face index -> mesh face (null_face() where refused)
  size_t refused = 0;               // faces not in the mesh
  size_t split = 0;                 // faces added as detached triangles
};

// A face that add_face refuses (not a triangle, a repeated or out-of-range index, or, without
// split_nonmanifold, a non-manifold configuration) is left out. With split_nonmanifold a
// triangle refused for making a non-manifold vertex or edge is added instead on its own copies
// of its three vertices (as CGAL's polygon-soup repair also duplicates such vertices).
inline Built_mesh build_surface_mesh(const Off_mesh& off, bool split_nonmanifold) {
  const size_t nv = off.xyz.size() / 3;
  Built_mesh b;
  b.mesh.reserve(static_cast<Mesh::size_type>(nv),
                 static_cast<Mesh::size_type>(3 * off.faces.size()),
                 static_cast<Mesh::size_type>(off.faces.size()));
  for (size_t i = 0; i < nv; ++i)
    b.mesh.add_vertex(Point(off.xyz[3 * i], off.xyz[3 * i + 1], off.xyz[3 * i + 2]));

  b.face_of.assign(off.faces.size(), Mesh::null_face());
  for (size_t i = 0; i < off.faces.size(); ++i) {
    const std::vector<long long>& f = off.faces[i];
    bool ok = f.size() == 3;
    for (size_t k = 0; ok && k < 3; ++k) ok = f[k] >= 0 && static_cast<size_t>(f[k]) < nv;
    ok = ok && f[0] != f[1] && f[1] != f[2] && f[0] != f[2];
    if (ok) {
      Vertex_index v[3];
      for (int k = 0; k < 3; ++k) v[k] = Vertex_index(static_cast<Mesh::size_type>(f[k]));
      b.face_of[i] = b.mesh.add_face(v[0], v[1], v[2]);
      if (b.face_of[i] == Mesh::null_face() && split_nonmanifold) {
        Vertex_index copy[3];
        for (int k = 0; k < 3; ++k) copy[k] = b.mesh.add_vertex(b.mesh.point(v[k]));
        b.face_of[i] = b.mesh.add_face(copy[0], copy[1], copy[2]);
        if (b.face_of[i] != Mesh::null_face()) ++b.split;
      }
    }
    if (b.face_of[i] == Mesh::null_face()) ++b.refused;
  }
  return b;
}

}  // namespace reference
