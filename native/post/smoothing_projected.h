// SPDX-License-Identifier: GPL-3.0-or-later
// Smoothing on projected points (paper 4.4, second method). Each point (face centroid or
// vertex) moves inward along its axis by half its SDF, which puts it near the medial axis;
// an octree over these points keeps the count and mean value of the points in each node; each
// point then becomes the weighted mean of the nodes within a sphere of radius equal to its own
// SDF around its projected position. A node that lies wholly inside the sphere is taken whole
// (weight = its count); a leaf that the sphere cuts weighs count x the approximate fraction of
// its cube inside the sphere. No radius to choose: the SDF gives it.
//
// Values must be lengths in mesh units (the SDF): they set both the projection and the radius.
#pragma once

#include <cstdint>
#include <vector>

#include "smooth/sdf_smooth_projected.h"

#include "mesh/mesh.h"
#include "post/value_range.h"
#include "prepare/sampling.h"
#include "util/parallel.h"
#include "util/stopwatch.h"

namespace sdf {

struct ProjectedOptions {
  int iterations = 1;  // repeats on the smoothed field, points re-projected each time (paper:
                       // "stronger smoothing can be obtained by iteratively running the method")
  // Paper 4.4 discussion: "8 was satisfying in most cases" (Table 2 times depths 2..14).
  int max_depth = 8;
  // A node branches only if it holds more than this fraction of all points (paper: "about
  // 0.2%"): fewer, larger leaves, and the query cost stops growing with the point count.
  double min_points = 0.002;
  // ... and only if its points' value is at most this times its side (paper: "compare the
  // average value of the points against the octree dimensions and if it is bigger, then we do
  // not branch"): a node already small next to the spheres that will query it gains nothing
  // from finer children. Larger ratios give finer leaves and slower queries.
  double node_size_ratio = 1.0;
  // Which value of the node's points that test uses. Mean: the paper's rule. Min: a node
  // holding any point thinner than itself still splits, so thin parts next to thick ones get
  // leaves of their own size instead of sharing a leaf whose mean the thick points set (the
  // paper's rule loses thin features there: on spot.obj the ears and horns take the head's
  // value). Costs more nodes near thin parts.
  enum class Branch { Mean, Min };
  Branch branch_on = Branch::Mean;
  // Each point gathers the points in a sphere of this share of its own value (the SDF, a
  // diameter) around its projected point. The paper's rule is 1: there a point reaches the
  // medial points a whole diameter away, across joints into parts of other thicknesses
  // (bench/smoothing_fidelity.py: it moved a clean field by 12% at the median of 13 meshes).
  double radius = 1.0;
  unsigned threads = 0;  // 0: every core
};

// One octree node (kernels/smooth/sdf_smooth_projected.h: the same bytes on the host and on an
// OpenCL device). Children of a branching node are stored next to each other from
// first_child on.
using PointOctreeNode = kern::SdfPointNode;

// ---- The rules both octree builders follow (this file's, on the host, and the OpenCL one in
// opencl/opencl_projected.cpp), so that they make the same tree node for node: nodes in
// breadth-first order (children of a branching node next to each other, in octant order,
// nodes of one level in their parents' order), sums in fixed point (kern::sdf_fixed_value). ----

// The root cube: the points' bounding cube, a little larger so every point falls strictly
// inside, and never of zero size (all points may coincide, as on a sphere).
struct PointCube {
  glm::vec3 center, corner;
  float side;
  std::uint32_t cells;  // per axis at the deepest level: 2^depth
  float scale;          // cells / side (kern::sdf_point_cell)
  PointCube(glm::vec3 lo, glm::vec3 hi, int depth);
};

// The fixed-point shift for sums of up to `count` values in [0, hi]: each value below
// 2^(62 - bits of count), so no sum reaches 2^62; hi maps to at least 2^(61 - bits of count)
// units (2^40 at 1.5M points), so a mean keeps float precision. A value below one unit (under
// 2^-40 of the largest at 1.5M points) counts as 0 in the means: an SDF does not span that.
int point_fixed_shift(float hi, std::size_t count);

// A node of `count` points (> 0) whose fixed-point values sum to `sum`, with no children yet.
PointOctreeNode make_point_node(glm::vec3 center, float half_side, std::uint32_t count,
                                std::uint64_t sum, int shift);

// The centre of child `octant` (bit 0 x, bit 1 y, bit 2 z) of `parent`.
glm::vec3 point_child_center(const PointOctreeNode& parent, unsigned octant);

// Whether a node of `level` branches: above the deepest level, holding more than
// branch_above points (min_points x all points), and with its points' value (their mean, or
// `min_value` when options.branch_on is Min) at most node_size_ratio x its side.
bool point_node_branches(const PointOctreeNode& node, int level, float min_value,
                         const ProjectedOptions& options, double branch_above);

// Checks options as build_point_octree does (std::invalid_argument).
void check_projected_options(const ProjectedOptions& options);

// kernels/smooth/sdf_smooth_projected.h's sdf_cube_fraction_in_sphere: approximate fraction of a
// cube of side `side` whose centre is `distance` from the centre of a sphere of radius
// `radius` that lies inside the sphere (the cube taken as the ball of equal volume).
float cube_fraction_in_sphere(float side, float distance, float radius);

// Octree over points with values (>= 0); nodes[0] is the root. Throws std::invalid_argument
// for a negative or non-finite value and for bad options (max_depth outside [0, 20],
// min_points outside [0, 1], node_size_ratio < 0).
// Built on options.threads from the points in Morton order (a parallel radix sort; every node
// is then a run of that order, its sum a difference of two prefix sums); the nodes do not
// depend on the thread count.
std::vector<PointOctreeNode> build_point_octree(const glm::vec3* points, const float* values,
                                                std::size_t count, const ProjectedOptions& options);

// The weighted mean of the nodes that a sphere (centre, radius) gathers, as described above.
// Returns false (and leaves *mean alone) when it gathers nothing.
bool gather_sphere(const PointOctreeNode* nodes, glm::vec3 center, float radius, float* mean);

// The range of projected smoothing's input: n values, each finite and >= 0. Throws
// std::invalid_argument naming the first that is not, or for iterations < 0 or bad options.
ValueRange checked_projected_input(const float* values, std::size_t n,
                                   const ProjectedOptions& options);

// values: one per face (kind Faces) or vertex (kind Vertices), >= 0. Returns the smoothed
// values, clamped to the input's [min, max]. A point that gathers nothing keeps its value.
// Throws std::invalid_argument for negative or non-finite values or bad options.
// (opencl/opencl_projected.h: the same on an OpenCL device.)
std::vector<float> smooth_projected(const Mesh& mesh, PointKind kind, const float* values,
                                    const ProjectedOptions& options,
                                    const ProgressFn& progress = nullptr,
                                    double progress_from = 0.0, double progress_to = 1.0);

// The same, writing the result into out[0, point count) (which may be the caller's final
// array, e.g. a NumPy one: no copy of the result is made). out must not overlap values.
// timings: where given, seconds per stage are added (checks, frames, points, the octree's
// "octree: Morton order", "octree: sums" and "octree: nodes", gather;
// bench/smoothing_stages.py prints them).
void smooth_projected_into(const Mesh& mesh, PointKind kind, const float* values,
                           const ProjectedOptions& options, float* out,
                           const ProgressFn& progress = nullptr, double progress_from = 0.0,
                           double progress_to = 1.0, StageTimings* timings = nullptr);

}  // namespace sdf
