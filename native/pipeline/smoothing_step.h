// SPDX-License-Identifier: GPL-3.0-or-later
// The smoothing stage (paper 4.4) as the pipeline and smooth() run it: one method and its
// options, the work that needs no values (done beside the cast), and the run on the CPU or an
// OpenCL device. The methods themselves are in post/ and opencl/.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "mesh/mesh.h"
#include "post/smoothing_kring.h"
#include "post/smoothing_projected.h"
#include "post/smoothing_texture.h"
#include "post/uv_plan.h"
#include "prepare/sampling.h"
#include "util/parallel.h"
#include "util/stopwatch.h"

namespace sdf {

enum class SmoothingMethod { None, Kring, Projected, Texture, Bilateral };

struct SmoothingOptions {
  SmoothingMethod method = SmoothingMethod::None;
  KringOptions kring;
  ProjectedOptions projected;
  TextureOptions texture;
  std::size_t bilateral_window = 0;  // rings; 0: CGAL's size for the face count
  bool return_image = false;         // texture: keep the blurred image
  unsigned threads = 0;              // every method's; 0: every core
  // texture: the UV map's islands and layout, found before (uv_plan.h), or null (found here).
  std::shared_ptr<const UvPlan> uv_plan;
};

// The mesh a smoothing reads, in the caller's units. `oriented`: wound outward (projected
// points move inward, k-ring corners compare normals). `as_given` and `uvs`: texture
// smoothing's where nothing was prepared (its UVs follow the caller's corners, 6 floats a
// face). `triangles`: the faces as 0-based int64 rows (the bilateral filter's face graph).
struct SmoothingMesh {
  const Mesh* oriented = nullptr;
  const Mesh* as_given = nullptr;
  const float* uvs = nullptr;
  const std::int64_t* triangles = nullptr;
  std::size_t face_count = 0, vertex_count = 0;
};

// What a smoothing made ready before the values exist (prepare_smoothing).
struct PreparedSmoothing {
  std::shared_ptr<PreparedTexture> texture;  // texture: islands (uploaded on a device)
  std::shared_ptr<void> projected;           // projected on a device: the points' frames there
  StageTimings timings;                      // of the preparation
};

// The preparation the method can do without values, for `engine` ("cpu" or an OpenCL
// selection; "opencl:all" smooths on its first device): texture smoothing's UV islands of
// `as_given` (the mesh as the caller wound it, which it keeps) and `uvs` (6 floats a face,
// alive while the result is); projected smoothing's frames of `points` (the cast's, in the
// caller's units) uploaded to a device. Uploads that fail leave the work to the host.
PreparedSmoothing prepare_smoothing(Mesh as_given, const float* uvs, PointKind kind,
                                    const SmoothingOptions& options, const std::string& engine,
                                    const SamplePoints* points);

struct Smoothed {
  std::vector<float> values;  // one per point
  StageTimings timings;       // the method's stages
  // Texture smoothing (smoothing_texture_pages.h): faces whose UV centroid lies in no UDIM
  // tile (kept), faces reaching beyond their tile (clipped), faces overlapping another UV
  // island's (smoothed on a layer of their own), the pages drawn; whether a device was asked
  // for but the work stayed on the CPU threads; each tile's image when asked.
  std::size_t faces_outside = 0;
  std::size_t faces_spanning = 0;
  std::size_t faces_overlapping = 0;
  bool overlaps_unparted = false;
  std::size_t pages = 0;
  bool kept_off_device = false;
  std::vector<TextureTile> tiles;
};

// The method on `values` (one per point of `kind`, finite; >= 0 for projected). prepared:
// from prepare_smoothing for this mesh, options and engine, or null. Projected smoothing of a
// mesh far from unit size runs on the mesh and values scaled by a power of two, as the cast
// does (unit_scale.h), and scales back (exact). Throws std::invalid_argument for bad options,
// cl::Error for a device's failure, Cancelled when progress says stop.
Smoothed smooth_values(const SmoothingMesh& mesh, PointKind kind, const float* values,
                       const SmoothingOptions& options, const std::string& engine,
                       const PreparedSmoothing* prepared, const ProgressFn& progress);

}  // namespace sdf
