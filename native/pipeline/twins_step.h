// SPDX-License-Identifier: GPL-3.0-or-later
// Double-sided meshes in the whole call: the mesh cast again without the faces that have a
// reversed twin (mesh/mesh_twins.h), and each of them, and each vertex only they use, given
// its twin's values afterwards.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "mesh/mesh.h"
#include "mesh/mesh_twins.h"

namespace sdf {

// The caller's mesh without the dropped faces. Vertices only they use (the back of a
// double-sided mesh on vertices of its own) are left out too, the others renumbered in order:
// k-ring smoothing merges vertices at one position, and would average their stand-in values
// into the front's.
class TwinsCut {
 public:
  // uvs: 6 floats a face of the caller's mesh, or null.
  TwinsCut(const MeshArrays& mesh, const ReversedTwins& twins, const float* uvs);

  // The mesh to cast; its arrays are this object's or the caller's (no vertex left out).
  MeshArrays mesh() const;
  const float* uvs() const { return uvs_.empty() ? nullptr : uvs_.data(); }
  std::size_t dropped() const { return twins_.dropped.size(); }

  // Per face (faces: true) or per vertex of the cut mesh -> per face or vertex of the
  // caller's mesh, the left-out ones given their twins' values.
  template <class T>
  std::vector<T> whole(const std::vector<T>& part, bool faces) const;
  // Per face of the cut mesh -> per face of the caller's, 0 for the dropped ones.
  std::vector<std::uint8_t> whole_faces_or_zero(const std::vector<std::uint8_t>& part) const;

 private:
  MeshArrays given_;
  const ReversedTwins& twins_;
  std::vector<std::uint8_t> kept_, lonely_;  // per face; per vertex only dropped faces use
  std::vector<double> vertices_;             // empty where no vertex is left out
  std::vector<std::int64_t> triangles_;
  std::vector<float> uvs_;
};

}  // namespace sdf
