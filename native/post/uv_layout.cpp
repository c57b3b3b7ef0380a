// SPDX-License-Identifier: GPL-3.0-or-later
#include "post/uv_layout.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>

#include "util/parallel.h"

namespace sdf {

namespace {

constexpr std::size_t kFaceGrain = 1 << 12;
constexpr double kSpanSlack = 1e-4;  // UV units a face may reach over its tile's border unnoticed

struct Point {
  double u, v;
};
using Triangle = std::array<Point, 3>;

double cross(Point o, Point a, Point b) {
  return (a.u - o.u) * (b.v - o.v) - (a.v - o.v) * (b.u - o.u);
}

// Face f's UV triangle in its tile's frame, counter-clockwise (mirrored islands wind the
// other way).
Triangle local_triangle(const float* uvs, std::size_t f, int column, int row) {
  Triangle t;
  for (int c = 0; c < 3; ++c)
    t[c] = {double(uvs[6 * f + 2 * c]) - column, double(uvs[6 * f + 2 * c + 1]) - row};
  if (cross(t[0], t[1], t[2]) < 0.0) std::swap(t[1], t[2]);
  return t;
}

// The area both counter-clockwise triangles cover: a clipped by b's three edges
// (Sutherland-Hodgman; a convex polygon of at most 9 corners).
double overlap_area(const Triangle& a, const Triangle& b) {
  std::array<Point, 12> poly, next;
  int n = 3;
  std::copy(a.begin(), a.end(), poly.begin());
  for (int e = 0; e < 3 && n > 0; ++e) {
    const Point p = b[e], q = b[(e + 1) % 3];
    int k = 0;
    for (int i = 0; i < n; ++i) {
      const Point s = poly[i], t = poly[(i + 1) % n];
      const double ds = cross(p, q, s), dt = cross(p, q, t);
      if (ds >= 0.0) next[k++] = s;
      if ((ds >= 0.0) != (dt >= 0.0)) {
        const double w = ds / (ds - dt);
        next[k++] = {s.u + w * (t.u - s.u), s.v + w * (t.v - s.v)};
      }
    }
    n = k;
    poly = next;
  }
  double twice = 0.0;
  for (int i = 1; i + 1 < n; ++i) twice += cross(poly[0], poly[i], poly[i + 1]);
  return 0.5 * twice;
}

// Whether an edge of one counter-clockwise triangle has the whole other on its outer side or
// on it: they then share no area (most pairs the search meets, neighbours across an edge or a
// corner of the other shell), known without clipping (exactly: a shared corner gives 0).
bool separated(const Triangle& a, const Triangle& b) {
  auto outside = [](const Triangle& s, const Triangle& o) {
    for (int e = 0; e < 3; ++e) {
      const Point p = s[e], q = s[(e + 1) % 3];
      if (cross(p, q, o[0]) <= 0.0 && cross(p, q, o[1]) <= 0.0 && cross(p, q, o[2]) <= 0.0)
        return true;
    }
    return false;
  };
  return outside(a, b) || outside(b, a);
}

struct FaceTiles {
  std::vector<int> tile_index;  // per face: index into tiles, -1 for none
  std::vector<int> tiles;       // the tile numbers used, ascending
};

// Each face's tile by its UV centroid; counts those in none and those reaching beyond theirs.
FaceTiles find_tiles(const float* uvs, std::size_t m, unsigned threads, UvLayout& layout) {
  std::vector<int> tile(m);
  std::vector<std::uint8_t> spanning(m);
  parallel_for(m, kFaceGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t f = begin; f < end; ++f) {
      const float* uv = uvs + 6 * f;
      const double cu = (double(uv[0]) + uv[2] + uv[4]) / 3.0;
      const double cv = (double(uv[1]) + uv[3] + uv[5]) / 3.0;
      tile[f] = uv_tile(cu, cv);
      for (int c = 0; c < 3 && tile[f] == 0; ++c) tile[f] = uv_tile(uv[2 * c], uv[2 * c + 1]);
      spanning[f] = 0;
      if (tile[f] == 0) continue;
      const double u0 = (tile[f] - kFirstTile) % kTileColumns;
      const double v0 = (tile[f] - kFirstTile) / kTileColumns;
      for (int c = 0; c < 3; ++c)
        spanning[f] |= uv[2 * c] < u0 - kSpanSlack || uv[2 * c] > u0 + 1 + kSpanSlack ||
                       uv[2 * c + 1] < v0 - kSpanSlack || uv[2 * c + 1] > v0 + 1 + kSpanSlack;
    }
  });
  // Tile numbers are few (1001 to 2000): a table from each to its index.
  constexpr int kTiles = kTileColumns * kTileRows;
  std::vector<int> index(kTiles, -1);
  for (std::size_t f = 0; f < m; ++f) {
    layout.faces_outside += tile[f] == 0;
    layout.faces_spanning += spanning[f];
    if (tile[f] != 0) index[tile[f] - kFirstTile] = 0;
  }
  FaceTiles found;
  for (int k = 0; k < kTiles; ++k)
    if (index[k] == 0) {
      index[k] = static_cast<int>(found.tiles.size());
      found.tiles.push_back(kFirstTile + k);
    }
  found.tile_index.resize(m);
  for (std::size_t f = 0; f < m; ++f)
    found.tile_index[f] = tile[f] == 0 ? -1 : index[tile[f] - kFirstTile];
  return found;
}

// A uniform grid over each used tile's square, g x g cells a tile, holding the faces whose
// clipped UV boxes touch each cell.
struct UvGrid {
  int g = 1;
  struct Box {
    int x0, y0, x1, y1;
  };
  // A face in a cell, with what the search reads of it (in one place: scanning the cells
  // was the layout's cost, most of it cache misses on arrays per face).
  struct Entry {
    std::uint32_t face;
    std::int32_t node;
    int x0, y0;            // its first cell
    float u0, v0, u1, v1;  // its UV box in its tile
  };
  std::vector<std::uint32_t> first;  // per cell, where its entries start
  std::vector<Entry> entries;
  // Per cell, 1 where its entries are of more than one node: only there can faces of two
  // nodes meet (a pair is looked at in the first cell both share). Most cells of a layout
  // without overlaps hold one island: their entries, read again by each of their faces, were
  // most of the search's time.
  std::vector<std::uint8_t> mixed;
  // Per entry, where the run of its node's entries in its cell ends: the search steps over
  // the runs of f's own node and of a node it already overlaps at once (on two stacked
  // shells, reading those entries one by one was most of its time).
  std::vector<std::uint32_t> run_end;
  std::vector<Box> boxes;                    // per face, its cells (x1 < x0 for faces in no tile)
  std::vector<std::array<float, 4>> extent;  // per face, its UV box in its tile: u0, v0, u1, v1
};

// Cells about the size of a typical face's UV box (the median side): a face then spans a few
// cells, each holding a few faces, whatever the faces' sizes (a cell per face on average
// scanned a random UV soup's hundreds of cells a face, each with thousands of faces).
int grid_size(const FaceTiles& t, const std::vector<std::array<float, 4>>& extent) {
  std::vector<float> side;
  side.reserve(extent.size());
  for (std::size_t f = 0; f < extent.size(); ++f)
    if (t.tile_index[f] >= 0)
      side.push_back(std::max(extent[f][2] - extent[f][0], extent[f][3] - extent[f][1]));
  if (side.empty()) return 1;
  std::nth_element(side.begin(), side.begin() + side.size() / 2, side.end());
  const double median = std::max(double(side[side.size() / 2]), 1.0 / 2048);
  const double per_tile = double(side.size()) / t.tiles.size();
  return std::clamp(static_cast<int>(1.0 / median), 1,
                    std::clamp(2 * int(std::sqrt(per_tile)), 1, 2048));
}

// Each cell's entries in runs of one node (a stable sort: face order within a run), each
// entry's run end, and which cells hold more than one node.
void mark_runs(UvGrid& grid, std::size_t cells, unsigned threads) {
  grid.mixed.resize(cells);
  grid.run_end.resize(grid.entries.size());
  parallel_for(cells, kFaceGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t c = begin; c < end; ++c) {
      const auto first = grid.entries.begin() + grid.first[c];
      const auto last = grid.entries.begin() + grid.first[c + 1];
      auto by_node = [](const UvGrid::Entry& a, const UvGrid::Entry& b) { return a.node < b.node; };
      if (!std::is_sorted(first, last, by_node)) std::stable_sort(first, last, by_node);
      for (std::uint32_t j = grid.first[c + 1]; j-- > grid.first[c];)
        grid.run_end[j] =
            j + 1 < grid.first[c + 1] && grid.entries[j + 1].node == grid.entries[j].node
                ? grid.run_end[j + 1]
                : j + 1;
      grid.mixed[c] =
          grid.first[c] < grid.first[c + 1] && grid.run_end[grid.first[c]] != grid.first[c + 1];
    }
  });
}

UvGrid build_grid(const float* uvs, const FaceTiles& t, const std::vector<std::int32_t>& face_node,
                  unsigned threads) {
  const std::size_t m = t.tile_index.size();
  UvGrid grid;
  grid.extent.resize(m);
  for (std::size_t f = 0; f < m; ++f) {
    if (t.tile_index[f] < 0) continue;
    const int tile = t.tiles[t.tile_index[f]];
    const Triangle tri = local_triangle(uvs, f, (tile - kFirstTile) % kTileColumns,
                                        (tile - kFirstTile) / kTileColumns);
    grid.extent[f] = {float(std::min({tri[0].u, tri[1].u, tri[2].u})),
                      float(std::min({tri[0].v, tri[1].v, tri[2].v})),
                      float(std::max({tri[0].u, tri[1].u, tri[2].u})),
                      float(std::max({tri[0].v, tri[1].v, tri[2].v}))};
  }
  grid.g = grid_size(t, grid.extent);
  const int g = grid.g;
  auto cell = [&](double x) { return std::clamp(static_cast<int>(std::floor(x * g)), 0, g - 1); };
  grid.boxes.resize(m);
  const std::size_t cells = t.tiles.size() * std::size_t(g) * g;
  grid.first.assign(cells + 1, 0);
  for (std::size_t f = 0; f < m; ++f) {
    UvGrid::Box& b = grid.boxes[f];
    b = {0, 0, -1, -1};
    if (t.tile_index[f] < 0) continue;
    const std::array<float, 4>& e = grid.extent[f];
    b = {cell(e[0]), cell(e[1]), cell(e[2]), cell(e[3])};
    const std::size_t base = std::size_t(t.tile_index[f]) * g * g;
    for (int y = b.y0; y <= b.y1; ++y)
      for (int x = b.x0; x <= b.x1; ++x) ++grid.first[base + std::size_t(y) * g + x + 1];
  }
  for (std::size_t c = 0; c < cells; ++c) grid.first[c + 1] += grid.first[c];
  grid.entries.resize(grid.first[cells]);
  std::vector<std::uint32_t> at(grid.first.begin(), grid.first.end() - 1);
  for (std::size_t f = 0; f < m; ++f) {
    const UvGrid::Box& b = grid.boxes[f];
    const std::array<float, 4>& e = grid.extent[f];
    const UvGrid::Entry entry{
        static_cast<std::uint32_t>(f), face_node[f], b.x0, b.y0, e[0], e[1], e[2], e[3]};
    const std::size_t base = t.tile_index[f] < 0 ? 0 : std::size_t(t.tile_index[f]) * g * g;
    for (int y = b.y0; y <= b.y1; ++y)
      for (int x = b.x0; x <= b.x1; ++x) grid.entries[at[base + std::size_t(y) * g + x]++] = entry;
  }
  mark_runs(grid, cells, threads);
  return grid;
}

// The (tile, island) nodes: per face its node, -1 in no tile; nodes ordered by tile, then
// island; returns each node's key, tile index x islands + island.
std::vector<std::int64_t> node_keys(const FaceTiles& t, const std::vector<std::int32_t>& island,
                                    std::int64_t islands, std::vector<std::int32_t>& face_node) {
  const std::size_t m = island.size();
  const std::int64_t slots = static_cast<std::int64_t>(t.tiles.size()) * islands;
  std::vector<std::int64_t> keys;
  face_node.assign(m, -1);
  if (slots <= static_cast<std::int64_t>(4 * m) + 1024) {  // a table of every (tile, island)
    std::vector<std::int32_t> node(static_cast<std::size_t>(slots), -1);
    for (std::size_t f = 0; f < m; ++f)
      if (t.tile_index[f] >= 0) node[t.tile_index[f] * islands + island[f]] = 0;
    for (std::int64_t k = 0; k < slots; ++k)
      if (node[k] == 0) {
        node[k] = static_cast<std::int32_t>(keys.size());
        keys.push_back(k);
      }
    for (std::size_t f = 0; f < m; ++f)
      if (t.tile_index[f] >= 0) face_node[f] = node[t.tile_index[f] * islands + island[f]];
    return keys;
  }
  for (std::size_t f = 0; f < m; ++f)
    if (t.tile_index[f] >= 0) keys.push_back(t.tile_index[f] * islands + island[f]);
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  for (std::size_t f = 0; f < m; ++f)
    if (t.tile_index[f] >= 0)
      face_node[f] = static_cast<std::int32_t>(
          std::lower_bound(keys.begin(), keys.end(), t.tile_index[f] * islands + island[f]) -
          keys.begin());
  return keys;
}

// Flags the faces overlapping a face of another node by more than kOverlapShare and returns
// the overlapping node pairs (a < b), each once.
std::vector<std::pair<std::int32_t, std::int32_t>> find_overlaps(
    const float* uvs, const FaceTiles& t, const UvGrid& grid,
    const std::vector<std::int32_t>& face_node, unsigned threads,
    std::vector<std::uint8_t>& overlapping, bool& over_budget) {
  const std::size_t m = face_node.size();
  const int g = grid.g;
  overlapping.assign(m, 0);
  const std::size_t chunks = (m + kFaceGrain - 1) / kFaceGrain;
  std::vector<std::vector<std::pair<std::int32_t, std::int32_t>>> pairs(chunks);
  auto triangle = [&](std::size_t f) {
    const int tile = t.tiles[t.tile_index[f]];
    return local_triangle(uvs, f, (tile - kFirstTile) % kTileColumns,
                          (tile - kFirstTile) / kTileColumns);
  };
  // Clips allowed, kClipsPerFace a face on average: a layout where UVs overlap everywhere (a
  // random soup: every face's box meets most others') stops here, unparted.
  const std::uint64_t budget = kClipsPerFace * std::uint64_t(m) + 4096;
  std::atomic<std::uint64_t> clips{0};
  std::atomic<bool> stop{false};
  parallel_for(m, kFaceGrain, threads, [&](std::size_t begin, std::size_t end) {
    auto& found = pairs[begin / kFaceGrain];
    std::uint64_t mine = 0;
    for (std::size_t f = begin; f < end; ++f) {
      if (stop.load(std::memory_order_relaxed)) return;
      if (mine > 4096) {
        if (clips.fetch_add(mine, std::memory_order_relaxed) + mine > budget) stop = true;
        mine = 0;
      }
      if (face_node[f] < 0) continue;
      const Triangle a = triangle(f);
      const double area_a = 0.5 * cross(a[0], a[1], a[2]);
      if (!(area_a > 0.0)) continue;
      const UvGrid::Box& bf = grid.boxes[f];
      const std::array<float, 4>& ef = grid.extent[f];
      const std::size_t base = std::size_t(t.tile_index[f]) * g * g;
      const std::int32_t node = face_node[f];
      std::int32_t known = -1;  // a node f was found to overlap: its other faces need no test
      for (int y = bf.y0; y <= bf.y1; ++y)
        for (int x = bf.x0; x <= bf.x1; ++x) {
          const std::size_t c = base + std::size_t(y) * g + x;
          if (!grid.mixed[c]) continue;  // f's node alone
          for (std::uint32_t j = grid.first[c]; j < grid.first[c + 1]; ++j) {
            const UvGrid::Entry& eh = grid.entries[j];
            if (eh.node == node || eh.node == known) {
              j = grid.run_end[j] - 1;
              continue;
            }
            // Each pair once: in the first cell both boxes share.
            if (x != std::max(bf.x0, eh.x0) || y != std::max(bf.y0, eh.y0)) continue;
            if (eh.u0 >= ef[2] || ef[0] >= eh.u1 || eh.v0 >= ef[3] || ef[1] >= eh.v1)
              continue;  // the boxes meet in a line at most: no area in common
            const std::uint32_t h = eh.face;
            const Triangle b = triangle(h);
            ++mine;
            const double area_b = 0.5 * cross(b[0], b[1], b[2]);
            if (!(area_b > 0.0) || separated(a, b)) continue;
            if (overlap_area(a, b) <= kOverlapShare * std::min(area_a, area_b)) continue;
            overlapping[f] = 1;
            known = face_node[h];
            if (face_node[f] < face_node[h]) found.emplace_back(face_node[f], face_node[h]);
          }
        }
    }
  });
  over_budget = stop.load();
  std::vector<std::pair<std::int32_t, std::int32_t>> all;
  if (over_budget) return all;
  for (auto& p : pairs) all.insert(all.end(), p.begin(), p.end());
  std::sort(all.begin(), all.end());
  all.erase(std::unique(all.begin(), all.end()), all.end());
  return all;
}

// Greedy colouring of the nodes in order: each the lowest layer its earlier neighbours lack,
// at most the last of kMostLayers.
std::vector<int> assign_layers(std::size_t nodes,
                               const std::vector<std::pair<std::int32_t, std::int32_t>>& pairs) {
  std::vector<std::vector<std::int32_t>> earlier(nodes);
  for (const auto& [a, b] : pairs) earlier[b].push_back(a);
  std::vector<int> layer(nodes, 0);
  std::vector<int> taken;
  for (std::size_t n = 0; n < nodes; ++n) {
    taken.clear();
    for (std::int32_t e : earlier[n]) taken.push_back(layer[e]);
    std::sort(taken.begin(), taken.end());
    int l = 0;
    for (int x : taken)
      if (x == l)
        ++l;
      else if (x > l)
        break;
    layer[n] = std::min(l, kMostLayers - 1);
  }
  return layer;
}

}  // namespace

int uv_tile(double u, double v) {
  if (!(u >= 0.0 && u < kTileColumns && v >= 0.0 && v < kTileRows)) return 0;
  return kFirstTile + static_cast<int>(std::floor(u)) +
         kTileColumns * static_cast<int>(std::floor(v));
}

UvLayout layout_uvs(const float* uvs, const std::vector<std::int32_t>& face_island,
                    unsigned threads) {
  const std::size_t m = face_island.size();
  UvLayout layout;
  const FaceTiles t = find_tiles(uvs, m, threads, layout);
  layout.tile_count = static_cast<int>(t.tiles.size());
  std::int64_t islands = 0;
  for (std::int32_t i : face_island) islands = std::max<std::int64_t>(islands, i + 1);
  std::vector<std::int32_t> face_node;
  const std::vector<std::int64_t> keys = node_keys(t, face_island, islands, face_node);
  const UvGrid grid = build_grid(uvs, t, face_node, threads);
  std::vector<std::uint8_t> overlapping;
  bool over_budget = false;
  const auto pairs = find_overlaps(uvs, t, grid, face_node, threads, overlapping, over_budget);
  layout.overlaps_unparted = over_budget;
  for (std::uint8_t o : overlapping) layout.faces_overlapping += o;
  const std::vector<int> layer = assign_layers(keys.size(), pairs);

  // Pages: (tile, layer) pairs in order.
  std::vector<std::int64_t> page_keys;
  const std::int64_t layers =
      1 + (layer.empty() ? 0 : *std::max_element(layer.begin(), layer.end()));
  for (std::size_t n = 0; n < keys.size(); ++n)
    page_keys.push_back(keys[n] / islands * layers + layer[n]);
  std::sort(page_keys.begin(), page_keys.end());
  page_keys.erase(std::unique(page_keys.begin(), page_keys.end()), page_keys.end());
  for (std::int64_t k : page_keys) {
    UvPage page;
    page.tile = t.tiles[k / layers];
    page.layer = static_cast<int>(k % layers);
    layout.pages.push_back(page);
  }
  layout.face_page.assign(m, -1);
  for (std::size_t f = 0; f < m; ++f) {
    if (face_node[f] < 0) continue;
    const std::int64_t k = keys[face_node[f]] / islands * layers + layer[face_node[f]];
    const std::size_t p =
        std::lower_bound(page_keys.begin(), page_keys.end(), k) - page_keys.begin();
    layout.face_page[f] = static_cast<std::int32_t>(p);
    ++layout.pages[p].faces;
  }
  return layout;
}

std::vector<float> page_uvs(const UvLayout& layout, const float* uvs, int page, unsigned threads) {
  const std::size_t m = layout.face_page.size();
  const float du = static_cast<float>(layout.pages[page].column());
  const float dv = static_cast<float>(layout.pages[page].row());
  std::vector<float> out(6 * m);
  parallel_for(m, kFaceGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t f = begin; f < end; ++f) {
      const bool mine = layout.face_page[f] == page;
      for (int c = 0; c < 3; ++c) {
        out[6 * f + 2 * c] = mine ? uvs[6 * f + 2 * c] - du : -4.0f;
        out[6 * f + 2 * c + 1] = mine ? uvs[6 * f + 2 * c + 1] - dv : -4.0f;
      }
    }
  });
  return out;
}

}  // namespace sdf
