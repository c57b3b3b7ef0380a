// SPDX-License-Identifier: GPL-3.0-or-later
// Projected-points smoothing (paper 4.4) on an OpenCL device, every stage there: the points
// moved inward, the octree built level by level (kernels/cl/sdf_point_octree_kernels.cl), the
// gather. The host uploads the points' frames (origin, inward axis) once, reads a few KiB
// back per level and makes that level's nodes by the host builder's rules
// (smoothing_projected.h), so the tree is the CPU version's node for node and the values are
// its values (to the float rounding of the shared gather code on each device).
#pragma once

#include <cstddef>
#include <memory>

#include "devices.h"
#include "mesh/mesh.h"
#include "post/smoothing_projected.h"
#include "prepare/sampling.h"
#include "util/stopwatch.h"

namespace sdf::cl {

// The points' frames on a device, uploaded ahead: compute() uploads its cast's own points
// (oriented as the cast saw the mesh) while the device casts, on the device's side queue.
struct PreparedProjected {
  std::shared_ptr<void> on_device;  // the frames' buffers; null if they were not uploaded
  std::size_t count = 0;            // points
  StageTimings timings;             // of the upload
};

// Uploads points' origins and axes to `device` on its side queue (threads: host threads that
// may copy into pinned memory; 0: every core, at most 8). Leaves prepared.on_device null,
// doing nothing, where they would take more than a quarter of its memory. Throws Error for
// OpenCL failures.
PreparedProjected prepare_projected(const Device& device, const SamplePoints& points,
                                    unsigned threads = 0);

// As sdf::smooth_projected_into, on `device`, with the frames that `prepared` uploaded.
// values: one per point, >= 0 (std::invalid_argument otherwise, as on the CPU). Throws
// Error for OpenCL failures (also when the device failed since the upload: its state was
// replaced) and when the buffers do not fit the device.
void smooth_projected_opencl(const Device& device, const PreparedProjected& prepared,
                             const float* values, const ProjectedOptions& options, float* out,
                             const ProgressFn& progress = nullptr, StageTimings* timings = nullptr);

// The same from a mesh: its points' frames made on the host threads and uploaded first.
void smooth_projected_opencl(const Device& device, const Mesh& mesh, PointKind kind,
                             const float* values, const ProjectedOptions& options, float* out,
                             const ProgressFn& progress = nullptr, StageTimings* timings = nullptr);

}  // namespace sdf::cl
