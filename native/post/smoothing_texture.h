// SPDX-License-Identifier: GPL-3.0-or-later
// Smoothing in texture space (paper 4.4, third method): the values are drawn into the mesh's
// UV layout, the image is blurred, and the values are read back.
//
// 1. Islands: faces that share a corner (same merged vertex, same UV) belong to one UV island.
// 2. Rasterise: every texel whose centre lies in a face's UV triangle takes the face's value
//    (face values) or the value interpolated from its corners (vertex values), and the face's
//    island. A face too small to cover any texel centre writes the texel under its UV centroid
//    if that one is still empty. Where UV triangles overlap, the later face wins.
// 3. Dilate: `margin` rings of empty texels around the islands take the mean of their
//    neighbours of one island (a bake margin, and room for bilinear reads at island borders).
// 4. Blur: a Gaussian of deviation radius / 2, cut at `radius` texels, run as two 1-D passes.
//    Only texels of the centre texel's island count, empty texels never do, and the weights
//    are renormalised over what counts: nothing crosses from one island to another, however
//    close they are, and borders do not darken. Optional bilateral weights exp(-1/2 (dv /
//    range)^2) on the value difference, per pass (the separable bilateral approximation of
//    Pham and van Vliet 2005).
// 5. Read back: a face takes the mean of the blurred texels it covers (of its own island); a
//    vertex takes the mean over its corners of a bilinear read at the corner's UV (taps of the
//    corner's island only).
//
// Texel (x, y) covers u in [x / width, (x + 1) / width), v in [y / height, (y + 1) / height):
// row 0 is at v = 0, the bottom of the image, as in Blender's Image.pixels. UVs outside [0, 1]
// are clipped; a face with no texel inside the image keeps its value.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "mesh/mesh.h"
#include "post/uv_islands.h"
#include "prepare/sampling.h"
#include "util/parallel.h"
#include "util/stopwatch.h"

namespace sdf {

struct TextureOptions {
  int width = 1024;  // texels
  int height = 1024;
  // Blur reach in texels; < 0: 2 * max(width, height) / 256 (paper 4.4: "we set the radius to
  // 2 for a 256x256 texture and multiply as necessary"), 8 at 1024. 0: no blur.
  double radius = -1.0;
  bool bilateral = false;
  double range_sigma = 0.1;      // bilateral: deviation of the value weight, times (max - min)
  int margin = 2;                // texels of dilation around each island
  double weld_tolerance = 1e-6;  // relative to the largest bounding-box side; < 0: no merging
  unsigned threads = 0;          // 0: every core
};

// One UDIM tile's image (smoothing_texture_pages.h), as TextureSmoothing's image and mask.
struct TextureTile {
  int tile = 1001;
  std::vector<float> image;
  std::vector<std::uint8_t> mask;
  int width = 0, height = 0;
};

struct TextureSmoothing {
  std::vector<float> values;  // per face or vertex, like the input, within its [min, max]
  // The blurred image, width x height, row-major from row 0 (v = 0), 0 where empty; and
  // per texel 1 where it holds a value (a face or the dilated margin), else 0.
  std::vector<float> image;
  std::vector<std::uint8_t> mask;
  int width = 0, height = 0;
  // Seconds per stage, in order (checks, islands, rasterise, dilate and blur, read back, image;
  // on a device, its own stages in place of the middle three): bench/smoothing_stages.py
  // prints them.
  StageTimings timings;
  // Faces whose UVs lie wholly outside the [0, 1] square (UDIM tiles, offset layouts): they
  // cover no texel and keep their values.
  std::size_t faces_outside = 0;
  // Set by smooth_texture_pages (uv_layout.h): faces reaching beyond their tile, faces
  // overlapping another island's, the pages drawn, and each tile's image (keep_image; the
  // image and mask above then stay empty). faces_outside: faces in no tile there.
  std::size_t faces_spanning = 0;
  std::size_t faces_overlapping = 0;
  bool overlaps_unparted = false;  // UVs overlapping everywhere, drawn as laid out (uv_layout.h)
  std::size_t pages = 0;
  std::vector<TextureTile> tiles;
  // A device was given, but a face whose UV box covers more than kMostTexelsPerDeviceFace
  // texels kept the work on the CPU threads (same values, a device's speed lost).
  bool kept_off_device = false;
};

// Vertex values' read-back averages each merged vertex's corners (the copies of a vertex
// split at a UV seam get one value): the corners grouped by merged vertex, each group in face
// order, the order the sums run in on the host and on a device.
struct CornerGroups {
  std::vector<std::uint32_t> first;            // per group k, where its corners start; k + 1 ends
  UninitializedVector<std::uint32_t> corners;  // 3 f + c for corner c of face f
};
// Groups by islands.merged (each vertex its own group when it is empty).
CornerGroups group_corners(const Mesh& mesh, const UvIslands& islands, unsigned threads);

// Steps 3 and 4 (dilate, blur) of one image, as smooth_texture runs them.
struct TextureFilter {
  int width = 0, height = 0;
  int margin = 0;              // rings of dilation
  int taps = 0;                // blur reach in texels; 0: no blur
  std::vector<float> kernel;   // taps + 1 Gaussian weights, kernel[|offset|]
  float inv_range = 0.0f;      // bilateral: 1 / the value deviation; 0: plain Gaussian
  float lo = 0.0f, hi = 0.0f;  // the input's range: blurred texels are clamped to it
};
// Steps 2 to 5 on another device (the OpenCL engine), after the host's step 1.
struct TextureJob {
  const Mesh* mesh = nullptr;
  PointKind kind = PointKind::Faces;
  const float* values = nullptr;  // per face or vertex, as given to smooth_texture
  const float* uvs = nullptr;     // 6 floats a face
  const std::int32_t* face_island = nullptr;
  const UvIslands* islands = nullptr;    // vertex values: their merged vertices ...
  const CornerGroups* groups = nullptr;  // ... and corners grouped by them
  TextureFilter filter;                  // sizes, dilation, blur, the values' range
  unsigned threads = 0;                  // host threads the device's uploads may copy on
};
// Draws, dilates, blurs and reads back into `values` (n floats, each written; the input is
// job.values), with the CPU's code (kernels/smooth/sdf_smooth_texture.h) and bits. Where `images`
// is true it also fills `island` (dilated) and `blurred`, row-major: the kept image. Appends its
// stages' seconds to `timings`. A device walks each face in one work item, so smooth_texture runs
// it only where no face's UV box covers more than kMostTexelsPerDeviceFace texels (a low-poly
// mesh on a large texture stays on the CPU threads, with the same values).
using TextureDeviceFn = std::function<void(const TextureJob& job, bool images, float* values,
                                           std::vector<std::int32_t>& island,
                                           std::vector<float>& blurred, StageTimings& timings)>;
constexpr double kMostTexelsPerDeviceFace = 65536.0;

// uvs: per face corner, (u, v) for corners 0, 1, 2 of face 0, then face 1, ... (6 floats a
// face), finite. keep_image: fill image and mask (else they stay empty). Throws
// std::invalid_argument for bad options, non-finite values or UVs. device: null runs
// steps 2 to 5 on the CPU threads. into: where given (one float per point, not overlapping
// values), the smoothed values go there and TextureSmoothing::values stays empty (the
// Python binding's own array: no copy of a result that was 4 ms of page faults at 1.5M).
TextureSmoothing smooth_texture(const Mesh& mesh, PointKind kind, const float* values,
                                const float* uvs, const TextureOptions& options, bool keep_image,
                                const ProgressFn& progress = nullptr, double progress_from = 0.0,
                                double progress_to = 1.0, const TextureDeviceFn& device = nullptr,
                                float* into = nullptr);

// As above, on UV islands (and, for vertex values, corner groups) made already for these
// faces, with other UVs: a page of a UDIM or layered layout (smoothing_texture_pages.h), whose
// faces keep the whole layout's islands (others', moved out of the square, draw nothing). On
// the CPU threads. Throws as above, and where vertex values come without groups.
TextureSmoothing smooth_texture_on_islands(const Mesh& mesh, PointKind kind, const float* values,
                                           const float* uvs, const UvIslands& islands,
                                           const CornerGroups* groups,
                                           const TextureOptions& options, bool keep_image,
                                           const ProgressFn& progress, float* into);

// What texture smoothing needs of the mesh and its UVs alone, made ahead of the values:
// compute() makes it while a device casts, when the host would only wait. The mesh, the UVs
// (checked; not copied: 36 MB at 1.5M faces took 20 ms of page faults and copying), their
// UV islands (step 1), and the most texels a face's UV box covers at width x height (a
// device walks one face per work item).
struct PreparedTexture {
  Mesh mesh;
  const float* uvs = nullptr;        // 6 floats a face, owned by the caller or by `keep`
  std::shared_ptr<const void> keep;  // what keeps `uvs` alive, if the caller set it
  UvIslands islands;
  CornerGroups groups;  // made for vertex values (need_merged) only
  int width = 0, height = 0;
  double largest_face_texels = 0.0;
  std::size_t faces_outside = 0;  // as TextureSmoothing::faces_outside
  // What an engine made of them on a device (opencl_smoothing.h), released with this.
  std::shared_ptr<void> on_device;
  StageTimings timings;  // seconds per step of the preparation (and of the uploads)
};

// The checks smooth_texture starts with: the size, the face count, and m faces' UVs finite.
// Throws std::invalid_argument naming the problem.
void check_texture_input(const float* uvs, std::size_t m, const TextureOptions& options);

// options' width, height, weld_tolerance and threads are used; need_merged: for vertex
// values. uvs must stay alive and unchanged while the result is used (set its `keep` to
// what owns them). islands: found already for these faces and UVs (uv_plan.h; copied), or
// null. Throws std::invalid_argument for non-finite UVs or a bad size.
PreparedTexture prepare_texture(Mesh mesh, const float* uvs, const TextureOptions& options,
                                bool need_merged, const UvIslands* islands = nullptr);

// As above on a prepared mesh and UVs. Throws std::invalid_argument where options ask for
// another size or weld tolerance than `prepared` was made for, or for vertex values when it
// was not made for them.
TextureSmoothing smooth_texture(const PreparedTexture& prepared, PointKind kind,
                                const float* values, const TextureOptions& options, bool keep_image,
                                const ProgressFn& progress = nullptr, double progress_from = 0.0,
                                double progress_to = 1.0, const TextureDeviceFn& device = nullptr,
                                float* into = nullptr);

}  // namespace sdf
