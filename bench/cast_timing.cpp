// SPDX-License-Identifier: GPL-3.0-or-later
// Benchmark tool, never part of the product: times our CPU engine's cast against the Embree 3
// reference caster of the same rule (as bench/embree_sdf.cpp casts it) in one process,
// alternating the two, so that the load of a shared machine hits both alike. Only casting and
// reducing are timed: points, rays and structures are built once, outside the clock.
//   cast_timing IN.off RAYS ROUNDS [VALUES_OUT.bin]
//   -> per round the rays per CPU second (all threads; time spent descheduled by other work on
//      a shared machine does not count) of Embree and of our 4-wide and 8-wide trees, and
//      their median ratios to Embree; checks that both trees give the same values, bit for
//      bit. VALUES_OUT.bin receives our raw values (float32) to compare builds.
#include <embree3/rtcore.h>

#include <algorithm>
#include <atomic>
#include <ctime>
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "../kernels/sdf_reduce.h"
#include "bvh.h"
#include "bvh4.h"
#include "bvh8.h"
#include "bvh_margin.h"
#include "cpu_engine.h"
#include "mesh.h"
#include "rays.h"
#include "sampling.h"

namespace {

struct Off {
  std::vector<double> v;
  std::vector<std::int64_t> f;
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
    std::int64_t a, b, c;
    in >> k >> a >> b >> c;
    m.f.insert(m.f.end(), {a, b, c});
  }
  if (!in) throw std::runtime_error(std::string("cannot read OFF triangles from ") + path);
  return m;
}

// CPU seconds of this process: on a shared machine, time spent descheduled does not count.
double cpu_seconds() {
  timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

// The loop of bench/embree_sdf.cpp: rtcIntersect1 per ray, every core.
double embree_cast(RTCScene scene, const sdf::Mesh& m, const sdf::SamplePoints& points,
                   const sdf::Cone& cone, float tmin) {
  const std::size_t nf = points.size();
  const int rays = cone.rays;
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
        const glm::vec3 origin = points.origins[f] + center;
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
          const float dn = d.x * rh.hit.Ng_x + d.y * rh.hit.Ng_y + d.z * rh.hit.Ng_z;
          if (dn <= 0.0f) continue;
          lengths[kept] = rh.ray.tfar;
          kept_angles[kept++] = angles[r];
        }
        out[f] = sdf::kern::sdf_reduce(SDF_SAMPLING_FIBONACCI, lengths.data(), kept_angles.data(),
                                       kept, cone.angle_floor);
      }
    }
  };
  const double t0 = cpu_seconds();
  std::vector<std::thread> pool;
  const unsigned threads = std::max(1u, std::thread::hardware_concurrency());
  for (unsigned i = 0; i < threads; ++i) pool.emplace_back(worker);
  for (auto& t : pool) t.join();
  return cpu_seconds() - t0;
}

RTCScene embree_scene(RTCDevice device, const Off& mesh) {
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

}  // namespace

int main(int argc, char** argv) {
  if (argc != 4 && argc != 5) {
    std::fprintf(stderr, "usage: cast_timing IN.off RAYS ROUNDS [VALUES_OUT.bin]\n");
    return 2;
  }
  const Off off = read_off(argv[1]);
  const int rays = std::stoi(argv[2]);
  const int rounds = std::stoi(argv[3]);
  const std::size_t nf = off.f.size() / 3;

  const sdf::Mesh m = sdf::make_mesh(off.v.data(), off.v.size() / 3, off.f.data(), nf);
  const sdf::SamplePoints points = sdf::sample_points(m, sdf::PointKind::Faces);
  const std::vector<std::uint32_t> order = sdf::spatial_order(points);
  const sdf::Cone cone = sdf::make_cone(rays, 120.0, sdf::Sampling::Fibonacci, 0);
  const float tmin = sdf::minimum_closeness(m);

  sdf::BvhConfig config;  // CAST_TIMING_LEAF=n tries another leaf size
  if (const char* leaf = std::getenv("CAST_TIMING_LEAF")) config.max_leaf_size = std::atoi(leaf);
  sdf::Bvh bvh = sdf::build_bvh(m, config);
  sdf::grow_boxes_to_cover_hits(bvh);
  const sdf::Bvh4 wide4 = sdf::collapse_to_bvh4(bvh);
  sdf::CpuScene scene4;
  scene4.bvh4 = &wide4;
  const char* merge = std::getenv("CAST_TIMING_MERGE");  // another merge_up_to
  const double collapse_from = cpu_seconds();
  const sdf::Bvh8 wide8 =
      sdf::collapse_to_bvh8(bvh, merge ? std::atoi(merge) : sdf::kBvh8MergeUpTo);
  std::printf("bvh8: %zu nodes, %zu packets for %zu triangles, collapsed in %.3f cpu s\n",
              wide8.nodes.size(), wide8.packets.size(), bvh.triangles.size(),
              cpu_seconds() - collapse_from);
  sdf::CpuScene scene8;
  scene8.bvh8 = &wide8;
  if (!sdf::bvh8_supported()) scene8 = scene4;

  RTCDevice device = rtcNewDevice(nullptr);
  RTCScene rtc = embree_scene(device, off);

  std::vector<float> raw(nf), raw4(nf);
  std::vector<std::int32_t> valid(nf);
  std::vector<double> ratios4, ratios8;
  auto ours = [&](const sdf::CpuScene& scene, std::vector<float>& values) {
    const double t0 = cpu_seconds();
    sdf::cast_cpu(scene, points, order, cone, tmin, 0, values.data(), valid.data(), nullptr,
                  0.0, 1.0);
    return cpu_seconds() - t0;
  };
  const double mrays = nf * rays / 1e6;
  for (int r = 0; r < rounds; ++r) {
    const double embree_s = embree_cast(rtc, m, points, cone, tmin);
    const double bvh4_s = ours(scene4, raw4);
    const double bvh8_s = ours(scene8, raw);
    ratios4.push_back(embree_s / bvh4_s);
    ratios8.push_back(embree_s / bvh8_s);
    std::printf("round %d: Mrays per cpu s: embree %.2f, bvh4 %.2f (%.3f), bvh8 %.2f (%.3f)\n", r,
                mrays / embree_s, mrays / bvh4_s, ratios4.back(), mrays / bvh8_s,
                ratios8.back());
  }
  std::sort(ratios4.begin(), ratios4.end());
  std::sort(ratios8.begin(), ratios8.end());
  std::printf("%s faces=%zu median ratio to Embree's rays/s: bvh4 %.3f, bvh8 %.3f; bvh8 values %s\n",
              argv[1], nf, ratios4[rounds / 2], ratios8[rounds / 2],
              raw == raw4 ? "equal to bvh4's" : "DIFFER from bvh4's");
  if (argc == 5) {
    std::ofstream out(argv[4], std::ios::binary);
    out.write(reinterpret_cast<const char*>(raw.data()), raw.size() * sizeof(float));
  }
  rtcReleaseScene(rtc);
  rtcReleaseDevice(device);
  return 0;
}
