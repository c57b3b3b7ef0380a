// SPDX-License-Identifier: GPL-3.0-or-later
#include "pipeline/smoothing_step.h"

#include <cmath>
#include <stdexcept>

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

void texture(const SmoothingMesh& mesh, PointKind kind, const float* values,
             const SmoothingOptions& options, [[maybe_unused]] DevicePtr device,
             const PreparedSmoothing* prepared, const ProgressFn& progress, Smoothed& out) {
  TextureOptions o = options.texture;
  o.threads = options.threads;
  const PreparedTexture* ready = prepared ? prepared->texture.get() : nullptr;
  if (!ready && !mesh.as_given)
    throw std::logic_error("texture smoothing needs the mesh as given or a prepared texture");
  const Mesh& given = ready ? ready->mesh : *mesh.as_given;
  out.values.resize(point_count(given, kind));
  TextureSmoothing done;
#ifdef SDF_HAVE_OPENCL
  if (device && ready)
    done = cl::smooth_texture_opencl(*device, *ready, kind, values, o, options.return_image,
                                     progress, out.values.data());
  else if (device)
    done = cl::smooth_texture_opencl(*device, given, kind, values, mesh.uvs, o,
                                     options.return_image, progress, out.values.data());
  else
#endif
      if (ready)
    done = smooth_texture(*ready, kind, values, o, options.return_image, progress, 0.0, 1.0,
                          nullptr, out.values.data());
  else
    done = smooth_texture(given, kind, values, mesh.uvs, o, options.return_image, progress, 0.0,
                          1.0, nullptr, out.values.data());
  out.timings = std::move(done.timings);
  out.faces_outside = done.faces_outside;
  out.kept_off_device = done.kept_off_device;
  out.image = std::move(done.image);
  out.mask = std::move(done.mask);
  out.width = done.width;
  out.height = done.height;
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
    prepared.texture = std::make_shared<PreparedTexture>(
        prepare_texture(std::move(as_given), uvs, o, kind == PointKind::Vertices));
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
