// SPDX-License-Identifier: GPL-3.0-or-later
// Grows the boxes of a binary BVH so that traversal prunes only boxes that hold no hit, making
// every engine and tree shape (binary on OpenCL, 4- or 8-wide on the CPU) return the nearest
// hit over all triangles, bit for bit the same (up to the limit below). Without it, two things let
// a box test drop the true nearest hit when another hit lies within a few ulps of it (measured: one
// ray of the teapot's 190k went to the second-nearest triangle through the binary and 4-wide
// trees):
//  - the triangle test accepts points up to SDF_BARYCENTRIC_SLACK outside a triangle, so
//    outside its box;
//  - slab distances are rounded ((lo - o) / d, or lo / d - o / d fused or not).
// What the margin does not bound: the rounding of the triangle test's own t, which grows as
// a ray grazes a triangle (about t * 6e-8 / sin of the angle between them). A ray within a
// fraction of a degree of a triangle's plane, crossing an edge where two hits lie closer
// than that error, could still be decided differently by differently shaped trees; no test
// mesh has shown it.
#pragma once

#include "accel/bvh.h"

namespace sdf {

// The growth for a tree whose triangles' box is (lo, hi) and whose longest edge component
// (of v1 - v0 and v2 - v0) is `edge`; 0 for no triangle (lo > hi). The formula below.
float tree_margin(glm::vec3 lo, glm::vec3 hi, float edge);

// The growth used by grow_boxes_to_cover_hits: 4 x the slack of the largest triangle edge
// (per axis) plus 2^-20 of the largest coordinate (16 ulps and more at the scene's scale).
float bvh_box_margin(const Bvh& bvh, unsigned threads = 0);

// Grows every node box by bvh_box_margin(bvh) on each side. Call once, after build_bvh and
// before traversing or collapsing the tree. `threads` as everywhere (0: every core).
void grow_boxes_to_cover_hits(Bvh& bvh, unsigned threads = 0);

}  // namespace sdf
