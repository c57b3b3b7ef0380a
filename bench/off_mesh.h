// SPDX-License-Identifier: GPL-3.0-or-later
// Benchmark meshes as bench/meshes.py makes them: a triangle OFF file read in double precision,
// optionally subdivided 1-to-4 at edge midpoints (the same triangles in the same order as
// meshes.py's subdivide; its new vertices are numbered differently), then the core's mesh of
// it. Benchmark code only.
#pragma once

#include <cstdint>
#include <fstream>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "mesh/mesh.h"

namespace bench {

struct OffMesh {
  std::vector<double> v;        // x, y, z per vertex
  std::vector<std::int64_t> f;  // a, b, c per triangle
};

inline OffMesh read_off_mesh(const std::string& path) {
  std::ifstream in(path);
  std::string magic;
  std::size_t nv = 0, nf = 0, ne = 0;
  in >> magic >> nv >> nf >> ne;
  if (!in || magic != "OFF") throw std::runtime_error(path + " is not an OFF file");
  OffMesh m;
  m.v.resize(3 * nv);
  for (double& x : m.v) in >> x;
  m.f.resize(3 * nf);
  for (std::size_t i = 0; i < nf; ++i) {
    int corners = 0;
    in >> corners >> m.f[3 * i] >> m.f[3 * i + 1] >> m.f[3 * i + 2];
    if (corners != 3) throw std::runtime_error(path + " has faces that are not triangles");
  }
  if (!in) throw std::runtime_error("cannot read the OFF triangles of " + path);
  return m;
}

// 1-to-4 midpoint subdivision: faces (a, ab, ca), then (ab, b, bc), (ca, bc, c), (ab, bc, ca)
// in four blocks, as meshes.py concatenates them; each edge's midpoint is made once.
inline OffMesh subdivide(const OffMesh& m) {
  const std::size_t nf = m.f.size() / 3;
  OffMesh out;
  out.v = m.v;
  std::map<std::pair<std::int64_t, std::int64_t>, std::int64_t> midpoints;
  auto midpoint = [&](std::int64_t a, std::int64_t b) {
    const auto key = std::make_pair(std::min(a, b), std::max(a, b));
    auto [it, fresh] = midpoints.emplace(key, static_cast<std::int64_t>(out.v.size() / 3));
    if (fresh)
      for (int k = 0; k < 3; ++k) out.v.push_back((m.v[3 * a + k] + m.v[3 * b + k]) / 2.0);
    return it->second;
  };
  std::vector<std::int64_t> mids(3 * nf);
  for (std::size_t i = 0; i < nf; ++i) {
    const std::int64_t* t = &m.f[3 * i];
    mids[3 * i] = midpoint(t[0], t[1]);
    mids[3 * i + 1] = midpoint(t[1], t[2]);
    mids[3 * i + 2] = midpoint(t[2], t[0]);
  }
  out.f.resize(12 * nf);
  for (std::size_t i = 0; i < nf; ++i) {
    const std::int64_t a = m.f[3 * i], b = m.f[3 * i + 1], c = m.f[3 * i + 2];
    const std::int64_t ab = mids[3 * i], bc = mids[3 * i + 1], ca = mids[3 * i + 2];
    const std::int64_t blocks[4][3] = {{a, ab, ca}, {ab, b, bc}, {ca, bc, c}, {ab, bc, ca}};
    for (int k = 0; k < 4; ++k)
      for (int j = 0; j < 3; ++j) out.f[3 * (k * nf + i) + j] = blocks[k][j];
  }
  return out;
}

inline sdf::Mesh core_mesh(const OffMesh& m) {
  return sdf::make_mesh(m.v.data(), m.v.size() / 3, m.f.data(), m.f.size() / 3);
}

}  // namespace bench
