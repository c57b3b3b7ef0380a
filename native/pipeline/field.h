// SPDX-License-Identifier: GPL-3.0-or-later
// The whole call, as shape_diameter.compute() makes it: the SDF cast (sdf.h), the mesh cast
// again without faces that have a reversed twin (twins_step.h), the field smoothed
// (smoothing_step.h), the twins given their values, the field normalised; where the caller
// allows it, an OpenCL device's failure runs the stage again on the CPU.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "mesh/mesh.h"
#include "pipeline/sdf.h"
#include "pipeline/smoothing_step.h"
#include "post/normalize.h"

namespace sdf {

struct FieldOptions {
  Options cast;                   // cast.engine runs the cast and the smoothing
  bool fall_back_to_cpu = false;  // an OpenCL failure (cl::Error) runs the stage on the CPU
  SmoothingOptions smoothing;     // smoothing.threads is cast.threads
  const float* uvs = nullptr;     // texture smoothing's: 6 floats a face
  Normalization normalize = Normalization::Linear;
};

struct Field {
  // The cast of the mesh (without its twin faces, where it has some), its raw, valid_rays and
  // orientation.reversed made whole (per face or vertex of the caller's mesh); timings hold
  // the whole call's stages ('smooth', 'twins (first run)', ...).
  Output cast;
  std::vector<float> values;       // smoothed (raw where no smoothing was asked)
  std::vector<float> normalized;   // of values
  std::string fallback;            // '<what> failed: <why>' where the CPU ran instead; or empty
  std::size_t twin_faces = 0;      // faces given their twins' values
  std::size_t smoothed_faces = 0;  // faces the smoothing ran on
  // Texture smoothing (smoothing_step.h's Smoothed): faces in no UDIM tile (left out), faces
  // overlapping another UV island's (smoothed apart), the pages drawn.
  std::size_t texture_faces_outside = 0;
  std::size_t texture_faces_overlapping = 0;
  bool texture_overlaps_unparted = false;
  std::size_t texture_pages = 0;
  bool texture_kept_off_device = false;  // texture smoothing: the device was not used
};

// mesh: checked by the caller as make_mesh does (std::invalid_argument otherwise). Progress
// runs from 0 to 1 and never back (the cast 0 to 0.9 with smoothing), and can cancel.
Field compute_field(const MeshArrays& mesh, const FieldOptions& options,
                    const ProgressFn& progress = nullptr);

}  // namespace sdf
