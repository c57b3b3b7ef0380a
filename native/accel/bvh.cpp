// SPDX-License-Identifier: GPL-3.0-or-later
// Builds in three phases, each spread over every thread:
//  1. references: the triangles with area, as PrimRefs in face order, slivers lying across
//     the axes cut into pieces of their own (bvh_split.h);
//  2. top levels: nodes of at least kTopLevelNode triangles are split one level at a time, all
//     threads binning and partitioning the level's nodes together (chunks of kChunk
//     triangles, bins merged, a stable partition into a second buffer);
//  3. subtrees: every node left over is built depth first on one thread (bvh_subtree.cpp),
//     the subtrees handed out largest first, then moved to their place in the node array.
// Every decision depends only on the mesh and the constants below, never on the thread count
// or on timing, so the node and triangle arrays are identical for any number of threads.
#include "accel/bvh.h"

#include <algorithm>
#include <memory>
#include <numeric>
#include <stdexcept>
#include <string>

#include "accel/bvh_sah.h"
#include "accel/bvh_split.h"
#include "accel/bvh_subtree.h"
#include "util/parallel.h"

namespace sdf {

using bvh_build::BinMapping;
using bvh_build::Bins;
using bvh_build::Box;
using bvh_build::PieceCounts;
using bvh_build::PrimRef;
using bvh_build::Range;
using bvh_build::Split;

namespace {

// Triangles per work item of the parallel passes: large enough that a chunk's bins (2.7 kB)
// and its hand-out cost nothing next to its work, small enough to balance 16 threads at the
// root's children.
constexpr std::size_t kChunk = 8192;
// Nodes at least this large are split by all threads together; smaller ones become subtrees
// of one thread each. 16384 leaves 75 to 150 subtrees for a million triangles, enough to keep
// 16 threads busy to the end.
constexpr std::size_t kTopLevelNode = 16384;

// The triangles with area (zero-area ones can never be hit: Moller-Trumbore's determinant is
// 0), in face order, with the bounds of the whole, into refs; scratch (as large) is used on
// the way and the two may be swapped. Returns how many there are. Each ref's `bins` holds the
// piece level its triangle wants (bvh_split.h), and `wanted` counts them.
std::size_t make_references(const Mesh& mesh, unsigned threads, UninitializedVector<PrimRef>& refs,
                            UninitializedVector<PrimRef>& scratch, Range& root,
                            PieceCounts& wanted) {
  const std::size_t faces = mesh.triangles.size();
  const std::size_t chunks = (faces + kChunk - 1) / kChunk;
  // One pass over the vertices: each chunk writes its references from its first face's
  // place in scratch; they are moved together only if some triangle had no area.
  std::vector<std::size_t> offset(chunks + 1, 0);
  std::vector<Range> chunk_bounds(chunks);
  std::vector<PieceCounts> chunk_wanted(chunks, PieceCounts{});
  PrimRef* out = scratch.data();
  parallel_for(chunks, 1, threads, [&](std::size_t b, std::size_t e) {
    for (std::size_t c = b; c < e; ++c) {
      std::size_t n = c * kChunk;
      bvh_build::Box4 bounds, centroids;
      for (std::size_t f = c * kChunk; f < std::min(faces, (c + 1) * kChunk); ++f) {
        const glm::uvec3 t = mesh.triangles[f];
        const glm::vec3 v0 = mesh.vertices[t.x], v1 = mesh.vertices[t.y], v2 = mesh.vertices[t.z];
        const glm::vec3 normal = glm::cross(v1 - v0, v2 - v0);  // as face_area_normal
        if (normal.x == 0.0f && normal.y == 0.0f && normal.z == 0.0f) continue;
        PrimRef& r = out[n++];
        // + 0: a -0 corner becomes +0, so the box does not depend on which of two equal
        // zeros min and max keep (a reversed face lists its corners in another order).
        r.lo = glm::min(v0, glm::min(v1, v2)) + 0.0f;
        r.hi = glm::max(v0, glm::max(v1, v2)) + 0.0f;
        r.id = static_cast<std::uint32_t>(f);
        r.bins = static_cast<std::uint32_t>(
            bvh_build::wanted_piece_level(Box{r.lo, r.hi}, glm::length(normal)));
        ++chunk_wanted[c][r.bins];
        const bvh_build::Float4 lo = bvh_build::lo4(r), hi = bvh_build::hi4(r), c2 = lo + hi;
        bounds.grow(lo, hi);
        centroids.grow(c2, c2);
      }
      offset[c + 1] = n - c * kChunk;
      chunk_bounds[c].bounds = bounds.box();
      chunk_bounds[c].centroids = centroids.box();
    }
  });
  std::partial_sum(offset.begin(), offset.end(), offset.begin());
  const std::size_t count = offset[chunks];
  if (count == faces) {
    std::swap(refs, scratch);
  } else {
    parallel_for(chunks, 1, threads, [&](std::size_t b, std::size_t e) {
      for (std::size_t c = b; c < e; ++c)
        std::copy(out + c * kChunk, out + c * kChunk + (offset[c + 1] - offset[c]),
                  refs.data() + offset[c]);
    });
  }
  root = Range{0, 0, count, 0, Box(), Box()};
  for (const Range& c : chunk_bounds) {
    root.bounds.grow(c.bounds);
    root.centroids.grow(c.centroids);
  }
  wanted = PieceCounts{};
  for (const PieceCounts& w : chunk_wanted)
    for (int k = 0; k < bvh_build::kPieceLevels; ++k) wanted[k] += w[k];
  return count;
}

// A node handed to phase 3, and which of the two reference buffers holds its triangles.
struct Subtree {
  Range range;
  int buffer;
};

// Phase 2. Splits the nodes of `level` (all in buffers[from]) into the other buffer; appends
// their children to nodes, and each child to next_level or subtrees by size.
class TopLevels {
 public:
  TopLevels(PrimRef* buffers[2], const BvhConfig& config,
            UninitializedVector<kern::SdfBvhNode>& nodes, std::vector<Subtree>& subtrees)
      : buffers_{buffers[0], buffers[1]}, config_(config), nodes_(nodes), subtrees_(subtrees) {}

  // Builds every level, starting with root in buffer 0.
  void build(const Range& root) {
    std::vector<Range> level;
    place(root, 0, level);
    for (int from = 0; !level.empty(); from = 1 - from) level = split_level(level, from);
  }

 private:
  struct Chunk {
    std::size_t node;  // in the level
    std::size_t begin, end;
  };
  // Per chunk, the bounds of what went to each side.
  struct Sides {
    Box bounds[2], centroids[2];
  };

  void place(const Range& r, int buffer, std::vector<Range>& next_level) {
    if (r.count() >= kTopLevelNode && r.depth < bvh_build::kMaxDepth)
      next_level.push_back(r);
    else
      subtrees_.push_back(Subtree{r, buffer});
  }

  std::vector<Range> split_level(const std::vector<Range>& level, int from) {
    PrimRef* src = buffers_[from];
    PrimRef* dst = buffers_[1 - from];
    std::vector<Chunk> chunks;
    std::vector<std::size_t> first_chunk(level.size() + 1);
    std::vector<BinMapping> maps;
    for (std::size_t n = 0; n < level.size(); ++n) {
      first_chunk[n] = chunks.size();
      for (std::size_t b = level[n].begin; b < level[n].end; b += kChunk)
        chunks.push_back(Chunk{n, b, std::min(level[n].end, b + kChunk)});
      maps.emplace_back(level[n].centroids, config_.bins);
    }
    first_chunk[level.size()] = chunks.size();

    std::vector<Bins> chunk_bins(chunks.size(), Bins(config_.bins));
    parallel_for(chunks.size(), 1, config_.threads, [&](std::size_t b, std::size_t e) {
      for (std::size_t c = b; c < e; ++c)
        chunk_bins[c].add(src + chunks[c].begin, chunks[c].end - chunks[c].begin,
                          maps[chunks[c].node]);
    });

    // Decide each node's split from its merged bins, and where each chunk's two sides go.
    std::vector<Split> splits(level.size());
    std::vector<std::size_t> left_out(chunks.size()), right_out(chunks.size());
    for (std::size_t n = 0; n < level.size(); ++n) {
      Bins bins(config_.bins);
      for (std::size_t c = first_chunk[n]; c < first_chunk[n + 1]; ++c)
        bins.merge(chunk_bins[c], config_.bins);
      splits[n] = choose_split(level[n], bins, maps[n], config_.max_leaf_size);
      std::size_t left_total = 0;
      for (std::size_t c = first_chunk[n]; c < first_chunk[n + 1]; ++c)
        left_total += left_count(chunks[c], chunk_bins[c], splits[n], level[n]);
      std::size_t left = level[n].begin, right = level[n].begin + left_total;
      for (std::size_t c = first_chunk[n]; c < first_chunk[n + 1]; ++c) {
        const std::size_t l = left_count(chunks[c], chunk_bins[c], splits[n], level[n]);
        left_out[c] = left;
        right_out[c] = right;
        left += l;
        right += (chunks[c].end - chunks[c].begin) - l;
      }
    }

    // Stable partition into the other buffer; a leaf's chunks are copied across unchanged.
    std::vector<Sides> sides(chunks.size());
    parallel_for(chunks.size(), 1, config_.threads, [&](std::size_t b, std::size_t e) {
      for (std::size_t c = b; c < e; ++c) {
        const Chunk& ch = chunks[c];
        const Split& split = splits[ch.node];
        const std::size_t mid = level[ch.node].begin + level[ch.node].count() / 2;
        std::size_t out[2] = {left_out[c], right_out[c]};
        bvh_build::Box4 bounds[2], centroids[2];
        for (std::size_t i = ch.begin; i < ch.end; ++i) {
          const PrimRef& r = src[i];
          const bool left = split.kind == Split::Sah ? split.goes_left(r)
                                                     : (split.kind == Split::Leaf || i < mid);
          const int side = left ? 0 : 1;
          dst[out[side]++] = r;
          const bvh_build::Float4 lo = bvh_build::lo4(r), hi = bvh_build::hi4(r), c2 = lo + hi;
          bounds[side].grow(lo, hi);
          centroids[side].grow(c2, c2);
        }
        for (int s = 0; s < 2; ++s) {
          sides[c].bounds[s] = bounds[s].box();
          sides[c].centroids[s] = centroids[s].box();
        }
      }
    });

    std::vector<Range> next_level;
    for (std::size_t n = 0; n < level.size(); ++n) {
      const Range& parent = level[n];
      if (splits[n].kind == Split::Leaf) {  // only with max_leaf_size >= kTopLevelNode
        subtrees_.push_back(Subtree{parent, 1 - from});
        continue;
      }
      const std::size_t mid =
          first_chunk[n] < first_chunk[n + 1] ? right_out[first_chunk[n]] : parent.begin;
      Range child[2] = {Range{0, parent.begin, mid, parent.depth + 1, Box(), Box()},
                        Range{0, mid, parent.end, parent.depth + 1, Box(), Box()}};
      for (std::size_t c = first_chunk[n]; c < first_chunk[n + 1]; ++c)
        for (int s = 0; s < 2; ++s) {
          child[s].bounds.grow(sides[c].bounds[s]);
          child[s].centroids.grow(sides[c].centroids[s]);
        }
      const std::uint32_t first = static_cast<std::uint32_t>(nodes_.size());
      nodes_.resize(first + 2);
      nodes_[parent.node].first = static_cast<std::int32_t>(first);
      nodes_[parent.node].count = 0;
      for (int s = 0; s < 2; ++s) {
        child[s].node = first + s;
        bvh_build::set_node_bounds(nodes_[first + s], child[s].bounds);
        place(child[s], 1 - from, next_level);
      }
    }
    return next_level;
  }

  // How many of a chunk's triangles go left: read off the chunk's bin counts, no extra pass.
  static std::size_t left_count(const Chunk& ch, const Bins& bins, const Split& split,
                                const Range& node) {
    const std::size_t size = ch.end - ch.begin;
    if (split.kind == Split::Leaf) return size;
    if (split.kind == Split::Median) {
      const std::size_t mid = node.begin + node.count() / 2;
      return mid <= ch.begin ? 0 : std::min(size, mid - ch.begin);
    }
    std::size_t n = 0;
    for (int b = 0; b <= split.bin; ++b) n += bins.count[split.axis][b];
    return n;
  }

  PrimRef* buffers_[2];
  const BvhConfig& config_;
  UninitializedVector<kern::SdfBvhNode>& nodes_;
  std::vector<Subtree>& subtrees_;
};

// Phase 3: builds the subtrees and appends them to nodes, each after the previous one, in
// the order they were found (so the layout does not depend on which thread finished first).
void build_subtrees(const std::vector<Subtree>& subtrees, PrimRef* buffers[2],
                    std::size_t buffer_size, const BvhConfig& config,
                    UninitializedVector<kern::SdfBvhNode>& nodes) {
  std::vector<std::size_t> largest_first(subtrees.size());
  std::iota(largest_first.begin(), largest_first.end(), 0);
  std::stable_sort(largest_first.begin(), largest_first.end(), [&](std::size_t a, std::size_t b) {
    return subtrees[a].range.count() > subtrees[b].range.count();
  });
  // Subtree k is built at 2 * (its first triangle) of one shared array, room enough (at most
  // 2n - 1 nodes for n triangles) without an allocation per subtree.
  UninitializedVector<kern::SdfBvhNode> built(2 * buffer_size);
  std::vector<std::size_t> built_count(subtrees.size());
  parallel_for(subtrees.size(), 1, config.threads, [&](std::size_t b, std::size_t e) {
    for (std::size_t k = b; k < e; ++k) {
      const Subtree& s = subtrees[largest_first[k]];
      // Leaves index buffer 0, so a subtree whose triangles are in buffer 1 moves them first.
      if (s.buffer == 1)
        std::copy(buffers[1] + s.range.begin, buffers[1] + s.range.end, buffers[0] + s.range.begin);
      built_count[largest_first[k]] =
          bvh_build::build_subtree(buffers[0], s.range, config.bins, config.max_leaf_size,
                                   config.morton_below, built.data() + 2 * s.range.begin);
    }
  });
  // Subtree k's root replaces its node; the rest of it goes to base[k].
  std::vector<std::size_t> base(subtrees.size() + 1);
  base[0] = nodes.size();
  for (std::size_t k = 0; k < subtrees.size(); ++k) base[k + 1] = base[k] + built_count[k] - 1;
  nodes.resize(base[subtrees.size()]);
  parallel_for(subtrees.size(), 1, config.threads, [&](std::size_t b, std::size_t e) {
    for (std::size_t k = b; k < e; ++k) {
      const kern::SdfBvhNode* local = built.data() + 2 * subtrees[k].range.begin;
      auto relocated = [&](kern::SdfBvhNode n) {
        if (n.count == 0) n.first = static_cast<std::int32_t>(base[k] + n.first - 1);
        return n;
      };
      nodes[subtrees[k].range.node] = relocated(local[0]);
      for (std::size_t j = 1; j < built_count[k]; ++j) nodes[base[k] + j - 1] = relocated(local[j]);
    }
  });
}

// Fills bvh.triangles[i] (already sized) with the record of face face_of(i), read from mesh.
template <class FaceOf>
void write_triangles(const Mesh& mesh, unsigned threads, FaceOf face_of, Bvh& bvh) {
  parallel_for(bvh.triangles.size(), kChunk, threads, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      const std::uint32_t f = face_of(i);
      const glm::uvec3 t = mesh.triangles[f];
      const glm::vec3 v0 = mesh.vertices[t.x];
      const glm::vec3 e1 = mesh.vertices[t.y] - v0, e2 = mesh.vertices[t.z] - v0;
      bvh.triangles[i] = kern::SdfTriangle{v0.x, v0.y, v0.z, static_cast<std::int32_t>(f),
                                           e1.x, e1.y, e1.z, 0.0f,
                                           e2.x, e2.y, e2.z, 0.0f};
    }
  });
}

}  // namespace

Bvh build_bvh(const Mesh& mesh, const BvhConfig& config) {
  if (config.max_leaf_size < 1 || config.bins < 2 || config.bins > bvh_build::kMaxBins)
    throw std::invalid_argument("BvhConfig: max_leaf_size >= 1 and 2 <= bins <= " +
                                std::to_string(bvh_build::kMaxBins) + " are required");
  const std::size_t faces = mesh.triangles.size();
  // Not zero-filled: that would be a serial pass over 32 bytes per face.
  UninitializedVector<PrimRef> refs(faces), scratch(faces);
  Range root;
  PieceCounts wanted;
  std::size_t count = make_references(mesh, config.threads, refs, scratch, root, wanted);
  if (count > wanted[0])
    count = bvh_build::split_slivers(mesh, wanted, count, config.threads, refs, scratch, root);
  Bvh bvh;
  if (count == 0) return bvh;

  PrimRef* buffers[2] = {refs.data(), scratch.data()};
  bvh.nodes.reserve(2 * count);
  bvh.nodes.resize(1);
  bvh_build::set_node_bounds(bvh.nodes[0], root.bounds);
  std::vector<Subtree> subtrees;
  TopLevels(buffers, config, bvh.nodes, subtrees).build(root);
  build_subtrees(subtrees, buffers, count, config, bvh.nodes);

  bvh.triangles.resize(count);
  write_triangles(
      mesh, config.threads, [&](std::size_t i) { return refs[i].id; }, bvh);
  return bvh;
}

void rewrite_triangles(Bvh& bvh, const Mesh& mesh, unsigned threads) {
  write_triangles(
      mesh, threads, [&](std::size_t i) { return static_cast<std::uint32_t>(bvh.triangles[i].id); },
      bvh);
}

int bvh_depth(const Bvh& bvh) {
  if (bvh.nodes.empty()) return 0;
  int deepest = 0;
  std::vector<std::pair<std::int32_t, int>> stack{{0, 0}};
  while (!stack.empty()) {
    const auto [index, depth] = stack.back();
    stack.pop_back();
    deepest = std::max(deepest, depth);
    const kern::SdfBvhNode& n = bvh.nodes[index];
    if (n.count == 0) {
      stack.push_back({n.first, depth + 1});
      stack.push_back({n.first + 1, depth + 1});
    }
  }
  return deepest;
}

}  // namespace sdf
