// SPDX-License-Identifier: GPL-3.0-or-later
// Soft clustering: CGAL's random sequence, a mixture recovered from a known sample.
#include <gtest/gtest.h>

#include <cstdlib>
#include <random>
#include <vector>

#include "segment/cgal_random.h"
#include "segment/soft_clustering.h"

namespace {

using namespace sdf::segment;

// The generator is POSIX's drand48 family: lrand48 after srand48(seed) gives the same
// 31-bit outputs, which CgalRandom buckets into [0, 2^15) for its first draw.
TEST(SegmentSoftClustering, RandomSequenceIsDrand48s) {
  srand48(1340818006);
  CgalRandom random(1340818006u);
  lrand48();  // the draw CGAL's constructor makes
  for (int i = 0; i < 100; ++i) {
    const long expected = lrand48();
    EXPECT_EQ(random.uniform_index(std::size_t{1} << 31), static_cast<std::size_t>(expected));
  }
}

TEST(SegmentSoftClustering, MixtureOfTwoGaussiansIsRecovered) {
  std::mt19937 rng(5);
  std::normal_distribution<double> thin(0.2, 0.03), thick(0.7, 0.05);
  std::vector<double> x;
  for (int i = 0; i < 30000; ++i) x.push_back(i % 10 < 3 ? thin(rng) : thick(rng));
  const auto centres = kmeans_centres(x.data(), x.size(), 2, 10, 2);
  ASSERT_EQ(centres.size(), 2u);
  const auto mixture = fit_mixture(x.data(), x.size(), centres, 50, 1e-9, 2);
  ASSERT_EQ(mixture.size(), 2u);
  EXPECT_NEAR(mixture[0].mean, 0.2, 0.003);
  EXPECT_NEAR(mixture[1].mean, 0.7, 0.003);
  EXPECT_NEAR(mixture[0].deviation, 0.03, 0.003);
  EXPECT_NEAR(mixture[1].deviation, 0.05, 0.003);
  EXPECT_NEAR(mixture[0].weight, 0.3, 0.01);
  std::vector<double> costs(2 * x.size());
  std::vector<int> labels(x.size());
  cluster_costs(x.data(), x.size(), mixture, 2, costs.data(), labels.data());
  int right = 0;
  for (std::size_t i = 0; i < x.size(); ++i) right += labels[i] == (i % 10 < 3 ? 0 : 1);
  EXPECT_GT(right, 0.999 * x.size());
}

TEST(SegmentSoftClustering, FewerDistinctValuesThanClustersGiveFewerClusters) {
  const std::vector<double> x{0.1, 0.1, 0.5, 0.5, 0.5};
  EXPECT_EQ(kmeans_centres(x.data(), x.size(), 4, 10, 1).size(), 2u);
}

TEST(SegmentSoftClustering, SameResultForAnyThreadCount) {
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<double> x(100000);
  for (double& v : x) v = u(rng) * u(rng);
  const auto c1 = kmeans_centres(x.data(), x.size(), 5, 10, 1);
  const auto m1 = fit_mixture(x.data(), x.size(), c1, 10, 1e-3, 1);
  for (unsigned threads : {2u, 3u, 8u}) {
    EXPECT_EQ(kmeans_centres(x.data(), x.size(), 5, 10, threads), c1);
    const auto m = fit_mixture(x.data(), x.size(), c1, 10, 1e-3, threads);
    for (std::size_t c = 0; c < 5; ++c) {
      EXPECT_EQ(m[c].mean, m1[c].mean);
      EXPECT_EQ(m[c].deviation, m1[c].deviation);
      EXPECT_EQ(m[c].weight, m1[c].weight);
    }
  }
}

}  // namespace
