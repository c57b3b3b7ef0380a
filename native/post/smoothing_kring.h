// SPDX-License-Identifier: GPL-3.0-or-later
// Smoothing on the mesh (paper 4.4, first method): each point becomes the Gaussian-weighted
// mean of the points in its rings 0..k, the weight a function of the ring index only.
//
// Rings are taken on the mesh with duplicate positions merged (mesh_weld.h), so they cross
// UV and normal seams. Vertex values: ring r+1 = vertices sharing an edge with ring r (the
// paper's rule). Face values: ring r+1 = faces sharing a vertex with ring r (CGAL's
// Neighbor_selector_by_vertex), which is the same as: face g is in ring 1 + min over its
// corners of the edge distance from the centre face's corners. The code walks vertices and
// uses that identity, which visits far fewer items than a face-to-face walk.
//
// Optional corner preservation (paper: "the dihedral angle between the connected triangles
// from 2 consecutive iterations can be used as additional weight"): a point reached in ring
// r+1 from a point of ring r carries the parent's factor times exp(-1/2 (angle / corner)^2),
// angle = between their normals (face normals, or area-weighted vertex normals); the best
// parent in ring r counts. Values beyond a crease sharper than `corner_angle` fade out.
#pragma once

#include <cstddef>
#include <vector>

#include "mesh/mesh.h"
#include "prepare/sampling.h"
#include "util/parallel.h"
#include "util/stopwatch.h"

namespace sdf {

struct KringOptions {
  int k = -1;                    // rings around each point; -1: default_kring_k(face count)
  double sigma = 0.0;            // Gaussian deviation over the ring index; 0: k / 2 (CGAL's
                                 // Bilateral_filtering uses window / 2)
  double corner_angle = 0.0;     // degrees; 0: no corner preservation
  double weld_tolerance = 1e-6;  // relative to the largest bounding-box side; < 0: no merging
  unsigned threads = 0;          // 0: every core
};

// k from the mesh size, as the paper's discussion reports (4.4): "meshes up to 20k triangles
// required radius of 2, while larger meshes ... with 500k+ triangles radius of 5+". This is
// the line through those two points in log(faces): k = round(2 + 3 ln(m / 20000) / ln 25),
// clamped to [1, 16] (about 1 below 6k faces, 6 at 1M, 8 at 8M). For comparison CGAL's
// get_window_size grows faster: floor(sqrt(m / 2000)) + 1 (4 at 20k, 16 at 500k).
int default_kring_k(std::size_t face_count);

// values: one per face (kind Faces) or per vertex (kind Vertices). Returns the smoothed values,
// each clamped to the input's [min, max] (so rounding can neither leave the range nor move a
// constant field). k = 0 returns the values unchanged. Throws std::invalid_argument for bad
// options. Progress covers [progress_from, progress_to] and can cancel (throws Cancelled).
std::vector<float> smooth_kring(const Mesh& mesh, PointKind kind, const float* values,
                                const KringOptions& options, const ProgressFn& progress = nullptr,
                                double progress_from = 0.0, double progress_to = 1.0);

// The same, writing the result into out[0, point count) (which may be the caller's final
// array, e.g. a NumPy one: no serial zeroing and copy of 4 bytes a point). out must not
// overlap values. With `timings`, appends the seconds of each stage, in order
// (bench/kring_stages.py prints them).
void smooth_kring_into(const Mesh& mesh, PointKind kind, const float* values,
                       const KringOptions& options, float* out,
                       const ProgressFn& progress = nullptr, double progress_from = 0.0,
                       double progress_to = 1.0, StageTimings* timings = nullptr);

}  // namespace sdf
