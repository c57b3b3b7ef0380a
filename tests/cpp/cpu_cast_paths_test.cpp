// SPDX-License-Identifier: GPL-3.0-or-later
// The CPU engine's trees: the binary tree (through the kernels' traversal, the path of
// machines without SSE), the 4-wide one (SSE) and the 8-wide one (AVX2) give the same values
// bit for bit, and compute() casts the widest this build and CPU can run.
#include <gtest/gtest.h>

#include <cstring>
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
#include "pipeline/sdf.h"
#include "smoothing_test_meshes.h"
#include "util/test_overrides.h"

namespace sdf {
namespace {

struct Cast {
  std::vector<float> raw;
  std::vector<std::int32_t> valid;
};

// The engine's cast of every face's point through `scene`, reading the trees `widths` names.
Cast cast_faces(const Mesh& mesh, Scene& scene, const BvhWidths& widths) {
  scene.widths = widths;
  const SamplePoints points = sample_points(mesh, PointKind::Faces, 2);
  const std::vector<std::uint32_t> order = spatial_order(points, 2);
  const Cone cone = make_cone(16, 120.0, Sampling::Fibonacci, 0);
  Cast c{std::vector<float>(mesh.triangles.size()),
         std::vector<std::int32_t>(mesh.triangles.size())};
  cast_cpu(scene, points, order, cone, minimum_closeness(mesh), 2, c.raw.data(), c.valid.data(),
           nullptr, 0.0, 1.0);
  return c;
}

bool same_bits(const Cast& a, const Cast& b) {
  return a.raw.size() == b.raw.size() && a.valid == b.valid &&
         std::memcmp(a.raw.data(), b.raw.data(), a.raw.size() * sizeof(float)) == 0;
}

TEST(CpuCastPaths, EveryTreeGivesTheBinaryTreesValuesBitForBit) {
  // A sphere (every ray hits), and a soup of crossing triangles (ties, rays dropped).
  for (const test::Arrays& arrays : {test::icosphere(4), test::soup(3000, 7)}) {
    const Mesh mesh = arrays.mesh();
    Scene scene;
    scene.bvh = build_bvh(mesh);
    grow_boxes_to_cover_hits(scene.bvh);
    const Cast want = cast_faces(mesh, scene, BvhWidths{true, false, false});
    int kept = 0;
    for (std::int32_t v : want.valid) kept += v > 0;
    EXPECT_GT(kept, static_cast<int>(mesh.triangles.size()) / 3) << "the case casts rays that hit";
#if SDF_HAVE_BVH4_SSE
    scene.bvh4 = collapse_to_bvh4(scene.bvh);
    EXPECT_TRUE(same_bits(cast_faces(mesh, scene, BvhWidths{false, true, false}), want))
        << "4-wide";
#endif
#if SDF_HAVE_BVH8
    if (bvh8_supported()) {
      scene.bvh8 = collapse_to_bvh8(scene.bvh);
      EXPECT_TRUE(same_bits(cast_faces(mesh, scene, BvhWidths{false, false, true}), want))
          << "8-wide";
    }
#endif
  }
}

// Whether /proc/cpuinfo lists AVX2 and FMA (false where it cannot be read).
bool cpuinfo_lists_avx2_and_fma() {
  std::ifstream in("/proc/cpuinfo");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("flags", 0) != 0) continue;
    const std::string flags = line + " ";
    return flags.find(" avx2 ") != std::string::npos && flags.find(" fma ") != std::string::npos;
  }
  return false;
}

TEST(CpuCastPaths, ComputeCastsTheWidestTreeThisMachineRuns) {
  Options options;
  options.engine = "cpu";
  options.rays = 8;
  options.threads = 2;
  const Output out = compute(test::box(1.0, 2.0, 3.0).mesh(), options);
  const BvhWidths width = cpu_bvh_width();
  const char* expected = width.eight ? "8-wide" : width.four ? "4-wide" : "binary";
  EXPECT_NE(out.engine.find(std::string("bvh, ") + expected), std::string::npos) << out.engine;
#if SDF_X86_SIMD
  if (cpuinfo_lists_avx2_and_fma()) {
    EXPECT_TRUE(width.eight) << "an AVX2 CPU casts the 8-wide tree";
  } else {
    EXPECT_TRUE(width.four) << "an x86-64 CPU without AVX2 casts the 4-wide tree";
  }
  // Acting out a CPU without AVX2 (the overrides of tests) gives the 4-wide tree, same values.
  test_overrides().cpu_without_avx2 = true;
  const Output sse = compute(test::box(1.0, 2.0, 3.0).mesh(), options);
  test_overrides().cpu_without_avx2 = false;
  EXPECT_NE(sse.engine.find("bvh, 4-wide"), std::string::npos) << sse.engine;
  EXPECT_EQ(sse.raw, out.raw);
#else
  EXPECT_TRUE(width.binary) << "without SSE the binary tree";
#endif
  // Face points of a 1 x 2 x 3 box: every value lies within the box's diagonal.
  for (float v : out.raw) {
    EXPECT_GT(v, 0.0f);
    EXPECT_LT(v, 3.75f);
  }
}

}  // namespace
}  // namespace sdf
