// SPDX-License-Identifier: GPL-3.0-or-later
// The OpenCL version of texture-space smoothing (paper 4.4; projected points:
// opencl_projected.h): the UV islands (and for vertex values the corners grouped by merged
// vertex) are found on the host; drawing, dilation, both blur passes and reading the values
// back run on the device. The device code is kernels/smooth/sdf_smooth_texture.h, which the CPU
// version runs as C++, so the results agree with the CPU's to float rounding (exp); on a
// device without double precision texture smoothing runs on the CPU threads, since drawing
// needs double.
#pragma once

#include <vector>

#include "devices.h"
#include "post/smoothing_texture.h"

namespace sdf::cl {

// As sdf::smooth_texture, on `device` (throws Error for OpenCL failures, also when the
// images do not fit the device).
TextureSmoothing smooth_texture_opencl(const Device& device, const Mesh& mesh, PointKind kind,
                                       const float* values, const float* uvs,
                                       const TextureOptions& options, bool keep_image,
                                       const ProgressFn& progress = nullptr, float* into = nullptr);

// The same on a prepared texture, reading its UVs and islands on the device where
// upload_prepared_texture put them there.
TextureSmoothing smooth_texture_opencl(const Device& device, const PreparedTexture& prepared,
                                       PointKind kind, const float* values,
                                       const TextureOptions& options, bool keep_image,
                                       const ProgressFn& progress = nullptr, float* into = nullptr);

// Uploads the prepared UVs and face islands to `device` on a queue of the device's own beside
// the one that casts (compute() calls it while the device casts), and keeps them in
// prepared.on_device. Returns false, doing nothing, where texture smoothing would not run on
// the device (no double precision, faces spanning more than 2^16 texels) or they would take
// more than a quarter of its memory. threads: the host threads that may copy into pinned
// memory (0: every core, at most 8). Throws Error for OpenCL failures.
bool upload_prepared_texture(const Device& device, PreparedTexture& prepared, unsigned threads = 0);

}  // namespace sdf::cl
