// SPDX-License-Identifier: GPL-3.0-or-later
// The segmentation stage: per-face SDF values in, parts out. Soft clustering (a Gaussian
// mixture over log-normalised values), hard clustering (alpha expansion over the face graph),
// segments (connected pieces of clusters), and what rigging needs from them.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "segment/alpha_expansion.h"
#include "segment/face_graph.h"
#include "segment/parts.h"
#include "segment/segments.h"
#include "segment/small_segments.h"
#include "segment/soft_clustering.h"
#include "util/parallel.h"
#include "util/stopwatch.h"

namespace sdf::segment {

struct SegmentOptions {
  std::size_t clusters = 5;      // k, at least 1 (fewer when the mesh has fewer faces)
  double smoothness = 0.26;      // lambda: weight of the cut cost against the cluster costs
  bool filter = false;           // CGAL's post-processing filter before clustering (bilateral)
  ExpansionRules expansion;      // CGAL's rules by default (ties move, first move only)
  std::size_t weight_rings = 2;  // rings the soft vertex weights fall off over
  // A minimum part size, as a share of the mesh's area in [0, 1): a segment below it joins
  // the neighbour it shares the longest boundary with (join_small_segments). 0: off.
  // Clusters stay the graph cut's, so a joined segment may hold faces of several clusters.
  double min_segment_area = 0.0;
  unsigned threads = 0;  // 0 = every core; results do not depend on it
};

struct Segmentation {
  std::vector<double> values;     // the values clustered: filled, (filtered,) rescaled to [0, 1]
  std::vector<Gaussian> mixture;  // the fitted components, by ascending mean
  std::vector<int> clusters;      // per face, in [0, k): 0 the thinnest
  std::vector<int> segments;      // per face, in [0, segment_count): by ascending mean
  std::size_t segment_count = 0;
  double energy = 0.0;      // of `clusters`
  double smoothness = 0.0;  // the lambda used (segment_to_count chooses it)
  SegmentStats stats;
  std::vector<int> vertex_labels;
  VertexWeights vertex_weights;
  std::vector<Boundary> boundaries;
  StageTimings timings;
};

// vertices (vertex_count, 3) and triangles (face_count, 3, 0-based, checked by the caller),
// values per face (NaN where missing). Throws std::invalid_argument for no face, k < 1 or a
// min_segment_area outside [0, 1).
// `progress` is called on the calling thread with the fraction done: between the steps, and
// at most every 20 ms inside the long ones (the filter, the mixture's iterations, each move
// of the graph cut and inside its max-flow). Returning false stops the work (Cancelled); an
// exception it throws stops the work and comes out of segment_mesh.
Segmentation segment_mesh(const double* vertices, std::size_t vertex_count,
                          const std::int64_t* triangles, std::size_t face_count,
                          const double* values, const SegmentOptions& options,
                          const ProgressFn& progress = nullptr);

// What segment_mesh computes before the clusters and smoothness matter: the face graph, and
// the values clustered (filled, filtered when options.filter, rescaled to [0, 1]), with the
// timings of both. Made once, it serves several segmentations of one mesh (segment_to_count:
// the filter, the costliest step, runs once). `progress` is told [0, 1] of this work.
struct SegmentInput {
  FaceGraph graph;
  std::vector<double> values;
  StageTimings timings;
};
SegmentInput prepare_segment_input(const std::int64_t* triangles, std::size_t face_count,
                                   std::size_t vertex_count, const double* values,
                                   const SegmentOptions& options,
                                   const ProgressFn& progress = nullptr);

// segment_mesh's steps after prepare_segment_input, for `input` made with the same mesh and
// options.filter: segment_mesh's result. `progress` is told [0, 1] of this work.
Segmentation segment_prepared(const SegmentInput& input, const double* vertices,
                              std::size_t vertex_count, const std::int64_t* triangles,
                              std::size_t face_count, const SegmentOptions& options,
                              const ProgressFn& progress = nullptr);

// The Potts energy that segment_mesh minimises for these values and options, of any
// labelling `clusters` (values already in [0, 1], as Segmentation::values): to compare
// another optimiser's labels on the same terms.
double segmentation_energy(const double* vertices, std::size_t vertex_count,
                           const std::int64_t* triangles, std::size_t face_count,
                           const double* values, const SegmentOptions& options,
                           const int* clusters);

}  // namespace sdf::segment
