// SPDX-License-Identifier: GPL-3.0-or-later
// The whole pipeline: sample, build, cast and reduce (CPU threads or OpenCL), fill.
// Each stage is also callable on its own (sampling.h, bvh.h, octree.h, cpu_engine.h, fill.h).
#pragma once

#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "accel/octree.h"
#include "mesh/mesh.h"
#include "mesh/mesh_twins.h"
#include "post/fill.h"
#include "prepare/orientation.h"
#include "prepare/rays.h"
#include "prepare/sampling.h"
#include "util/parallel.h"
#include "util/stopwatch.h"

namespace sdf {

enum class Accel { Bvh, Octree };

// How the BVH is built (Embree's build quality). High: binned SAH at every node, the fastest
// tree to cast. Fast: SAH down to nodes of kFastMortonBelow triangles, Morton-code splits
// below (bvh_morton.h): on an H100 with 16 host cores, 1.2M faces at 30 rays, the build went
// from 78 to 49 ms and the cast from 55 to 65 ms, so end to end 211 -> 178 ms; the CPU engine,
// whose cast is 100x its build, loses. Auto: Fast where every device is a GPU and rays <= 64
// (there the build is the larger cost), High otherwise.
enum class BvhQuality { Auto, High, Fast };

struct Options {
  int rays = 30;              // per point (Shapira et al. and the paper: 30)
  double cone_angle = 120.0;  // full apex angle in degrees (paper: 120)
  Sampling sampling = Sampling::Fibonacci;
  std::uint32_t seed = 0;  // for Sampling::Random
  PointKind points = PointKind::Faces;
  unsigned threads = 0;  // CPU threads; 0: every core (and the BVH builds beside
                         // orientation and sampling, each on every core)
  // "cpu", or an OpenCL selection: "opencl", "opencl:N", "opencl:all", "opencl:<name part>".
  std::string engine = "cpu";
  Accel accel = Accel::Bvh;
  OctreeConfig octree;
  Orientation orientation = Orientation::Auto;
  BvhQuality bvh_quality = BvhQuality::Auto;
  // Look for faces with a reversed twin (mesh_twins.h) and, where there are any, stop there
  // and return them (Output::twins): the caller casts the mesh without them.
  bool find_twins = true;
  // Output::mesh: the mesh as cast (wound outward), for what runs on it afterwards.
  bool keep_mesh = false;
};

struct Output {
  std::vector<float> raw;                // per point, input units, filled
  std::vector<std::int32_t> valid_rays;  // rays kept per point; 0 = value was filled
  StageTimings timings;                  // stage -> seconds
  FillResult fill = FillResult::NothingToFill;
  std::string engine;              // what ran, e.g. "cpu (2 threads, bvh, 8-wide)"
  std::uint64_t device_bytes = 0;  // OpenCL buffers on the device (0 on the CPU)
  float near_cutoff = 0.0f;        // hits nearer than this are ignored (input units)
  OrientationReport orientation;   // faces the computation reversed
  // Faces with a reversed twin, in the caller's winding (Options::find_twins). When there are
  // any, the computation stopped on finding them: raw and valid_rays are empty.
  ReversedTwins twins;
  Mesh mesh;  // Options::keep_mesh: the computation's mesh, oriented, in the caller's units
};

// Host work that needs no result of the computation, run once on the calling thread: while
// an OpenCL device casts (when the host would only wait), or after the CPU engine's cast.
// It gets the points the cast casts from (on the mesh as orientation wound it).
// compute(smoothing='texture') prepares its texture there (UV islands; on OpenCL the UVs'
// upload), compute(smoothing='projected') on OpenCL uploads the points' frames. An exception
// it throws ends the computation and propagates.
using BesideCast = std::function<void(const SamplePoints& points)>;

// Takes the mesh by value: the computation reorients its own copy, and a caller that has no
// further use for its mesh moves it in and saves the copy (~10 ms per million faces).
Output compute(Mesh mesh, const Options& options, const ProgressFn& progress = nullptr,
               const BesideCast& beside_cast = nullptr);

// Whether this build has the OpenCL engine (it still needs a driver at run time).
bool opencl_built();

}  // namespace sdf
