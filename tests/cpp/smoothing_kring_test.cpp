// SPDX-License-Identifier: GPL-3.0-or-later
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "mesh/mesh_weld.h"
#include "post/smoothing_kring.h"
#include "smoothing_test_meshes.h"

namespace sdf {
namespace {

KringOptions with_k(int k, double corner = 0.0) {
  KringOptions o;
  o.k = k;
  o.corner_angle = corner;
  return o;
}

TEST(KringSmoothing, KZeroIsTheIdentity) {
  const Mesh mesh = test::icosphere(2).mesh();
  for (PointKind kind : {PointKind::Faces, PointKind::Vertices}) {
    const std::size_t n = kind == PointKind::Faces ? mesh.triangles.size() : mesh.vertices.size();
    const std::vector<float> v = test::noisy(n, 3.0f, 1.0f, 1);
    EXPECT_EQ(smooth_kring(mesh, kind, v.data(), with_k(0)), v);
  }
}

TEST(KringSmoothing, ConstantStaysExactlyConstant) {
  const Mesh mesh = test::split_cube(6).mesh();
  for (PointKind kind : {PointKind::Faces, PointKind::Vertices})
    for (double corner : {0.0, 30.0}) {
      const std::size_t n = kind == PointKind::Faces ? mesh.triangles.size() : mesh.vertices.size();
      const std::vector<float> v(n, 0.1f);  // not a sum of powers of two
      EXPECT_EQ(smooth_kring(mesh, kind, v.data(), with_k(3, corner)), v);
    }
}

TEST(KringSmoothing, FaceRingsByHand) {
  // A strip of triangles: face t has vertices t, t + 1, t + 2, so faces share a vertex with
  // the faces up to two away.
  test::Arrays a;
  for (int i = 0; i < 10; ++i)
    a.vertices.insert(a.vertices.end(), {double(i / 2), double(i % 2), 0.0});
  for (std::int64_t t = 0; t < 8; ++t) a.triangles.insert(a.triangles.end(), {t, t + 1, t + 2});
  const Mesh mesh = a.mesh();
  std::vector<float> v(8, 0.0f);
  v[0] = 1.0f;
  KringOptions o = with_k(1);
  o.sigma = 0.5;  // ring 1 weighs exp(-2)
  const std::vector<float> s = smooth_kring(mesh, PointKind::Faces, v.data(), o);
  const double w1 = std::exp(-2.0);
  EXPECT_FLOAT_EQ(s[0], 1.0 / (1.0 + 2.0 * w1));  // ring 1 of face 0: faces 1, 2
  EXPECT_FLOAT_EQ(s[1], w1 / (1.0 + 3.0 * w1));   // faces 0, 2, 3
  EXPECT_FLOAT_EQ(s[2], w1 / (1.0 + 4.0 * w1));   // faces 0, 1, 3, 4
  EXPECT_EQ(s[3], 0.0f);                          // face 0 is in ring 2 of face 3
  // k = 2 reaches face 0 from face 4 (ring 2: 0, 1, 5, 6 beyond ring 1: 2, 3, 5, 6).
  o = with_k(2);
  o.sigma = 1.0;
  const std::vector<float> s2 = smooth_kring(mesh, PointKind::Faces, v.data(), o);
  const double r1 = std::exp(-0.5), r2 = std::exp(-2.0);
  EXPECT_FLOAT_EQ(s2[4], r2 / (1.0 + 4.0 * r1 + 3.0 * r2));  // ring 2 of face 4: 0, 1, 7
  EXPECT_EQ(s2[5], 0.0f);
}

TEST(KringSmoothing, VertexRingsByHand) {
  const Mesh mesh = test::grid(4, 1).mesh();  // vertices 0..4 bottom, 5..9 top
  std::vector<float> v(10, 0.0f);
  v[0] = 1.0f;
  KringOptions o = with_k(1);
  o.sigma = 1.0;
  const std::vector<float> s = smooth_kring(mesh, PointKind::Vertices, v.data(), o);
  const double w1 = std::exp(-0.5);
  EXPECT_FLOAT_EQ(s[0], 1.0 / (1.0 + 3.0 * w1));  // neighbours of 0: 1, 5, 6 (diagonal)
  EXPECT_FLOAT_EQ(s[1], w1 / (1.0 + 4.0 * w1));   // neighbours of 1: 0, 2, 6, 7
  EXPECT_EQ(s[2], 0.0f);
}

TEST(KringSmoothing, FaceRingIdentityMatchesAFaceWalk) {
  // The fast face path (vertex walk) against the corner path with a crease angle so large
  // that every step weighs 1: a plain walk from face to face.
  const Mesh mesh = test::icosphere(3).mesh();
  const std::vector<float> v = test::noisy(mesh.triangles.size(), 2.0f, 1.0f, 7);
  for (int k : {1, 2, 4}) {
    const std::vector<float> fast = smooth_kring(mesh, PointKind::Faces, v.data(), with_k(k));
    const std::vector<float> walk = smooth_kring(mesh, PointKind::Faces, v.data(), with_k(k, 1e12));
    for (std::size_t f = 0; f < v.size(); ++f) ASSERT_NEAR(fast[f], walk[f], 1e-6) << f;
  }
}

TEST(KringSmoothing, NoiseGoesDownAndValuesStayInRange) {
  const Mesh mesh = test::icosphere(4).mesh();
  for (PointKind kind : {PointKind::Faces, PointKind::Vertices}) {
    const std::size_t n = kind == PointKind::Faces ? mesh.triangles.size() : mesh.vertices.size();
    const std::vector<float> v = test::noisy(n, 2.0f, 0.5f, 3);
    const auto [lo, hi] = std::minmax_element(v.begin(), v.end());
    for (int k : {1, 3}) {
      const std::vector<float> s = smooth_kring(mesh, kind, v.data(), with_k(k));
      // k = 1 weighs ring 1 by exp(-2) only (sigma = k / 2).
      EXPECT_LT(test::variance(s), (k == 1 ? 0.5 : 0.1) * test::variance(v));
      for (float x : s) {
        ASSERT_GE(x, *lo);
        ASSERT_LE(x, *hi);
      }
    }
  }
}

TEST(KringSmoothing, SplitSeamsSmoothLikeTheWeldedMesh) {
  // The split cube against the same cube with its vertices merged by hand.
  const test::Arrays split = test::split_cube(5);
  const Mesh split_mesh = split.mesh();
  test::Arrays welded;
  std::map<std::array<double, 3>, std::int64_t> index;
  std::vector<std::int64_t> remap;
  for (std::size_t v = 0; v < split.vertices.size() / 3; ++v) {
    const std::array<double, 3> p = {split.vertices[3 * v], split.vertices[3 * v + 1],
                                     split.vertices[3 * v + 2]};
    auto it = index.find(p);
    if (it == index.end()) {
      it = index.emplace(p, static_cast<std::int64_t>(welded.vertices.size() / 3)).first;
      welded.vertices.insert(welded.vertices.end(), p.begin(), p.end());
    }
    remap.push_back(it->second);
  }
  for (std::int64_t t : split.triangles) welded.triangles.push_back(remap[t]);
  const Mesh welded_mesh = welded.mesh();

  const std::vector<float> fv = test::noisy(split_mesh.triangles.size(), 1.0f, 0.5f, 5);
  EXPECT_EQ(smooth_kring(split_mesh, PointKind::Faces, fv.data(), with_k(3)),
            smooth_kring(welded_mesh, PointKind::Faces, fv.data(), with_k(3)));
  // Vertex values: the split copies carry their welded vertex's value.
  const std::vector<float> wv = test::noisy(welded_mesh.vertices.size(), 1.0f, 0.5f, 6);
  std::vector<float> sv(split_mesh.vertices.size());
  for (std::size_t v = 0; v < sv.size(); ++v) sv[v] = wv[remap[v]];
  const std::vector<float> ws =
      smooth_kring(welded_mesh, PointKind::Vertices, wv.data(), with_k(2));
  const std::vector<float> ss = smooth_kring(split_mesh, PointKind::Vertices, sv.data(), with_k(2));
  for (std::size_t v = 0; v < sv.size(); ++v) ASSERT_EQ(ss[v], ws[remap[v]]);
  // Without merging, the sides are separate sheets and smooth differently.
  KringOptions apart = with_k(3);
  apart.weld_tolerance = -1.0;
  EXPECT_NE(smooth_kring(split_mesh, PointKind::Faces, fv.data(), apart),
            smooth_kring(welded_mesh, PointKind::Faces, fv.data(), with_k(3)));
}

// Split copies carrying different values: the split mesh smooths as the welded one holding
// their means, summed in double in index order (the serial loop that the parallel merge of
// the copies' values replaced), with and without corner preservation (vertex normals
// gathered per vertex where they were scattered per face), on any thread count.
TEST(KringSmoothing, SplitCopiesSmoothAsTheirSeriallySummedMeans) {
  const test::Arrays split = test::split_cube(6);
  const Mesh split_mesh = split.mesh();
  const Weld weld = weld_vertices(split_mesh.vertices.data(), split_mesh.vertices.size(),
                                  weld_tolerance(split_mesh));
  test::Arrays welded;
  welded.vertices.resize(3 * weld.count);
  for (std::size_t v = split_mesh.vertices.size(); v-- > 0;)
    for (int a = 0; a < 3; ++a) welded.vertices[3 * weld.merged[v] + a] = split.vertices[3 * v + a];
  for (std::int64_t t : split.triangles) welded.triangles.push_back(weld.merged[t]);
  const Mesh welded_mesh = welded.mesh();
  const std::vector<float> sv = test::noisy(split_mesh.vertices.size(), 1.0f, 0.5f, 11);
  std::vector<double> sum(weld.count, 0.0);
  std::vector<int> count(weld.count, 0);
  for (std::size_t v = 0; v < sv.size(); ++v) {
    sum[weld.merged[v]] += sv[v];
    ++count[weld.merged[v]];
  }
  const auto [lo, hi] = std::minmax_element(sv.begin(), sv.end());
  std::vector<float> wv(weld.count);
  for (std::size_t w = 0; w < wv.size(); ++w)
    wv[w] = std::min(*hi, std::max(*lo, static_cast<float>(sum[w] / count[w])));
  for (double corner : {0.0, 40.0})
    for (unsigned threads : {1u, 3u, 8u}) {
      KringOptions o = with_k(2, corner);
      o.threads = threads;
      const std::vector<float> ss = smooth_kring(split_mesh, PointKind::Vertices, sv.data(), o);
      const std::vector<float> ws = smooth_kring(welded_mesh, PointKind::Vertices, wv.data(), o);
      for (std::size_t v = 0; v < sv.size(); ++v)
        ASSERT_EQ(ss[v], ws[weld.merged[v]])
            << "vertex " << v << ", corner " << corner << ", threads " << threads;
    }
}

TEST(KringSmoothing, CornerPreservationKeepsSidesApart) {
  // A cube whose top side holds 1 and the rest 0: without corner preservation the top's edge
  // faces take in values from the sides; with it (30 degrees) the 90-degree crease holds.
  const Mesh mesh = test::split_cube(8).mesh();
  std::vector<float> v(mesh.triangles.size(), 0.0f);
  const std::size_t per_side = mesh.triangles.size() / 6;
  std::fill(v.begin(), v.begin() + per_side, 1.0f);  // side 0 is +z
  const std::vector<float> plain = smooth_kring(mesh, PointKind::Faces, v.data(), with_k(3));
  const std::vector<float> kept = smooth_kring(mesh, PointKind::Faces, v.data(), with_k(3, 30.0));
  const float plain_low = *std::min_element(plain.begin(), plain.begin() + per_side);
  const float kept_low = *std::min_element(kept.begin(), kept.begin() + per_side);
  EXPECT_LT(plain_low, 0.8f);
  EXPECT_GT(kept_low, 0.95f);
  // Inside a flat side nothing changes.
  const float kept_side = *std::max_element(kept.begin() + per_side, kept.end());
  EXPECT_LT(kept_side, 0.05f);
}

TEST(KringSmoothing, DefaultKFollowsThePaper) {
  EXPECT_EQ(default_kring_k(1000), 1);
  EXPECT_EQ(default_kring_k(20000), 2);
  EXPECT_EQ(default_kring_k(500000), 5);
  EXPECT_EQ(default_kring_k(1000000), 6);
  EXPECT_EQ(default_kring_k(1000000000), 12);
  EXPECT_EQ(default_kring_k(std::size_t(1) << 62), 16);
}

TEST(KringSmoothing, RejectsBadInput) {
  const Mesh mesh = test::icosphere(1).mesh();
  std::vector<float> v(mesh.triangles.size(), 1.0f);
  KringOptions o = with_k(2);
  o.sigma = -1.0;
  EXPECT_THROW(smooth_kring(mesh, PointKind::Faces, v.data(), o), std::invalid_argument);
  EXPECT_THROW(smooth_kring(mesh, PointKind::Faces, v.data(), with_k(300)), std::invalid_argument);
  v[3] = NAN;
  EXPECT_THROW(smooth_kring(mesh, PointKind::Faces, v.data(), with_k(2)), std::invalid_argument);
}

TEST(KringSmoothing, SameResultForAnyThreadCount) {
  const Mesh mesh = test::icosphere(4).mesh();
  const std::vector<float> v = test::noisy(mesh.triangles.size(), 2.0f, 0.5f, 9);
  KringOptions one = with_k(3), many = with_k(3);
  one.threads = 1;
  many.threads = 7;
  EXPECT_EQ(smooth_kring(mesh, PointKind::Faces, v.data(), one),
            smooth_kring(mesh, PointKind::Faces, v.data(), many));
}

TEST(KringSmoothing, SameResultForAnyThreadCountOnSeveralSetupBlocks) {
  // 81,920 faces and 40,962 vertices: more than one block in each parallel setup stage
  // (Morton codes and their sort: 64k items; vertex neighbours: 16k vertices).
  const Mesh mesh = test::icosphere(6).mesh();
  for (PointKind kind : {PointKind::Faces, PointKind::Vertices}) {
    const std::size_t n = kind == PointKind::Faces ? mesh.triangles.size() : mesh.vertices.size();
    const std::vector<float> v = test::noisy(n, 2.0f, 0.5f, 10);
    KringOptions one = with_k(2), many = with_k(2);
    one.threads = 1;
    many.threads = 3;
    EXPECT_EQ(smooth_kring(mesh, kind, v.data(), one), smooth_kring(mesh, kind, v.data(), many));
  }
}

}  // namespace
}  // namespace sdf
