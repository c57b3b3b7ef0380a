// SPDX-License-Identifier: GPL-3.0-or-later
// Texture smoothing of a UV layout on several pages (uv_layout.h): UDIM tiles, and within a
// tile, layers that part overlapping UV islands. Each page is drawn, blurred and read back as
// an image of its own (smooth_texture, or a device's code), one after another, with its faces
// moved into the [0, 1] square and every other face outside it; the results are read back per
// face from the page that drew it.
//
// Face values: a face takes its page's result (bit for bit what smoothing its page's faces
// alone gives, as the move into the square is exact). Vertex values: a vertex takes the mean
// over its corners of its pages' results (a page's result at a vertex being the mean of its
// corners there), so a vertex on a tile border, or shared by overlapping islands, joins both
// sides as a one-image layout would. Faces of no tile, and vertices of none of the drawn
// faces, keep their values.
//
// Images: one per tile, width x height; the layers of a tile are laid over each other in
// order (a later layer's texels, where it holds a value, over the earlier ones'), as one
// image holds overlapping islands.
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "post/smoothing_texture.h"
#include "post/uv_layout.h"

namespace sdf {

// One page as one image: uvs (6 floats a face, the page's faces in [0, 1]); progress from 0 to
// 1; every point's value written to `into`.
using TexturePageFn = std::function<TextureSmoothing(const float* uvs, bool keep_image,
                                                     const ProgressFn& progress, float* into)>;

// values: n per face or vertex of `mesh`; into: n floats, the result. The returned
// TextureSmoothing's values stay empty; its tiles hold the images (keep_image), its counts
// the layout's. A layout of one page in tile 1001 runs once on `uvs` as given.
TextureSmoothing smooth_texture_pages(const Mesh& mesh, PointKind kind, const float* values,
                                      const float* uvs, const UvLayout& layout, bool keep_image,
                                      unsigned threads, const ProgressFn& progress,
                                      const TexturePageFn& run_page, float* into);

}  // namespace sdf
