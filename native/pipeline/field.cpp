// SPDX-License-Identifier: GPL-3.0-or-later
#include "pipeline/field.h"

#include <algorithm>
#include <utility>

#include "pipeline/fallback.h"
#include "pipeline/twins_step.h"
#include "prepare/unit_scale.h"
#include "util/stopwatch.h"

namespace sdf {

namespace {

// With smoothing, the cast reports [0, kCastShare] of the progress and the smoothing the rest.
constexpr double kCastShare = 0.9;

// The caller's progress, never told less than it was told already: a second cast (without
// twin faces) reports from 0 again.
ProgressFn monotone(const ProgressFn& progress, double& high) {
  if (!progress) return nullptr;
  return [&progress, &high](double fraction) {
    high = std::max(high, fraction);
    return progress(high);
  };
}

ProgressFn part_of(const ProgressFn& progress, double from, double to) {
  if (!progress) return nullptr;
  return [progress, from, to](double f) { return progress(from + (to - from) * f); };
}

bool winding_matters(SmoothingMethod method) {
  return method == SmoothingMethod::Kring || method == SmoothingMethod::Projected;
}

// One cast of `mesh` on `engine`, with the smoothing's preparation beside it where the host
// would otherwise wait: texture smoothing's UV islands (on a device, uploaded); on a device,
// projected smoothing's frames, from the cast's own points (oriented as the cast saw the
// mesh). A mesh far from unit size smooths projected points from the mesh, scaled
// (smoothing_step.h), so no frames are made ahead for it.
struct CastRun {
  Output out;
  PreparedSmoothing prepared;
};

CastRun cast_once(const MeshArrays& arrays, const float* uvs, const FieldOptions& options,
                  const std::string& engine, bool find_twins, const ProgressFn& progress) {
  Options o = options.cast;
  o.engine = engine;
  o.find_twins = find_twins;
  const SmoothingMethod method = options.smoothing.method;
  o.keep_mesh = winding_matters(method) || method == SmoothingMethod::Bilateral ||
                method == SmoothingMethod::None;
  CastRun run;
  Mesh mesh = make_mesh(arrays, o.threads);
  BesideCast beside;
  const bool frames_ahead = method == SmoothingMethod::Projected && engine != "cpu" &&
                            unit_scale_exponent(mesh.max_extent) == 0;
  if (method == SmoothingMethod::Texture || frames_ahead) {
    beside = [&](const SamplePoints& points) {
      Stopwatch clock;
      Mesh given = method == SmoothingMethod::Texture ? make_mesh(arrays, o.threads) : Mesh();
      const double made = clock.lap();
      run.prepared =
          prepare_smoothing(std::move(given), uvs, o.points, options.smoothing, engine, &points);
      if (method == SmoothingMethod::Texture)
        run.prepared.timings.insert(run.prepared.timings.begin(), {"mesh", made});
    };
  }
  run.out = compute(std::move(mesh), o, progress, beside);
  return run;
}

}  // namespace

namespace {

// The cast's values smoothed into field.values, on `engine` (the CPU after a fallback);
// 'beside cast: ...', 'smooth' and 'smooth: ...' added to the cast's timings.
void smooth_cast(Field& field, CastRun& run, const MeshArrays& arrays, const float* uvs,
                 const FieldOptions& options, std::string& engine, const ProgressFn& told) {
  Output& out = run.out;
  for (const auto& [name, seconds] : run.prepared.timings)
    out.timings.emplace_back("beside cast: " + name, seconds);
  const SmoothingMethod method = options.smoothing.method;
  if (method == SmoothingMethod::None) {
    field.values = out.raw;
    return;
  }
  Stopwatch clock;
  SmoothingOptions o = options.smoothing;
  o.threads = options.cast.threads;
  SmoothingMesh mesh;
  mesh.oriented = winding_matters(method) ? &out.mesh : nullptr;
  mesh.uvs = uvs;
  mesh.triangles = arrays.triangles;
  mesh.face_count = arrays.triangle_count;
  mesh.vertex_count = arrays.vertex_count;
  const ProgressFn smoothing_progress = part_of(told, kCastShare, 1.0);
  const std::string smoothing_engine = engine;
  std::string failure;
  Smoothed done =
      with_fallback(engine, options.fall_back_to_cpu, failure, [&](const std::string& on) {
        // A failed device's frames are of no use to the CPU, which works from the mesh.
        const bool frames_elsewhere = method == SmoothingMethod::Projected && on == "cpu";
        return smooth_values(mesh, options.cast.points, out.raw.data(), o, on,
                             frames_elsewhere ? nullptr : &run.prepared, smoothing_progress);
      });
  if (!failure.empty()) field.fallback = "smoothing on " + smoothing_engine + " failed: " + failure;
  field.values = std::move(done.values);
  out.timings.emplace_back("smooth", clock.lap());
  for (const auto& [name, seconds] : done.timings)
    out.timings.emplace_back("smooth: " + name, seconds);
  field.smoothed_faces = arrays.triangle_count;
  field.texture_faces_outside = done.faces_outside;
  field.texture_faces_overlapping = done.faces_overlapping;
  field.texture_overlaps_unparted = done.overlaps_unparted;
  field.texture_pages = done.pages;
  field.texture_kept_off_device = done.kept_off_device;
  out.mesh = Mesh();  // no longer needed
}

// The cast of the mesh without its twin faces, and its smoothed values, made whole.
void give_twins_values(Field& field, const TwinsCut& cut, bool faces) {
  Output& out = field.cast;
  out.raw = cut.whole(out.raw, faces);
  field.values = cut.whole(field.values, faces);
  out.valid_rays = cut.whole(out.valid_rays, faces);
  if (!out.orientation.reversed.empty())
    out.orientation.reversed = cut.whole_faces_or_zero(out.orientation.reversed);
  field.twin_faces = cut.dropped();
}

}  // namespace

Field compute_field(const MeshArrays& arrays, const FieldOptions& options,
                    const ProgressFn& progress) {
  double high = 0.0;
  const ProgressFn told = monotone(progress, high);
  const bool smoothing = options.smoothing.method != SmoothingMethod::None;
  const ProgressFn cast_progress = smoothing ? part_of(told, 0.0, kCastShare) : told;
  std::string engine = options.cast.engine;
  const std::string chosen = engine;
  Field field;
  auto cast = [&](const MeshArrays& mesh, const float* uvs, bool find_twins) {
    std::string failure;
    CastRun run =
        with_fallback(engine, options.fall_back_to_cpu, failure, [&](const std::string& on) {
          return cast_once(mesh, uvs, options, on, find_twins, cast_progress);
        });
    if (!failure.empty()) field.fallback = chosen + " failed: " + failure;
    return run;
  };
  Stopwatch clock;
  CastRun run = cast(arrays, options.uvs, options.cast.find_twins);
  if (run.out.twins.empty()) {
    smooth_cast(field, run, arrays, options.uvs, options, engine, told);
    field.cast = std::move(run.out);
  } else {
    // Faces with a reversed twin: the run that found them stopped there; cast without them.
    const double first_run = clock.lap();
    const StageTimings first = std::move(run.out.timings);
    const ReversedTwins twins = std::move(run.out.twins);
    const TwinsCut cut(arrays, twins, options.uvs);
    run = cast(cut.mesh(), cut.uvs(), false);
    smooth_cast(field, run, cut.mesh(), cut.uvs(), options, engine, told);
    field.cast = std::move(run.out);
    clock.lap();
    give_twins_values(field, cut, options.cast.points == PointKind::Faces);
    // The run that found them, until it stopped (the search's own time within it), and the
    // values given to the faces left out.
    StageTimings& timings = field.cast.timings;
    timings.emplace_back("twins (first run)", first_run);
    for (const auto& [name, seconds] : first)
      if (name == "twins" || name == "twins (beside cast)") timings.emplace_back(name, seconds);
    timings.emplace_back("twins: values given", clock.lap());
  }
  clock.lap();
  field.normalized.resize(field.values.size());
  normalize(field.values.data(), field.values.size(), options.normalize, options.cast.threads,
            field.normalized.data());
  field.cast.timings.emplace_back("normalize", clock.lap());
  return field;
}

}  // namespace sdf
