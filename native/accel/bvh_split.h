// SPDX-License-Identifier: GPL-3.0-or-later
// Early split clipping (Ernst and Greiner 2007): a long thin triangle lying across the axes
// (a sliver of a CAD fan, a strip between distant vertices) has a box far larger than itself,
// which overlaps its neighbours' and every ray near it must open. Such a triangle enters the
// BVH as several references, each the box of one piece of it, so that the tree can separate
// them. A leaf may then hold one triangle more than once: tested twice, it gives the same hit.
// (A fan of 32k slivers cast 14x slower per face than a sphere before.)
#pragma once

#include <array>
#include <cstdint>

#include "accel/bvh_sah.h"
#include "mesh/mesh.h"
#include "util/uninitialized_vector.h"

namespace sdf::bvh_build {

// Pieces a triangle is cut into: 1, 2, 4, 8 or 16, a power of two (each cut halves a box).
constexpr int kPieceLevels = 5;
using PieceCounts = std::array<std::size_t, kPieceLevels>;  // triangles wanting 2^k pieces

// The pieces a triangle wants, as k of 2^k: from the ratio of its box's half area to its own
// area (2 for a triangle in an axis plane, with a box as tight as it gets; about L/w for a
// sliver of length L and width w lying diagonally). `twice_area` is |cross(e1, e2)|.
int wanted_piece_level(const Box& box, float twice_area);

// Replaces refs[0, count) by the references of their pieces (in order, a triangle's pieces
// together), each triangle cut into 2^min(wanted, cap) pieces, the cap the largest that keeps
// the added references within twice count. A ref's `bins` holds its wanted level on entry.
// refs and scratch are reallocated to the new count; root's bounds stay, its centroids are
// remade. Returns the new count. Deterministic for any thread count.
std::size_t split_slivers(const Mesh& mesh, const PieceCounts& wanted, std::size_t count,
                          unsigned threads, UninitializedVector<PrimRef>& refs,
                          UninitializedVector<PrimRef>& scratch, Range& root);

}  // namespace sdf::bvh_build
