// SPDX-License-Identifier: GPL-3.0-or-later
// A UV map's islands (uv_islands.h) and layout (uv_layout.h: UDIM tiles, overlapping islands),
// found once: before the work, so that a caller can say what the layout is (faces outside
// every tile, overlapping shells) before the long part starts, and then given to texture
// smoothing, which uses them instead of finding them again.
#pragma once

#include <cstddef>
#include <cstdint>

#include "mesh/mesh.h"
#include "post/uv_islands.h"
#include "post/uv_layout.h"

namespace sdf {

struct UvPlan {
  UvIslands islands;
  UvLayout layout;
  std::size_t face_count = 0, vertex_count = 0;
  std::uint64_t uv_fingerprint = 0;  // of the UVs it was found for (uv_fingerprint)
  double seconds = 0.0;              // what finding them took
};

// uvs: 6 floats a face, finite (checked: std::invalid_argument names the first that is not).
// weld_tolerance and need_merged as for label_uv_islands (need_merged: for vertex values).
UvPlan plan_uvs(const Mesh& mesh, const float* uvs, double weld_tolerance, bool need_merged,
                unsigned threads);

// A hash of the UVs (6 floats a face): a plan given back is used only with the UVs it was
// found for, as its islands index vertices and faces of that mesh.
std::uint64_t uv_fingerprint(const float* uvs, std::size_t face_count);

// Whether `plan` was made for this mesh's counts, these UVs (null: not known, so no) and weld
// tolerance, with the merged vertices vertex values need. Texture smoothing finds the layout
// again where it was not (a double-sided mesh's second cast smooths the mesh without its twin
// faces; a plan given for another mesh).
bool plan_fits(const UvPlan& plan, std::size_t face_count, std::size_t vertex_count,
               const float* uvs, double weld_tolerance, bool need_merged);

}  // namespace sdf
