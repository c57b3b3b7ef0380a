// SPDX-License-Identifier: GPL-3.0-or-later
// Which way faces point. The SDF casts rays against the outward normal, so a mesh wound
// inside out (or with some faces flipped) would measure nothing. Stage 0 of the pipeline.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "mesh/mesh.h"
#include "util/stopwatch.h"

namespace sdf {

enum class Orientation {
  Auto,  // make each part consistent, then outward (below)
  AsIs,  // trust the winding
  Flip,  // reverse every face
};

struct OrientationReport {
  std::size_t flipped_faces = 0;  // faces whose winding the computation reversed
  std::size_t parts = 0;          // parts the mesh was seen as (Auto only)
  // Per face, 1 where it was reversed; empty when none was (no cost for the common case).
  // What ran on the oriented mesh afterwards (projected smoothing's inward axes) needs it.
  std::vector<std::uint8_t> reversed;
};

// Auto:
// 1. Within each patch of faces joined by manifold edges (edges of exactly two faces, an edge
//    being its two ends' positions, so that unwelded seams and triangle soups join too), faces
//    are made to agree with their neighbours (a shared edge runs opposite ways in two faces
//    that agree), keeping the winding of the larger area where the patch disagrees.
// 2. Patches that touch (share a vertex position, so unwelded seams count as touching) form a
//    part; a part whose signed volume, taken about its bounding-box centre, is clearly
//    negative (below -1e-6 x its area x the larger of its bounding-box diagonal and its
//    farthest coordinate) is reversed. Open parts are judged the same way: their volume is
//    indicative, and only a clearly negative one is acted on. A flat sheet whose box centre
//    lies on its plane (volume 0, its corners' rounding under the threshold) is left alone;
//    one whose centre lies off it (a triangle's) is turned to face away from the centre: a
//    sheet has no inside, and casts nothing either way.
// 3. Except a part that lies inside another (orientation_nesting.h: the inner wall of a hollow
//    solid, a bubble): it keeps its winding relative to the innermost part around it, reversed
//    only when that one is. A cavity wound inward stays so; a mesh wound inside out as a whole
//    is turned outward as a whole. A separate solid inside another (an eye inside a closed
//    head) is treated alike: right when the two were wound alike, but an eye wound inside out
//    inside a head wound outward stays inside out (its winding alone cannot tell it from a
//    cavity's wall).
// Reverses faces in place (swapping two corners) and reports what it did. Runs on `threads`
// (0 = every core); the result does not depend on the thread count.
// steps: where given, Auto's steps' seconds are appended ('orientation: edges', 'patches',
// 'parts', 'volumes', 'nesting').
OrientationReport orient(Mesh& mesh, Orientation mode, unsigned threads = 0,
                         StageTimings* steps = nullptr);

// What orient() would do, without doing it (the mesh is only read), and then doing it:
// orient() is apply_orientation(mesh, decide_orientation(mesh, ...)). The OpenCL engine's
// device-built tree casts while the orientation is decided (sdf.cpp).
OrientationReport decide_orientation(const Mesh& mesh, Orientation mode, unsigned threads = 0,
                                     StageTimings* steps = nullptr);
void apply_orientation(Mesh& mesh, const OrientationReport& report, unsigned threads = 0);

// Auto as orient() does it, but with step 1 always run. orient() skips it when no manifold
// edge runs the same way in its two faces (it would reverse nothing); tests compare the two.
OrientationReport orient_auto_without_fast_path(Mesh& mesh, unsigned threads = 0);

}  // namespace sdf
