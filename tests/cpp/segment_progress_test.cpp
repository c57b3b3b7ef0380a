// SPDX-License-Identifier: GPL-3.0-or-later
// Progress and cancellation of the segmentation stage: fractions that rise from 0 to 1, a
// report at every move of the graph cut, and a stop asked at any report ends the work.
#include <gtest/gtest.h>

#include <random>
#include <stdexcept>
#include <vector>

#include "segment/segmentation.h"
#include "segment_test_meshes.h"

namespace {

using namespace sdf::segment;

struct Case {
  sdf::test::Arrays mesh;
  std::vector<double> values;
};

Case noisy_dumbbell() {
  Case c;
  c.mesh = sdf::test::dumbbell(&c.values);
  std::mt19937 rng(11);
  std::normal_distribution<double> noise(0.0, 0.1);
  for (double& v : c.values) v += noise(rng);
  return c;
}

Segmentation run(const Case& c, bool cgal, bool filter, const sdf::ProgressFn& progress) {
  SegmentOptions o;
  o.expansion = ExpansionRules{cgal, cgal};
  o.filter = filter;
  return segment_mesh(c.mesh.vertices.data(), c.mesh.vertices.size() / 3, c.mesh.triangles.data(),
                      c.mesh.triangles.size() / 3, c.values.data(), o, progress);
}

TEST(SegmentProgress, RisesFromZeroToOneWithAReportPerMove) {
  const Case c = noisy_dumbbell();
  for (bool cgal : {false, true})
    for (bool filter : {false, true}) {
      std::vector<double> seen;
      const Segmentation s = run(c, cgal, filter, [&](double f) {
        seen.push_back(f);
        return true;
      });
      ASSERT_GE(seen.size(), 8u);
      EXPECT_EQ(seen.front(), 0.0);
      EXPECT_EQ(seen.back(), 1.0);
      for (std::size_t i = 1; i < seen.size(); ++i) EXPECT_LE(seen[i - 1], seen[i]);
      // The same labels as without a callback.
      EXPECT_EQ(s.segments, run(c, cgal, filter, nullptr).segments);
      // The graph cut's moves: CGAL's rules make one, the converged cut at least k = 5 (a
      // sweep), each told at its start, strictly inside the stage.
      std::size_t distinct_inside = 0;
      for (std::size_t i = 1; i < seen.size(); ++i)
        if (seen[i] != seen[i - 1] && seen[i] > 0.0 && seen[i] < 1.0) ++distinct_inside;
      EXPECT_GE(distinct_inside, cgal ? 6u : 10u);
    }
}

TEST(SegmentProgress, AStopAtAnyReportEndsTheWork) {
  // Stops asked at each fraction reported (the reports between the steps and at each move
  // come on every run; polls inside the steps come as time passes).
  const Case c = noisy_dumbbell();
  std::vector<double> seen;
  run(c, false, false, [&](double f) {
    seen.push_back(f);
    return true;
  });
  for (double stop_at : seen) {
    bool stopped = false;
    std::size_t after = 0;
    EXPECT_THROW(run(c, false, false,
                     [&](double f) {
                       after += stopped;
                       stopped = stopped || f >= stop_at;
                       return !stopped;
                     }),
                 sdf::Cancelled)
        << "stop at " << stop_at;
    EXPECT_EQ(after, 0u);  // nothing is reported after the stop
  }
}

TEST(SegmentProgress, TheCallbacksExceptionComesOut) {
  const Case c = noisy_dumbbell();
  struct Stop : std::runtime_error {
    Stop() : std::runtime_error("stop") {}
  };
  for (bool filter : {false, true}) {
    int calls = 0;
    EXPECT_THROW(run(c, false, filter,
                     [&](double f) {
                       if (++calls > 1 && f > 0.5) throw Stop();
                       return true;
                     }),
                 Stop);
  }
}

}  // namespace
