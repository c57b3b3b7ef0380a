// SPDX-License-Identifier: GPL-3.0-or-later
// The SDF made ready for clustering, as CGAL's sdf_values(postprocess = true) does it:
// missing values filled, one bilateral filter pass, a linear rescale to [0, 1].
#pragma once

#include <cstddef>

#include "segment/face_graph.h"
#include "util/parallel.h"

namespace sdf::segment {

// Faces whose value is NaN take the mean of their edge neighbours that have one (neighbours
// read before any face is filled); those with none take the smallest value. All NaN: all 0.
void fill_missing_from_edge_neighbours(const FaceGraph& graph, double* values, std::size_t n);

// CGAL's window for the filter: floor(sqrt(faces / 2000)) + 1 rings of edge neighbours
// (1 up to 2000 faces, 2 up to 8000, 25 at 1.2M faces).
std::size_t bilateral_window(std::size_t face_count);

// One pass of a bilateral filter over edge-neighbour rings: each face takes the mean of the
// faces within `window` rings (itself included), weighted by exp(-d^2 / (2 s^2)) for ring
// distance d, s = window / 2, times exp(-dv^2 / (2 r^2)) for the value difference dv, where r
// is 1.5 times the RMS difference to the face's value over the window (a face whose window is
// flat keeps its value). Reads `values`, writes `out` (may not alias). Parallel over faces;
// the result does not depend on `threads`. Progress as parallel_for's: it covers
// [progress_from, progress_to] and may cancel.
void bilateral_filter(const FaceGraph& graph, const double* values, std::size_t n,
                      std::size_t window, unsigned threads, double* out,
                      const ProgressFn& progress = nullptr, double progress_from = 0.0,
                      double progress_to = 1.0);

// (x - min) / (max - min); a constant field becomes all 0. Returns false for a constant one.
bool rescale_to_unit(double* values, std::size_t n);

}  // namespace sdf::segment
