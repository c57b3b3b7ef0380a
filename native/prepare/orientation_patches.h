// SPDX-License-Identifier: GPL-3.0-or-later
// Step 1 of orient(Auto) (orientation.h): per face, reverse it (1) or not (0) so that faces
// agree with their manifold-edge neighbours, each patch keeping the winding most of its area
// already has.
#pragma once

#include <optional>
#include <vector>

#include "mesh/mesh.h"
#include "prepare/orientation_edges.h"

namespace sdf {

// Parallel over `threads` (0 = every core) where it can, serial where it must (below); the
// result does not depend on the thread count.
std::vector<char> patch_flips(const Mesh& mesh, const EdgeUses& edges, unsigned threads);

// The serial definition: patches grown from faces in face order, each face taking its
// winding from the face that reached it first; a patch's areas summed in face order. Where a
// patch cannot be oriented (a Moebius strip), or a face lists a neighbour that does not list
// it back (a degenerate face using an edge twice lists the face across it), the result
// depends on which face is reached first: only this order defines it.
std::vector<char> patch_flips_serial(const Mesh& mesh, const EdgeNeighbours& edges);

// The same result in parallel, for meshes where every neighbour lists its neighbour back and
// every patch can be oriented: a patch is then a connected set of faces and each face's
// winding relative to the patch's first face is fixed, whatever reaches it first. Made from
// the edge uses straight away (EdgeUses::join_patches), without the lists. nullopt for any
// other mesh.
std::optional<std::vector<char>> patch_flips_parallel(const Mesh& mesh, const EdgeUses& edges,
                                                      unsigned threads);

}  // namespace sdf
