// SPDX-License-Identifier: GPL-3.0-or-later
// Benchmark tool, never part of the product: times our CPU engine's cast against the Embree 3
// reference caster of the same rule (bench/embree_caster.h, the one embree_sdf runs) in one
// process, alternating the two, so that the load of a shared machine hits both alike. Only casting
// and reducing are timed: points, rays and structures are built once, outside the clock.
//   cast_timing IN.off RAYS ROUNDS [VALUES_OUT.bin]
//   -> per round the rays per CPU second (all threads; time spent descheduled by other work on
//      a shared machine does not count) of Embree and of our binary (the path of CPUs without
//      SSE), 4-wide and 8-wide trees, and their median ratios to Embree; checks that the trees
//      give the same values, bit for bit. VALUES_OUT.bin receives our raw values (float32) to
//      compare builds. Off x86-64 the 4-wide and 8-wide columns time the binary tree.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <string>
#include <vector>

#include "accel/bvh.h"
#include "accel/bvh4.h"
#include "accel/bvh8.h"
#include "accel/bvh_margin.h"
#include "accel/scene.h"
#include "cast/bvh4_traverse.h"
#include "cast/cpu_engine.h"
#include "embree_caster.h"

namespace {

// CPU seconds of this process: on a shared machine, time spent descheduled does not count.
double cpu_seconds() {
  timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 4 && argc != 5) {
    std::fprintf(stderr, "usage: cast_timing IN.off RAYS ROUNDS [VALUES_OUT.bin]\n");
    return 2;
  }
  const bench::Off off = bench::read_off(argv[1]);
  const int rays = std::stoi(argv[2]);
  const int rounds = std::stoi(argv[3]);
  const std::size_t nf = off.f.size() / 3;

  const sdf::Mesh m = bench::core_mesh(off);
  const sdf::SamplePoints points = sdf::sample_points(m, sdf::PointKind::Faces);
  const std::vector<std::uint32_t> order = sdf::spatial_order(points);
  const sdf::Cone cone = sdf::make_cone(rays, 120.0, sdf::Sampling::Fibonacci, 0);
  const float tmin = sdf::minimum_closeness(m);

  sdf::BvhConfig config;  // CAST_TIMING_LEAF=n tries another leaf size
  if (const char* leaf = std::getenv("CAST_TIMING_LEAF")) config.max_leaf_size = std::atoi(leaf);
  // One scene holding every width; each cast sets the widths it reads.
  sdf::Scene scene;
  scene.bvh = sdf::build_bvh(m, config);
  sdf::grow_boxes_to_cover_hits(scene.bvh);
  scene.bvh4 = sdf::collapse_to_bvh4(scene.bvh);
  const char* merge = std::getenv("CAST_TIMING_MERGE");  // another merge_up_to
  const double collapse_from = cpu_seconds();
  scene.bvh8 = sdf::collapse_to_bvh8(scene.bvh, merge ? std::atoi(merge) : sdf::kBvh8MergeUpTo);
  std::printf("bvh8: %zu nodes, %zu packets for %zu triangles, collapsed in %.3f cpu s\n",
              scene.bvh8.nodes.size(), scene.bvh8.packets.size(), scene.bvh.triangles.size(),
              cpu_seconds() - collapse_from);
  // The widths each column casts; where this build or CPU lacks one, the next narrower.
  sdf::BvhWidths binary, four, eight;
  binary.binary = true;
  four.four = SDF_HAVE_BVH4_SSE;
  four.binary = !four.four;
  eight = four;
  if (sdf::bvh8_supported()) eight = sdf::BvhWidths{false, false, true};

  RTCDevice device = rtcNewDevice(nullptr);
  RTCScene rtc = bench::embree_scene(device, off);

  std::vector<float> raw(nf), raw2(nf), raw4(nf), embree_values;
  std::vector<std::int32_t> valid(nf);
  std::vector<double> ratios2, ratios4, ratios8;
  auto ours = [&](const sdf::BvhWidths& widths, std::vector<float>& values) {
    scene.widths = widths;
    const double t0 = cpu_seconds();
    sdf::cast_cpu(scene, points, order, cone, tmin, 0, values.data(), valid.data(), nullptr, 0.0,
                  1.0);
    return cpu_seconds() - t0;
  };
  const double mrays = nf * rays / 1e6;
  for (int r = 0; r < rounds; ++r) {
    const double embree_from = cpu_seconds();
    bench::embree_cast(rtc, m, points, cone, tmin, embree_values);
    const double embree_s = cpu_seconds() - embree_from;
    const double bvh2_s = ours(binary, raw2);
    const double bvh4_s = ours(four, raw4);
    const double bvh8_s = ours(eight, raw);
    ratios2.push_back(embree_s / bvh2_s);
    ratios4.push_back(embree_s / bvh4_s);
    ratios8.push_back(embree_s / bvh8_s);
    std::printf(
        "round %d: Mrays per cpu s: embree %.2f, binary %.2f (%.3f), bvh4 %.2f (%.3f), "
        "bvh8 %.2f (%.3f)\n",
        r, mrays / embree_s, mrays / bvh2_s, ratios2.back(), mrays / bvh4_s, ratios4.back(),
        mrays / bvh8_s, ratios8.back());
  }
  std::sort(ratios2.begin(), ratios2.end());
  std::sort(ratios4.begin(), ratios4.end());
  std::sort(ratios8.begin(), ratios8.end());
  std::printf(
      "%s faces=%zu median ratio to Embree's rays/s: binary %.3f, bvh4 %.3f, bvh8 %.3f; "
      "values %s\n",
      argv[1], nf, ratios2[rounds / 2], ratios4[rounds / 2], ratios8[rounds / 2],
      raw == raw4 && raw == raw2 ? "equal in all three" : "DIFFER between trees");
  if (argc == 5) {
    std::ofstream out(argv[4], std::ios::binary);
    out.write(reinterpret_cast<const char*>(raw.data()), raw.size() * sizeof(float));
  }
  rtcReleaseScene(rtc);
  rtcReleaseDevice(device);
  return 0;
}
