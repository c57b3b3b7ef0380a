// SPDX-License-Identifier: GPL-3.0-or-later
// Stages 3-4 on OpenCL devices: upload the acceleration structure and the points, cast and
// reduce in launches short enough for display watchdogs, read the values back.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "accel/bvh.h"
#include "accel/scene.h"
#include "devices.h"
#include "mesh/mesh.h"
#include "prepare/rays.h"
#include "prepare/sampling.h"
#include "util/parallel.h"

namespace sdf::cl {

// The kernels that cast a BVH: the binary or 8-wide tree, one work item per point or per ray.
// The octree has one kernel.
enum class CastKernel { BvhPerPoint, Bvh8PerPoint, BvhPerRay };

// The kernel `device` runs (see opencl_engine.cpp for the measurements behind the choice).
CastKernel cast_kernel_for(const Device& device);

// Which trees `devices` cast, for the caller to build (Scene::widths).
BvhWidths wanted_bvhs(const std::vector<const Device*>& devices);

// The scene, from where the caller makes it: cast_opencl calls it once, from a device thread
// once the points are on their way to the devices, so the caller can still be building it.
// The scene outlives the cast.
using SceneSource = std::function<const Scene&()>;

struct CastTimings {
  double upload = 0.0, cast = 0.0, download = 0.0;
  double wait = 0.0;               // for the scene, once the points were uploaded
  double build = 0.0;              // of a tree made on the device (the faces' sort and the tree)
  bool rewound = false;            // that tree was a kept one, rewound (CastInput::rewind_trees)
  std::uint64_t device_bytes = 0;  // buffers on the device (the largest of several devices)
};

// Trees the devices made in one cast, kept for a second cast of the same mesh (CastInput::
// trees); freed with it.
class KeptTrees {
 public:
  KeptTrees();
  ~KeptTrees();
  KeptTrees(const KeptTrees&) = delete;
  KeptTrees& operator=(const KeptTrees&) = delete;
  struct Slots;  // opencl_engine.cpp
  Slots& slots() { return *slots_; }

 private:
  std::unique_ptr<Slots> slots_;
};

// What the devices cast: points sampled on the host (`points`, cast in the spatial `order`
// through the tree `scene` gives), or, with `mesh` set, its faces, each device making their
// order and a BVH itself (device_tree.h) and its cast the faces' points. size: points or
// faces.
struct CastInput {
  SceneSource scene;
  const SamplePoints* points = nullptr;
  const std::uint32_t* order = nullptr;
  std::size_t size = 0;
  const Mesh* mesh = nullptr;
  // While it points at true, launches of about 5 ms instead of 100, so that a verdict that
  // the cast is moot (sdf.cpp: the orientation reverses faces) stops the devices soon.
  const std::atomic<bool>* short_launches = nullptr;
  // With `mesh`: where each device leaves its tree when beside_cast stops the cast by
  // throwing (null, or a cast that ends otherwise: freed before cast_opencl returns), and
  // whether a tree found there is of this mesh as an earlier cast had it wound: the same
  // vertices, each face the same corners, some reversed. A face's box does not depend on
  // its winding, so such a tree is rewound (the faces uploaded again, the triangles'
  // records remade: device_tree.h) instead of made.
  KeptTrees* trees = nullptr;
  bool rewind_trees = false;
};

// Casts every point on `devices` (several: points are shared out dynamically; results are
// identical to one device); `host_threads` (0: every core) put the results in mesh order.
// Writes raw[i] (-1 when no ray was kept) and valid_rays[i].
// Throws Error for OpenCL failures (naming the call and code), also when the scene does not
// fit a device's memory. Progress covers [progress_from, progress_to].
// beside_cast (sdf.h's BesideCast) runs on the calling thread once the devices have started
// (with input.mesh: once the mesh is on every device, its staging copies done).
CastTimings cast_opencl(const std::vector<const Device*>& devices, const CastInput& input,
                        const Cone& cone, float min_closeness, unsigned host_threads, float* raw,
                        std::int32_t* valid_rays, const ProgressFn& progress, double progress_from,
                        double progress_to, const std::function<void()>& beside_cast = nullptr);

// Whether the tree is made on the device: `preferred`, unless a test override
// (util/test_overrides.h) forces the host or the device.
bool tree_on_device(bool preferred);

// Test hooks: build `source` for device `index` (the build log comes back in the Error), and
// run the layout probe kernel, returning what it wrote.
void build_source_for_test(int index, const std::string& source);
std::vector<std::uint32_t> probe_layout(int index);

}  // namespace sdf::cl
