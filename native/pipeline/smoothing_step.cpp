// SPDX-License-Identifier: GPL-3.0-or-later
#include "pipeline/smoothing_step.h"

#include <cmath>
#include <stdexcept>

#include "post/smoothing_texture_pages.h"
#include "post/uv_islands.h"
#include "post/uv_layout.h"
#include "prepare/unit_scale.h"
#include "segment/face_graph.h"
#include "segment/postprocess.h"
#ifdef SDF_HAVE_OPENCL
#include "opencl/devices.h"
#include "opencl/opencl_projected.h"
#include "opencl/opencl_smoothing.h"
#endif

namespace sdf {

namespace {

#ifdef SDF_HAVE_OPENCL
using DevicePtr = const cl::Device*;
DevicePtr device_for(const std::string& engine) {
  if (engine == "cpu") return nullptr;
  if (engine.compare(0, 6, "opencl") != 0)
    throw std::invalid_argument("engine must be 'cpu' or 'opencl...', got '" + engine + "'");
  return cl::select_devices(engine).front();
}
#else
using DevicePtr = const void*;
DevicePtr device_for(const std::string& engine) {
  if (engine == "cpu") return nullptr;
  throw std::invalid_argument("this build of shape_diameter has no OpenCL engine (engine '" +
                              engine + "')");
}
#endif

std::size_t point_count(const Mesh& mesh, PointKind kind) {
  return kind == PointKind::Faces ? mesh.triangles.size() : mesh.vertices.size();
}

void bilateral(const SmoothingMesh& mesh, PointKind kind, const float* values,
               const SmoothingOptions& options, Smoothed& out) {
  if (kind != PointKind::Faces)
    throw std::invalid_argument(
        "smoothing 'bilateral' smooths per-face values: points must be 'faces', got 'vertices'");
  Stopwatch clock;
  const std::size_t n = mesh.face_count;
  const std::vector<double> in(values, values + n);
  std::vector<double> filtered(n);
  const auto graph =
      segment::build_face_graph(mesh.triangles, n, mesh.vertex_count, options.threads);
  const std::size_t window =
      options.bilateral_window ? options.bilateral_window : segment::bilateral_window(n);
  segment::bilateral_filter(graph, in.data(), n, window, options.threads, filtered.data());
  out.values.assign(filtered.begin(), filtered.end());
  out.timings.emplace_back("bilateral", clock.lap());
}

// Projected smoothing moves points along the mesh in 32-bit floats: a mesh far from unit size
// (7% off at 1e10 units) is smoothed scaled by a power of two, as compute() casts it.
void projected(const Mesh& mesh, PointKind kind, const float* values, const ProjectedOptions& o,
               DevicePtr device, const PreparedSmoothing* prepared, const ProgressFn& progress,
               Smoothed& out) {
  const std::size_t n = point_count(mesh, kind);
  out.values.resize(n);
#ifdef SDF_HAVE_OPENCL
  if (device && prepared && prepared->projected) {
    const auto& frames = *static_cast<const cl::PreparedProjected*>(prepared->projected.get());
    cl::smooth_projected_opencl(*device, frames, values, o, out.values.data(), progress,
                                &out.timings);
    return;
  }
#else
  (void)prepared;
#endif
  const int exponent = unit_scale_exponent(mesh.max_extent);
  if (exponent != 0) {
    Mesh scaled = copy_mesh(mesh, o.threads);
    scale_mesh(scaled, exponent, o.threads);
    std::vector<float> scaled_values(values, values + n);
    for (float& x : scaled_values) x = std::ldexp(x, exponent);
    projected(scaled, kind, scaled_values.data(), o, device, nullptr, progress, out);
    for (float& x : out.values) x = std::ldexp(x, -exponent);
    return;
  }
#ifdef SDF_HAVE_OPENCL
  if (device) {
    cl::smooth_projected_opencl(*device, mesh, kind, values, o, out.values.data(), progress,
                                &out.timings);
    return;
  }
#endif
  smooth_projected_into(mesh, kind, values, o, out.values.data(), progress, 0.0, 1.0, &out.timings);
}

// The UV layout found before (options.uv_plan), where it was found for these faces (not for
// a double-sided mesh's second cast, without its twins), or null: found here.
const UvPlan* fitting_plan(const SmoothingOptions& options, std::size_t face_count,
                           std::size_t vertex_count, const float* uvs, PointKind kind) {
  const UvPlan* plan = options.uv_plan.get();
  return plan && plan_fits(*plan, face_count, vertex_count, uvs, options.texture.weld_tolerance,
                           kind == PointKind::Vertices)
             ? plan
             : nullptr;
}

// Texture smoothing on the UV layout's pages (uv_layout.h): UDIM tiles and layers that part
// overlapping islands, one image each, one after another through the per-image code (on the
// CPU threads or a device). A layout of one page in the [0, 1] square uses what was prepared
// (its islands; on a device, what was uploaded).
void texture(const SmoothingMesh& mesh, PointKind kind, const float* values,
             const SmoothingOptions& options, [[maybe_unused]] DevicePtr device,
             const PreparedSmoothing* prepared, const ProgressFn& progress, Smoothed& out) {
  TextureOptions o = options.texture;
  o.threads = options.threads;
  const PreparedTexture* given_ready = prepared ? prepared->texture.get() : nullptr;
  if (!given_ready && !mesh.as_given)
    throw std::logic_error("texture smoothing needs the mesh as given or a prepared texture");
  Stopwatch clock;
  // Without a preparation, one made here: the layout and a one-image run share its islands
  // (and its checks of the UVs and size come first, with their own words).
  const UvPlan* plan = fitting_plan(options, mesh.face_count, mesh.vertex_count, mesh.uvs, kind);
  PreparedTexture own;
  if (!given_ready) {
    own = prepare_texture(copy_mesh(*mesh.as_given, o.threads), mesh.uvs, o,
                          kind == PointKind::Vertices, plan ? &plan->islands : nullptr);
    for (auto& stage : own.timings)
      out.timings.emplace_back("prepare: " + stage.first, stage.second);
    clock.lap();
  }
  const PreparedTexture& ready = given_ready ? *given_ready : own;
  const Mesh& given = ready.mesh;
  const float* uvs = ready.uvs;
  out.values.resize(point_count(given, kind));
  // The layout found before (its search cost about as much as a 1024^2 smoothing), or now.
  UvLayout found;
  if (!plan) {
    found = layout_uvs(uvs, ready.islands.face_island, o.threads);
    out.timings.emplace_back("uv layout", clock.lap());
  }
  const UvLayout& layout = plan ? plan->layout : found;
  const bool one_image = layout.single_square();
  auto run_page = [&](const float* page_uvs, bool keep, const ProgressFn& part, float* into) {
#ifdef SDF_HAVE_OPENCL
    // What prepare_smoothing made (uploaded to the device where it could), or the page's UVs.
    if (device && one_image && given_ready)
      return cl::smooth_texture_opencl(*device, ready, kind, values, o, keep, part, into);
    if (device)
      return cl::smooth_texture_opencl(*device, given, kind, values, page_uvs, o, keep, part, into);
#endif
    if (one_image)
      return smooth_texture(ready, kind, values, o, keep, part, 0.0, 1.0, nullptr, into);
    // A page keeps the whole layout's islands (labelling them again cost as much as the rest).
    return smooth_texture_on_islands(given, kind, values, page_uvs, ready.islands,
                                     kind == PointKind::Vertices ? &ready.groups : nullptr, o, keep,
                                     part, into);
  };
  TextureSmoothing done =
      smooth_texture_pages(given, kind, values, uvs, layout, options.return_image, o.threads,
                           progress, run_page, out.values.data());
  for (auto& stage : done.timings) out.timings.push_back(std::move(stage));
  out.faces_outside = done.faces_outside;
  out.faces_spanning = done.faces_spanning;
  out.faces_overlapping = done.faces_overlapping;
  out.overlaps_unparted = done.overlaps_unparted;
  out.pages = done.pages;
  out.kept_off_device = done.kept_off_device;
  out.tiles = std::move(done.tiles);
}

}  // namespace

PreparedSmoothing prepare_smoothing(Mesh as_given, const float* uvs, PointKind kind,
                                    const SmoothingOptions& options, const std::string& engine,
                                    const SamplePoints* points) {
  PreparedSmoothing prepared;
  [[maybe_unused]] const DevicePtr device = device_for(engine);
  if (options.method == SmoothingMethod::Texture) {
    TextureOptions o = options.texture;
    o.threads = options.threads;
    const UvPlan* plan =
        fitting_plan(options, as_given.triangles.size(), as_given.vertices.size(), uvs, kind);
    prepared.texture = std::make_shared<PreparedTexture>(prepare_texture(
        std::move(as_given), uvs, o, kind == PointKind::Vertices, plan ? &plan->islands : nullptr));
#ifdef SDF_HAVE_OPENCL
    if (device) {
      try {
        cl::upload_prepared_texture(*device, *prepared.texture, options.threads);
      } catch (const cl::Error&) {  // the host then does the work
      }
    }
#endif
    prepared.timings = prepared.texture->timings;
  }
#ifdef SDF_HAVE_OPENCL
  if (options.method == SmoothingMethod::Projected && device && points) {
    try {
      auto frames = std::make_shared<cl::PreparedProjected>(
          cl::prepare_projected(*device, *points, options.threads));
      prepared.timings = frames->timings;
      if (frames->on_device) prepared.projected = std::move(frames);
    } catch (const cl::Error&) {  // the device then works from the mesh
    }
  }
#else
  (void)points;
#endif
  return prepared;
}

Smoothed smooth_values(const SmoothingMesh& mesh, PointKind kind, const float* values,
                       const SmoothingOptions& options, const std::string& engine,
                       const PreparedSmoothing* prepared, const ProgressFn& progress) {
  Smoothed out;
  switch (options.method) {
    case SmoothingMethod::None:
      out.values.assign(values,
                        values + (kind == PointKind::Faces ? mesh.face_count : mesh.vertex_count));
      break;
    case SmoothingMethod::Bilateral: bilateral(mesh, kind, values, options, out); break;
    case SmoothingMethod::Kring: {
      KringOptions o = options.kring;
      o.threads = options.threads;
      out.values.resize(point_count(*mesh.oriented, kind));
      smooth_kring_into(*mesh.oriented, kind, values, o, out.values.data(), progress, 0.0, 1.0,
                        &out.timings);
      break;
    }
    case SmoothingMethod::Projected: {
      ProjectedOptions o = options.projected;
      o.threads = options.threads;
      projected(*mesh.oriented, kind, values, o, device_for(engine), prepared, progress, out);
      break;
    }
    case SmoothingMethod::Texture:
      texture(mesh, kind, values, options, device_for(engine), prepared, progress, out);
      break;
  }
  return out;
}

}  // namespace sdf
