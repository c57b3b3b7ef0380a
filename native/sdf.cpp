// SPDX-License-Identifier: GPL-3.0-or-later
#include "sdf.h"

#include <chrono>

#include "bvh.h"
#include "cpu_engine.h"

namespace sdf {

namespace {

class Stopwatch {
 public:
  double lap() {
    const auto now = std::chrono::steady_clock::now();
    const double s = std::chrono::duration<double>(now - last_).count();
    last_ = now;
    return s;
  }

 private:
  std::chrono::steady_clock::time_point last_ = std::chrono::steady_clock::now();
};

void report(const ProgressFn& progress, double fraction) {
  if (progress && !progress(fraction)) throw Cancelled();
}

}  // namespace

Output compute(const Mesh& mesh, const Options& options, const ProgressFn& progress) {
  const Cone cone = make_cone(options.rays, options.cone_angle, options.sampling, options.seed);
  Output out;
  Stopwatch clock;
  report(progress, 0.0);
  const SamplePoints points = sample_points(mesh, options.points);
  out.timings.emplace_back("prepare", clock.lap());

  BvhConfig config;
  config.threads = options.threads;
  const Bvh bvh = build_bvh(mesh, config);
  out.timings.emplace_back("build", clock.lap());
  report(progress, 0.05);

  out.raw.resize(points.size());
  out.valid_rays.resize(points.size());
  // Casting and reducing are fused per point on the CPU: the lengths never leave the cache.
  cast_cpu(bvh, points, cone, minimum_closeness(mesh), options.threads, out.raw.data(),
           out.valid_rays.data(), progress, 0.05, 0.99);
  out.timings.emplace_back("cast", clock.lap());

  out.fill = fill_missing(mesh, options.points, out.raw.data(), out.valid_rays.data());
  out.timings.emplace_back("fill", clock.lap());
  report(progress, 1.0);
  return out;
}

}  // namespace sdf
