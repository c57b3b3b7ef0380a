// SPDX-License-Identifier: GPL-3.0-or-later
// Benchmark reference only, never part of the product: our SDF rule cast with Embree 3
// (rtcIntersect1 per ray, every core), the best-in-class CPU ray caster. Points, ray
// directions and the per-point reduction are the core's (the rule being measured is ours);
// the casting is Embree's own BVH and intersector, so it also checks our traversal.
//   embree_sdf IN.off RAYS OUT.txt   -> one value per face (-1: no valid ray); time on stderr
#include <embree3/rtcore.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "../kernels/sdf_reduce.h"
#include "mesh.h"
#include "rays.h"
#include "sampling.h"

namespace {

struct Off {
  std::vector<float> v;
  std::vector<unsigned> f;
};

Off read_off(const char* path) {
  std::ifstream in(path);
  std::string magic;
  std::size_t nv = 0, nf = 0, ne = 0;
  in >> magic >> nv >> nf >> ne;
  Off m;
  m.v.resize(3 * nv);
  for (auto& x : m.v) in >> x;
  for (std::size_t i = 0; i < nf; ++i) {
    int k;
    unsigned a, b, c;
    in >> k >> a >> b >> c;
    m.f.insert(m.f.end(), {a, b, c});
  }
  if (!in) throw std::runtime_error(std::string("cannot read OFF triangles from ") + path);
  return m;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 4) {
    std::fprintf(stderr, "usage: embree_sdf IN.off RAYS OUT.txt\n");
    return 2;
  }
  const Off mesh = read_off(argv[1]);
  const int rays = std::stoi(argv[2]);
  const std::size_t nf = mesh.f.size() / 3;

  RTCDevice device = rtcNewDevice(nullptr);
  const auto t0 = std::chrono::steady_clock::now();
  RTCScene scene = rtcNewScene(device);
  RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
  float* vb = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0,
                                                          RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                                          mesh.v.size() / 3));
  std::copy(mesh.v.begin(), mesh.v.end(), vb);
  unsigned* ib = static_cast<unsigned*>(rtcSetNewGeometryBuffer(
      geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), nf));
  std::copy(mesh.f.begin(), mesh.f.end(), ib);
  rtcCommitGeometry(geom);
  rtcAttachGeometry(scene, geom);
  rtcReleaseGeometry(geom);
  rtcCommitScene(scene);
  const auto t1 = std::chrono::steady_clock::now();

  // Points, tangent frames, ray directions and the reduction are the product's own (the rule
  // being measured); only the casting is Embree's.
  std::vector<double> vd(mesh.v.begin(), mesh.v.end());
  std::vector<std::int64_t> fd(mesh.f.begin(), mesh.f.end());
  const sdf::Mesh m = sdf::make_mesh(vd.data(), vd.size() / 3, fd.data(), nf);
  const sdf::SamplePoints points = sdf::sample_points(m, sdf::PointKind::Faces);
  const sdf::Cone cone = sdf::make_cone(rays, 120.0, sdf::Sampling::Fibonacci, 0);
  const float tmin = sdf::minimum_closeness(m);
  const glm::vec3 center(m.center);

  std::vector<float> out(nf);
  std::atomic<std::size_t> next{0};
  auto worker = [&] {
    std::vector<glm::vec3> directions(rays);
    std::vector<float> angles(rays), lengths(rays), kept_angles(rays);
    RTCIntersectContext context;
    for (;;) {
      const std::size_t begin = next.fetch_add(256);
      if (begin >= nf) break;
      for (std::size_t f = begin; f < std::min(nf, begin + 256); ++f) {
        const glm::vec3 axis = points.axes[f];
        if (axis == glm::vec3(0.0f)) {
          out[f] = -1.0f;
          continue;
        }
        sdf::cone_rays(cone, axis, points.tangents[f], static_cast<std::uint32_t>(f),
                       directions.data(), angles.data());
        const glm::vec3 origin = points.origins[f] + center;  // Embree has the input coordinates
        int kept = 0;
        for (int r = 0; r < rays; ++r) {
          const glm::vec3 d = directions[r];
          rtcInitIntersectContext(&context);
          RTCRayHit rh;
          rh.ray.org_x = origin.x;
          rh.ray.org_y = origin.y;
          rh.ray.org_z = origin.z;
          rh.ray.dir_x = d.x;
          rh.ray.dir_y = d.y;
          rh.ray.dir_z = d.z;
          rh.ray.tnear = tmin;
          rh.ray.tfar = INFINITY;
          rh.ray.mask = ~0u;
          rh.ray.flags = 0;
          rh.ray.time = 0.0f;
          rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
          rtcIntersect1(scene, &context, &rh);
          if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID || rh.hit.primID == f) continue;
          // Embree's Ng is cross(e1, e2) with e1 = v0 - v1, e2 = v2 - v0: the outward normal.
          const float dn = d.x * rh.hit.Ng_x + d.y * rh.hit.Ng_y + d.z * rh.hit.Ng_z;
          if (dn <= 0.0f) continue;  // entering the solid: the ray is dropped
          lengths[kept] = rh.ray.tfar;
          kept_angles[kept++] = angles[r];
        }
        out[f] = sdf::kern::sdf_reduce(SDF_SAMPLING_FIBONACCI, lengths.data(), kept_angles.data(),
                                       kept, cone.angle_floor);
      }
    }
  };
  std::vector<std::thread> pool;
  const unsigned threads = std::max(1u, std::thread::hardware_concurrency());
  for (unsigned i = 0; i < threads; ++i) pool.emplace_back(worker);
  for (auto& t : pool) t.join();
  const auto t2 = std::chrono::steady_clock::now();

  const double build_s = std::chrono::duration<double>(t1 - t0).count();
  const double cast_s = std::chrono::duration<double>(t2 - t1).count();
  std::fprintf(stderr, "embree_sdf: faces=%zu rays=%d threads=%u build %.3f s cast %.3f s %.2f Mrays/s\n",
               nf, rays, threads, build_s, cast_s, nf * rays / cast_s / 1e6);
  FILE* o = std::fopen(argv[3], "w");
  for (float v : out) std::fprintf(o, "%.9g\n", v);
  std::fclose(o);
  rtcReleaseScene(scene);
  rtcReleaseDevice(device);
  return 0;
}
