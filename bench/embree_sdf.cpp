// SPDX-License-Identifier: GPL-3.0-or-later
// Benchmark reference only, never part of the product: our SDF rule cast with Embree 3
// (rtcIntersect1 per ray, every core), the best-in-class CPU ray caster (embree_caster.h).
// Since the casting is Embree's own BVH and intersector, it also checks our traversal.
//   embree_sdf IN.off RAYS OUT.txt   -> one value per face (-1: no valid ray); time on stderr
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "embree_caster.h"

int main(int argc, char** argv) {
  if (argc != 4) {
    std::fprintf(stderr, "usage: embree_sdf IN.off RAYS OUT.txt\n");
    return 2;
  }
  const bench::Off mesh = bench::read_off(argv[1]);
  const int rays = std::stoi(argv[2]);
  const std::size_t nf = mesh.f.size() / 3;

  RTCDevice device = rtcNewDevice(nullptr);
  const auto t0 = std::chrono::steady_clock::now();
  RTCScene scene = bench::embree_scene(device, mesh);
  const auto t1 = std::chrono::steady_clock::now();

  // Points, tangent frames, ray directions and the reduction are the product's own (the rule
  // being measured); only the casting is Embree's. (Sampling is inside the cast time.)
  const sdf::Mesh m = bench::core_mesh(mesh);
  const sdf::SamplePoints points = sdf::sample_points(m, sdf::PointKind::Faces);
  const sdf::Cone cone = sdf::make_cone(rays, 120.0, sdf::Sampling::Fibonacci, 0);
  std::vector<float> out;
  const unsigned threads =
      bench::embree_cast(scene, m, points, cone, sdf::minimum_closeness(m), out);
  const auto t2 = std::chrono::steady_clock::now();

  const double build_s = std::chrono::duration<double>(t1 - t0).count();
  const double cast_s = std::chrono::duration<double>(t2 - t1).count();
  std::fprintf(stderr,
               "embree_sdf: faces=%zu rays=%d threads=%u build %.3f s cast %.3f s %.2f Mrays/s\n",
               nf, rays, threads, build_s, cast_s, nf * rays / cast_s / 1e6);
  FILE* o = std::fopen(argv[3], "w");
  for (float v : out) std::fprintf(o, "%.9g\n", v);
  std::fclose(o);
  rtcReleaseScene(scene);
  rtcReleaseDevice(device);
  return 0;
}
