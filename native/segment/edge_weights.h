// SPDX-License-Identifier: GPL-3.0-or-later
// What cutting the face graph at each edge costs: cheap across concave creases, where
// people see parts meet, dear across flat and convex ones (CGAL's weights).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "segment/face_graph.h"
#include "segment/stage_progress.h"

namespace sdf::segment {

// Per pair: -log(max(w, 5e-6)) * smoothness * 100, where w = 1 - |theta| / 180 from the
// signed angle theta in degrees between the two faces' planes (CGAL's
// approximate_dihedral_angle: +-180 flat, positive where the edge is concave), times 0.08 on
// convex and flat edges. vertices: (vertex_count, 3) row-major. Parallel over pairs; `check`
// is called now and then (on this thread) and may throw to stop.
std::vector<double> edge_weights(const FaceGraph& graph, const double* vertices,
                                 const std::int64_t* triangles, double smoothness, unsigned threads,
                                 const WorkCheck& check = nullptr);

}  // namespace sdf::segment
