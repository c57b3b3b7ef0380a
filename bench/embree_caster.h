// SPDX-License-Identifier: GPL-3.0-or-later
// The Embree 3 reference caster of our rule, shared by bench/embree_sdf.cpp (values and time
// for bench.py) and bench/cast_timing.cpp (alternating with our engine): an OFF reader, the
// Embree scene, and the cast (rtcIntersect1 per ray, every core). Points, ray directions and
// the per-point reduction are the core's (the rule being measured is ours); the casting is
// Embree's own BVH and intersector. Benchmark code only, never part of the product.
#pragma once

#include <embree3/rtcore.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <fstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "mesh/mesh.h"
#include "prepare/rays.h"
#include "prepare/sampling.h"
#include "ray/sdf_reduce.h"

namespace bench {

struct Off {
  std::vector<float> v;
  std::vector<unsigned> f;
};

inline Off read_off(const char* path) {
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

// The core's mesh of the same OFF data (make_mesh reads doubles and 64-bit indices).
inline sdf::Mesh core_mesh(const Off& off) {
  const std::vector<double> v(off.v.begin(), off.v.end());
  const std::vector<std::int64_t> f(off.f.begin(), off.f.end());
  return sdf::make_mesh(v.data(), v.size() / 3, f.data(), f.size() / 3);
}

inline RTCScene embree_scene(RTCDevice device, const Off& mesh) {
  RTCScene scene = rtcNewScene(device);
  RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
  const std::size_t nv = mesh.v.size() / 3, nf = mesh.f.size() / 3;
  float* vb = static_cast<float*>(rtcSetNewGeometryBuffer(
      geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), nv));
  std::copy(mesh.v.begin(), mesh.v.end(), vb);
  unsigned* ib = static_cast<unsigned*>(rtcSetNewGeometryBuffer(
      geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), nf));
  std::copy(mesh.f.begin(), mesh.f.end(), ib);
  rtcCommitGeometry(geom);
  rtcAttachGeometry(scene, geom);
  rtcReleaseGeometry(geom);
  rtcCommitScene(scene);
  return scene;
}

// Casts every face point of `points` (sampled from `m`) with Embree on every core and writes
// the reduced value per face into out (-1: no valid ray). Returns the number of threads.
inline unsigned embree_cast(RTCScene scene, const sdf::Mesh& m, const sdf::SamplePoints& points,
                            const sdf::Cone& cone, float tmin, std::vector<float>& out) {
  const std::size_t nf = points.size();
  const int rays = cone.rays;
  const glm::vec3 center(m.center);
  out.assign(nf, 0.0f);
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
  return threads;
}

}  // namespace bench
