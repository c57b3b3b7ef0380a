// SPDX-License-Identifier: GPL-3.0-or-later
#include "segment/segmentation.h"

#include <algorithm>
#include <stdexcept>

#include "segment/alpha_expansion.h"
#include "segment/edge_weights.h"
#include "segment/postprocess.h"
#include "segment/stage_progress.h"

namespace sdf::segment {
namespace {

// CGAL's constants (Surface_mesh_segmentation.h, Expectation_maximization.h).
constexpr double kLogAlpha = 5.0;           // log(5 x + 1) / log(6)
constexpr std::size_t kMaxIterations = 10;  // k-means and EM
constexpr double kLikelihoodGain = 1e-3;    // EM stops below this relative gain

// Where each step starts, as a share of the stage (progress). Measured on the 832k-face
// armadillo on 2 cores: the graph cut takes most of the time (4 to 7 s of 8), and the
// bilateral filter, where it runs, nine tenths of everything (70 s).
enum Step { kGraph, kValues, kClusters, kWeights, kCut, kSegments, kParts, kEnd };
constexpr double kPlain[kEnd + 1] = {0.0, 0.02, 0.03, 0.12, 0.15, 0.93, 0.95, 1.0};
constexpr double kFiltered[kEnd + 1] = {0.0, 0.01, 0.9, 0.91, 0.915, 0.99, 0.995, 1.0};

// Filled, optionally filtered, rescaled to [0, 1]; the filter's progress covers [from, to].
std::vector<double> prepare_values(const FaceGraph& graph, const double* values, std::size_t n,
                                   const SegmentOptions& options, const ProgressFn& progress,
                                   double from, double to) {
  std::vector<double> out(values, values + n);
  fill_missing_from_edge_neighbours(graph, out.data(), n);
  if (options.filter) {
    std::vector<double> filtered(n);
    bilateral_filter(graph, out.data(), n, bilateral_window(n), options.threads, filtered.data(),
                     progress, from, to);
    out.swap(filtered);
  }
  rescale_to_unit(out.data(), n);
  return out;
}

// The unary costs (n x k) and starting labels; returns the number of clusters, which is
// below the one asked for when the values take fewer distinct levels. Progress over
// `within`: k-means, the mixture, the costs.
std::size_t soft_clusters(const std::vector<double>& values, const SegmentOptions& options,
                          std::vector<Gaussian>& mixture, std::vector<double>& costs,
                          std::vector<int>& labels, StageProgress* progress = nullptr,
                          const double* within = nullptr) {
  const std::size_t n = values.size();
  std::vector<double> logs(n);
  log_normalize(values.data(), n, kLogAlpha, logs.data());
  const std::size_t k = std::min(options.clusters, n);
  auto step = [&](double from, double to) -> WorkCheck {
    if (!progress) return nullptr;
    const double span = within[1] - within[0];
    return progress->step(within[0] + from * span, within[0] + to * span);
  };
  const std::vector<double> centres =
      kmeans_centres(logs.data(), n, k, kMaxIterations, options.threads, step(0.0, 0.4));
  mixture = fit_mixture(logs.data(), n, centres, kMaxIterations, kLikelihoodGain, options.threads,
                        step(0.4, 0.85));
  costs.resize(n * mixture.size());
  labels.resize(n);
  cluster_costs(logs.data(), n, mixture, options.threads, costs.data(), labels.data(),
                step(0.85, 1.0));
  return mixture.size();
}

// What rigging reads: segment areas and means, vertex labels and weights, boundary loops.
void describe_parts(const FaceGraph& graph, const double* vertices, std::size_t vertex_count,
                    const std::int64_t* triangles, std::size_t n, const std::vector<double>& areas,
                    const SegmentOptions& options, StageProgress& progress, const double* within,
                    Segmentation& out) {
  const double step = (within[1] - within[0]) / 3.0;
  out.stats =
      segment_stats(areas.data(), out.values.data(), out.segments.data(), n, out.segment_count);
  out.vertex_labels = vertex_labels(vertex_count, triangles, areas.data(), out.segments.data(), n);
  progress.report(within[0] + step);
  out.vertex_weights = vertex_weights(vertex_count, triangles, areas.data(), out.segments.data(), n,
                                      options.weight_rings, options.threads,
                                      progress.step(within[0] + step, within[0] + 2.0 * step));
  progress.report(within[0] + 2.0 * step);
  out.boundaries = boundaries(graph, vertices, vertex_count, triangles, out.segments.data());
}

void check(std::size_t face_count, const SegmentOptions& options) {
  if (face_count == 0) throw std::invalid_argument("segmentation needs at least one face");
  if (options.clusters < 1) throw std::invalid_argument("clusters must be at least 1");
  if (!(options.min_segment_area >= 0.0 && options.min_segment_area < 1.0))
    throw std::invalid_argument("min_segment_area must be in [0, 1)");
}

// The face graph and the values clustered; progress at[kGraph] to at[kClusters] (the filter
// reports through `callback` itself).
SegmentInput prepare_input(const std::int64_t* triangles, std::size_t n, std::size_t vertex_count,
                           const double* values, const SegmentOptions& options,
                           StageProgress& progress, const ProgressFn& callback, const double* at) {
  progress.report(at[kGraph]);
  SegmentInput in;
  StageClock clock(&in.timings);
  in.graph = build_face_graph(triangles, n, vertex_count, options.threads,
                              progress.step(at[kGraph], at[kValues]));
  clock.lap("face_graph");
  progress.report(at[kValues]);
  in.values = prepare_values(in.graph, values, n, options, callback, at[kValues], at[kClusters]);
  clock.lap(options.filter ? "postprocess" : "rescale");
  return in;
}

// The steps after prepare_input; progress at[kClusters] to at[kEnd].
Segmentation segment_input(const SegmentInput& in, const double* vertices, std::size_t vertex_count,
                           const std::int64_t* triangles, std::size_t n,
                           const SegmentOptions& options, StageProgress& progress,
                           const double* at) {
  const FaceGraph& graph = in.graph;
  Segmentation out;
  out.smoothness = options.smoothness;
  out.values = in.values;
  out.timings = in.timings;
  StageClock clock(&out.timings);
  progress.report(at[kClusters]);
  std::vector<double> costs;
  const std::size_t k = soft_clusters(out.values, options, out.mixture, costs, out.clusters,
                                      &progress, &at[kClusters]);
  clock.lap("soft_clustering");
  progress.report(at[kWeights]);
  const std::vector<double> weights =
      edge_weights(graph, vertices, triangles, options.smoothness, options.threads,
                   progress.step(at[kWeights], at[kCut]));
  const std::vector<double> areas = face_areas(vertices, triangles, n, options.threads);
  clock.lap("edge_weights");  // (and the faces' areas)
  progress.report(at[kCut]);
  out.energy =
      alpha_expansion(graph, weights.data(), costs.data(), k, options.expansion,
                      out.clusters.data(), n, options.threads, &progress, at[kCut], at[kSegments]);
  clock.lap("graph_cut");
  progress.report(at[kSegments]);
  out.segments.resize(n);
  out.segment_count =
      number_segments(graph, out.clusters.data(), out.values.data(), n, out.segments.data());
  progress.report(0.5 * (at[kSegments] + at[kParts]));
  out.segment_count =
      join_small_segments(graph, vertices, triangles, areas.data(), out.values.data(), n,
                          options.min_segment_area, out.segments.data(), out.segment_count);
  clock.lap("segments");
  progress.report(at[kParts]);
  describe_parts(graph, vertices, vertex_count, triangles, n, areas, options, progress, &at[kParts],
                 out);
  clock.lap("parts");
  progress.report(at[kEnd]);
  return out;
}

// `callback` told the fraction of [from, to] that an absolute fraction is.
ProgressFn rescaled(const ProgressFn& callback, double from, double to) {
  if (!callback) return nullptr;
  return [&callback, from, to](double f) {
    return callback(std::clamp((f - from) / (to - from), 0.0, 1.0));
  };
}

}  // namespace

Segmentation segment_mesh(const double* vertices, std::size_t vertex_count,
                          const std::int64_t* triangles, std::size_t n, const double* values,
                          const SegmentOptions& options, const ProgressFn& callback) {
  check(n, options);
  StageProgress progress(callback);
  const double* at = options.filter ? kFiltered : kPlain;
  const SegmentInput in =
      prepare_input(triangles, n, vertex_count, values, options, progress, callback, at);
  return segment_input(in, vertices, vertex_count, triangles, n, options, progress, at);
}

SegmentInput prepare_segment_input(const std::int64_t* triangles, std::size_t n,
                                   std::size_t vertex_count, const double* values,
                                   const SegmentOptions& options, const ProgressFn& callback) {
  check(n, options);
  const double* at = options.filter ? kFiltered : kPlain;
  const ProgressFn own = rescaled(callback, at[kGraph], at[kClusters]);
  StageProgress progress(own);
  SegmentInput in = prepare_input(triangles, n, vertex_count, values, options, progress, own, at);
  progress.report(at[kClusters]);
  return in;
}

Segmentation segment_prepared(const SegmentInput& in, const double* vertices,
                              std::size_t vertex_count, const std::int64_t* triangles,
                              std::size_t n, const SegmentOptions& options,
                              const ProgressFn& callback) {
  check(n, options);
  if (in.values.size() != n)
    throw std::invalid_argument("the prepared segmentation input is for another face count");
  const double* at = options.filter ? kFiltered : kPlain;
  const ProgressFn own = rescaled(callback, at[kClusters], at[kEnd]);
  StageProgress progress(own);
  return segment_input(in, vertices, vertex_count, triangles, n, options, progress, at);
}

double segmentation_energy(const double* vertices, std::size_t vertex_count,
                           const std::int64_t* triangles, std::size_t n, const double* values,
                           const SegmentOptions& options, const int* clusters) {
  check(n, options);
  const FaceGraph graph = build_face_graph(triangles, n, vertex_count, options.threads);
  const std::vector<double> prepared = prepare_values(graph, values, n, options, nullptr, 0, 1);
  std::vector<Gaussian> mixture;
  std::vector<double> costs;
  std::vector<int> labels;
  const std::size_t k = soft_clusters(prepared, options, mixture, costs, labels);
  for (std::size_t f = 0; f < n; ++f)
    if (clusters[f] < 0 || static_cast<std::size_t>(clusters[f]) >= k)
      throw std::invalid_argument("a cluster label is outside [0, k)");
  const std::vector<double> weights =
      edge_weights(graph, vertices, triangles, options.smoothness, options.threads);
  return potts_energy(graph, weights.data(), costs.data(), k, clusters, n, options.threads);
}

}  // namespace sdf::segment
