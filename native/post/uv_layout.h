// SPDX-License-Identifier: GPL-3.0-or-later
// The pages texture smoothing draws a mesh's UVs on (smoothing_texture_pages.h): UDIM tiles,
// and within a tile, layers that keep overlapping UV islands apart.
//
// Tiles (the UDIM convention): UV (u, v) lies in tile 1001 + floor(u) + 10 floor(v), for u in
// [0, 10) and v in [0, 100) (tiles 1001 to 2000); tile 1001 is the [0, 1] square. A face
// belongs to the tile of its UV centroid and is drawn in that tile alone: where its UVs reach into
// a neighbouring tile, that part is clipped, and a UV island that continues across a tile border is
// cut there (each part smoothed in its own tile). A face whose centroid lies in no tile (u < 0, u
// >= 10, v < 0 or v >= 100) belongs to the tile of its first corner in one (a face over the
// square's edge is drawn clipped, as in one image); a face with no corner in a tile belongs to no
// page: it keeps its value.
//
// Overlaps: two faces of different UV islands in one tile overlap when their UV triangles share
// more than kOverlapShare of the smaller one's area (mirrored halves, stacked shells). The
// islands of a tile are then spread over layers (greedily, in order of each island's first face:
// the lowest layer none of its overlapping islands already holds), each layer its own image, so
// values never mix across overlapping shells: the repacking keeps every island where it is and
// at its resolution, on an image of its own. A tile has at most kMostLayers layers (each costs
// a pass over an image): islands that find none free share the last, where overlapping faces
// are drawn as in one image (the later face wins), as are faces that overlap faces of their
// own island (a folded island), which no layering parts. Where UVs overlap everywhere (the search
// would clip more than kClipsPerFace pairs a face: a random UV soup), the search stops and each
// tile is drawn in one image, as laid out.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "mesh/mesh.h"

namespace sdf {

constexpr double kOverlapShare = 0.01;
constexpr int kMostLayers = 8;
// The overlap search clips at most this many face pairs a face on average; beyond, the UVs
// overlap everywhere (a random soup) and are drawn as laid out, in one image a tile.
constexpr std::uint64_t kClipsPerFace = 64;
constexpr int kFirstTile = 1001;
constexpr int kTileColumns = 10;
constexpr int kTileRows = 100;  // tiles 1001 to 2000, as Blender holds them

struct UvPage {
  int tile = kFirstTile;  // UDIM number, 1001 + column + 10 row
  int layer = 0;          // 0, 1, ...: images of one tile that keep overlapping islands apart
  std::size_t faces = 0;
  int column() const { return (tile - kFirstTile) % kTileColumns; }  // u offset
  int row() const { return (tile - kFirstTile) / kTileColumns; }     // v offset
};

struct UvLayout {
  std::vector<std::int32_t> face_page;  // per face: its page, -1 for none (no tile)
  std::vector<UvPage> pages;            // by tile, then layer
  std::size_t faces_outside = 0;        // no corner in a tile: not drawn, values kept
  std::size_t faces_spanning = 0;       // UVs reaching beyond their tile by more than 1e-4
  std::size_t faces_overlapping = 0;    // overlapping faces of another island (see above)
  // The search stopped at kClipsPerFace: faces_overlapping counts those found so far (at
  // least that many), and no layers part them.
  bool overlaps_unparted = false;
  int tile_count = 0;
  // One page, tile 1001: the UVs are drawn as given, in one image (faces of no tile too,
  // clipped: one whose corners lie in no tile still covers a sliver of the square at most).
  bool single_square() const { return pages.size() == 1 && pages[0].tile == kFirstTile; }
};

// The tile of UV point (u, v), or 0 for none.
int uv_tile(double u, double v);

// face_island: per face, its UV island (uv_islands.h) of the UVs as given (6 floats a face,
// finite). Runs on `threads` (0: every core); the result does not depend on them.
UvLayout layout_uvs(const float* uvs, const std::vector<std::int32_t>& face_island,
                    unsigned threads);

// The UVs page `page` draws: its faces' moved into the [0, 1] square (u - column, v - row:
// exact in floats, as a page's faces lie in [column, column + 1) by their centroids), every
// other face's corners at (-4, -4), outside the square (they cover no texel and keep their
// values).
std::vector<float> page_uvs(const UvLayout& layout, const float* uvs, int page, unsigned threads);

}  // namespace sdf
