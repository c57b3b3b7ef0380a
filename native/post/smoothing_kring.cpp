// SPDX-License-Identifier: GPL-3.0-or-later
#include "post/smoothing_kring.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <functional>
#include <limits>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>

#include "mesh/mesh_weld.h"
#include "post/smoothing_kring_sums.h"
#include "post/value_range.h"
#include "util/morton.h"
#include "util/parallel_scan.h"
#include "util/radix_sort.h"
#include "util/uninitialized_vector.h"

namespace sdf {

namespace {

// ---- Plain rings, 64 points at a time (bit-parallel breadth-first search). ----
// A batch of up to 64 nearby points walks its rings together: every item of the region the
// batch can reach holds a 64-bit mask, bit b set when point b of the batch has reached it.
// One pass over the region per ring ORs each item's neighbours' masks into its own; the bits
// that are new at ring r are the batch points whose ring r holds the item. Every (point,
// item) pair is still visited once, but the walk itself costs one mask OR per region edge
// and ring for all 64 points, with no per-point visited marks or queues, and the pairs are
// summed by add_item or add_ring_avx512 (smoothing_kring_sums.h).
//
// Vertex rings: D_0 = the batch's vertices; D_{r+1}(v) = D_r(v) | OR of D_r over v's edge
// neighbours; ring r of point b = {v : bit b in D_r(v) and not in D_{r-1}(v)}.
// Face rings (faces sharing a vertex): with D_d over vertices started from the batch faces'
// corners, face g is within ring d + 1 of point b when a corner of g has bit b in D_d (the
// identity in the header); F_0 = the batch faces themselves.
//
// The region is grown breadth-first from the batch, so it lists its vertices by level (edge
// distance from the batch), and its faces by the level of their first listed corner. D_d can
// hold bits only on levels 0..d, and a face only through a corner there: pass d walks that
// prefix of the region, not all of it (40% fewer face and vertex visits at k = 6, 1.5M faces).
// The prefixes keep the region's order, so each point sums its items in the same order as a
// walk of it all.

constexpr int kBatch = 64;

struct BatchScratch {
  std::vector<std::uint32_t> vertex_stamp, face_stamp;
  // Read only where vertex_stamp holds the current epoch, so never zeroed (one array fewer to
  // write per thread before its first batch).
  UninitializedVector<std::uint32_t> vertex_local;
  std::vector<std::uint32_t> region_vertices, region_faces;     // global ids, walk order
  std::vector<std::uint32_t> vertex_level_end, face_level_end;  // prefix ends by level
  std::vector<std::uint32_t> local_offsets, local_items;        // region vertex adjacency, local
  // 3 local vertex ids per face; a corner outside the region points at the spare slot after
  // the region's vertices, whose mask stays zero (no test in the face loop).
  std::vector<std::uint32_t> face_corners;
  std::vector<std::uint64_t> reach, next, seen;
  // The items new to some point in the current ring, summed at its end by add_ring_avx512 where
  // the CPU has AVX-512 (`simd`); otherwise each is summed as it is found (add_item), which
  // saves the list (a tenth of the walk).
  std::vector<RingItem> ring;
  bool simd = add_ring_avx512_supported();
  std::uint32_t epoch = 0;
  std::uint32_t next_epoch() {
    if (++epoch == 0) {
      std::fill(vertex_stamp.begin(), vertex_stamp.end(), 0u);
      std::fill(face_stamp.begin(), face_stamp.end(), 0u);
      epoch = 1;
    }
    return epoch;
  }
};

// Adds the vertices within `depth` edges of the region's first vertices (already in it) to the
// region, level after level (vertex_level_end[d]: region vertices at levels 0..d), and builds
// the region's adjacency in local ids.
void grow_region(BatchScratch& s, int depth, const Adjacency& vv, std::uint32_t epoch) {
  s.vertex_level_end.assign(1, static_cast<std::uint32_t>(s.region_vertices.size()));
  std::size_t begin = 0;
  for (int d = 0; d < depth; ++d) {
    const std::size_t end = s.region_vertices.size();
    for (std::size_t i = begin; i < end; ++i) {
      const std::uint32_t v = s.region_vertices[i];
      for (std::uint32_t j = vv.offsets[v]; j < vv.offsets[v + 1]; ++j) {
        const std::uint32_t u = vv.items[j];
        if (s.vertex_stamp[u] == epoch) continue;
        s.vertex_stamp[u] = epoch;
        s.vertex_local[u] = static_cast<std::uint32_t>(s.region_vertices.size());
        s.region_vertices.push_back(u);
      }
    }
    begin = end;
    s.vertex_level_end.push_back(static_cast<std::uint32_t>(s.region_vertices.size()));
  }
  s.local_offsets.resize(s.region_vertices.size() + 1);
  s.local_offsets[0] = 0;
  s.local_items.clear();
  for (std::size_t i = 0; i < s.region_vertices.size(); ++i) {
    const std::uint32_t v = s.region_vertices[i];
    for (std::uint32_t j = vv.offsets[v]; j < vv.offsets[v + 1]; ++j) {
      const std::uint32_t u = vv.items[j];
      if (s.vertex_stamp[u] == epoch) s.local_items.push_back(s.vertex_local[u]);
    }
    s.local_offsets[i + 1] = static_cast<std::uint32_t>(s.local_items.size());
  }
}

// An item new to the points of `fresh` in the current ring (of weight w).
inline void ring_item(BatchScratch& s, std::uint64_t fresh, float value, double w, double* sum,
                      double* weight) {
  if (s.simd)
    s.ring.push_back({fresh, value});
  else
    add_item({fresh, value}, w, sum, weight);
}

// D_d from D_{d-1} on the vertices before `end` (s.reach -> s.next, then swapped). Both
// buffers start zero and each pass writes a longer prefix than the pass before it on the same
// buffer, so what lies past `end` stays zero, as D does there. With `values`, also sums the
// vertices new to some point's ring with weight w (the vertex walk).
void spread(BatchScratch& s, std::uint32_t end, const float* values, double w, double* sum,
            double* weight) {
  const std::uint64_t* from = s.reach.data();
  std::uint64_t* to = s.next.data();
  for (std::uint32_t v = 0; v < end; ++v) {
    std::uint64_t m = from[v];
    for (std::uint32_t j = s.local_offsets[v]; j < s.local_offsets[v + 1]; ++j)
      m |= from[s.local_items[j]];
    to[v] = m;
    if (values) {
      const std::uint64_t fresh = m & ~from[v];
      if (fresh) ring_item(s, fresh, values[s.region_vertices[v]], w, sum, weight);
    }
  }
  s.reach.swap(s.next);
}

// Mask buffers for a region of `region` vertices plus the spare slot, all zero.
void clear_masks(BatchScratch& s, std::size_t region) {
  s.reach.assign(region + 1, 0u);
  s.next.assign(region + 1, 0u);
}

// Vertex rings for the batch points[0 .. count).
void kring_vertex_batch(const std::uint32_t* points, int count, int k, const float* ring_weight,
                        const Adjacency& vv, const float* values, BatchScratch& s, double* sum,
                        double* weight) {
  const std::uint32_t epoch = s.next_epoch();
  s.region_vertices.clear();
  for (int b = 0; b < count; ++b) {
    const std::uint32_t v = points[b];
    s.vertex_stamp[v] = epoch;
    s.vertex_local[v] = static_cast<std::uint32_t>(b);
    s.region_vertices.push_back(v);
  }
  grow_region(s, k, vv, epoch);
  clear_masks(s, s.region_vertices.size());
  for (int b = 0; b < count; ++b) {
    s.reach[b] = std::uint64_t(1) << b;
    sum[b] = ring_weight[0] * static_cast<double>(values[points[b]]);
    weight[b] = ring_weight[0];
  }
  for (int r = 1; r <= k; ++r) {
    s.ring.clear();
    spread(s, s.vertex_level_end[r], values, ring_weight[r], sum, weight);
    if (s.simd) add_ring_avx512(s.ring.data(), s.ring.size(), ring_weight[r], sum, weight);
  }
}

// Face rings for the batch points[0 .. count).
void kring_face_batch(const std::uint32_t* points, int count, int k, const float* ring_weight,
                      const glm::uvec3* triangles, const Adjacency& vf, const Adjacency& vv,
                      const float* values, BatchScratch& s, double* sum, double* weight) {
  const std::uint32_t epoch = s.next_epoch();
  s.region_vertices.clear();
  for (int b = 0; b < count; ++b)
    for (int c = 0; c < 3; ++c) {
      const std::uint32_t v = triangles[points[b]][c];
      if (s.vertex_stamp[v] == epoch) continue;
      s.vertex_stamp[v] = epoch;
      s.vertex_local[v] = static_cast<std::uint32_t>(s.region_vertices.size());
      s.region_vertices.push_back(v);
    }
  grow_region(s, k - 1, vv, epoch);
  // The faces around the region's vertices, the batch faces first (their corners are on
  // level 0), then by the level of their first listed corner.
  s.region_faces.assign(points, points + count);
  for (int b = 0; b < count; ++b) s.face_stamp[points[b]] = epoch;
  s.face_level_end.clear();
  std::uint32_t v = 0;
  for (const std::uint32_t level_end : s.vertex_level_end) {
    for (; v < level_end; ++v) {
      const std::uint32_t global = s.region_vertices[v];
      for (std::uint32_t j = vf.offsets[global]; j < vf.offsets[global + 1]; ++j) {
        const std::uint32_t g = vf.items[j];
        if (s.face_stamp[g] == epoch) continue;
        s.face_stamp[g] = epoch;
        s.region_faces.push_back(g);
      }
    }
    s.face_level_end.push_back(static_cast<std::uint32_t>(s.region_faces.size()));
  }
  const std::size_t faces = s.region_faces.size(), region = s.region_vertices.size();
  s.face_corners.resize(3 * faces);
  for (std::size_t f = 0; f < faces; ++f)
    for (int c = 0; c < 3; ++c) {
      const std::uint32_t u = triangles[s.region_faces[f]][c];
      s.face_corners[3 * f + c] =
          s.vertex_stamp[u] == epoch ? s.vertex_local[u] : static_cast<std::uint32_t>(region);
    }
  clear_masks(s, region);
  s.seen.assign(faces, 0u);
  for (int b = 0; b < count; ++b) {
    const std::uint64_t bit = std::uint64_t(1) << b;
    s.seen[b] = bit;
    for (int c = 0; c < 3; ++c) s.reach[s.vertex_local[triangles[points[b]][c]]] |= bit;
    sum[b] = ring_weight[0] * static_cast<double>(values[points[b]]);
    weight[b] = ring_weight[0];
  }
  for (int d = 0; d < k; ++d) {
    if (d > 0) spread(s, s.vertex_level_end[d], nullptr, 0.0, nullptr, nullptr);
    const double w = ring_weight[d + 1];
    s.ring.clear();
    const std::uint64_t* reach = s.reach.data();
    const std::uint32_t end = s.face_level_end[d];
    for (std::uint32_t f = 0; f < end; ++f) {
      const std::uint32_t* corner = &s.face_corners[3 * f];
      const std::uint64_t fresh =
          (reach[corner[0]] | reach[corner[1]] | reach[corner[2]]) & ~s.seen[f];
      if (!fresh) continue;
      s.seen[f] |= fresh;
      ring_item(s, fresh, values[s.region_faces[f]], w, sum, weight);
    }
    if (s.simd) add_ring_avx512(s.ring.data(), s.ring.size(), w, sum, weight);
  }
}

// Points in Morton order of their positions, so that a batch of consecutive points is a
// compact patch and the region it walks stays small. Ties keep index order (a stable sort of
// the 30-bit codes), so the batches depend on nothing but the mesh.
UninitializedVector<std::uint32_t> morton_order(const UninitializedVector<glm::vec3>& positions,
                                                unsigned threads) {
  const std::size_t n = positions.size();
  constexpr std::size_t kBlock = 1 << 16;
  const std::size_t blocks = std::max<std::size_t>(1, (n + kBlock - 1) / kBlock);
  std::vector<glm::vec3> block_lo(blocks, glm::vec3(std::numeric_limits<float>::infinity()));
  std::vector<glm::vec3> block_hi(blocks, -block_lo[0]);
  parallel_for(blocks, 1, threads, [&](std::size_t b0, std::size_t b1) {
    // In registers: stores into the shared arrays on every point made the blocks of two
    // threads fight over cache lines (slower on 2 threads than on 1).
    for (std::size_t b = b0; b < b1; ++b) {
      glm::vec3 l = block_lo[b], h = block_hi[b];
      for (std::size_t i = b * kBlock; i < std::min(n, (b + 1) * kBlock); ++i) {
        l = glm::min(l, positions[i]);
        h = glm::max(h, positions[i]);
      }
      block_lo[b] = l;
      block_hi[b] = h;
    }
  });
  glm::vec3 lo = block_lo[0], hi = block_hi[0];
  for (std::size_t b = 1; b < blocks; ++b) {
    lo = glm::min(lo, block_lo[b]);
    hi = glm::max(hi, block_hi[b]);
  }
  const glm::vec3 extent = hi - lo;
  const float side = std::max(extent.x, std::max(extent.y, extent.z));
  const float scale = side > 0.0f ? 1023.0f / side : 0.0f;
  // (code << 32) | index: sorting by the code's 30 bits keeps equal codes in index order.
  UninitializedVector<std::uint64_t> keyed(n);
  parallel_for(n, kBlock, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      const glm::vec3 q = (positions[i] - lo) * scale;
      const std::uint64_t code = morton_30(glm::uvec3(q));
      keyed[i] = code << 32 | i;
    }
  });
  radix_sort_by_bits(keyed, 32, 30, threads);
  UninitializedVector<std::uint32_t> order(n);
  parallel_for(n, kBlock, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) order[i] = static_cast<std::uint32_t>(keyed[i]);
  });
  return order;
}

// ---- Setup: the merged mesh renumbered, on parallel_for (no serial pass over the mesh: at
// 16 threads those took most of the time of k = 1). ----

constexpr std::size_t kGrain = 1 << 15;  // items per chunk of the setup loops

// The inverse of a permutation: order[i] -> i.
UninitializedVector<std::uint32_t> inverse(const UninitializedVector<std::uint32_t>& order,
                                           unsigned threads) {
  UninitializedVector<std::uint32_t> rank(order.size());
  parallel_for(order.size(), kGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) rank[order[i]] = static_cast<std::uint32_t>(i);
  });
  return rank;
}

// 0, 1, ..., n - 1.
UninitializedVector<std::uint32_t> identity_order(std::size_t n, unsigned threads) {
  UninitializedVector<std::uint32_t> order(n);
  parallel_for(n, kGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) order[i] = static_cast<std::uint32_t>(i);
  });
  return order;
}

// Each merged vertex at the position of its first input vertex.
UninitializedVector<glm::vec3> merged_positions(const Mesh& mesh, const Weld& weld,
                                                unsigned threads) {
  UninitializedVector<glm::vec3> position(weld.count);
  parallel_for(weld.count, kGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t w = begin; w < end; ++w) position[w] = mesh.vertices[weld.first[w]];
  });
  return position;
}

// Three times each face's centroid (the Morton order needs no division).
UninitializedVector<glm::vec3> centroids(const Mesh& mesh, unsigned threads) {
  UninitializedVector<glm::vec3> centroid(mesh.triangles.size());
  parallel_for(mesh.triangles.size(), kGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t f = begin; f < end; ++f) {
      const glm::uvec3 t = mesh.triangles[f];
      centroid[f] = mesh.vertices[t.x] + mesh.vertices[t.y] + mesh.vertices[t.z];
    }
  });
  return centroid;
}

// The mesh the rings walk: vertices merged (mesh_weld.h), merged vertices and faces
// renumbered in Morton order of their positions (a batch of consecutive points is then a
// compact patch, and its walk reads nearby memory whatever the input's order: a subdivided
// mesh scatters neighbours all over its arrays), and its adjacency.
struct RingMesh {
  Weld weld;
  UninitializedVector<std::uint32_t> new_vertex;  // input vertex -> new merged vertex
  UninitializedVector<std::uint32_t> face_order;  // new -> input face
  UninitializedVector<glm::uvec3> triangles;      // new faces, new vertices
  Adjacency faces_of_vertices, vertex_neighbours;
};

// Faces are ordered only for face values; for vertex values they only link vertices.
RingMesh ring_mesh(const Mesh& mesh, bool faces, double weld_tolerance_relative, unsigned threads,
                   StageClock& clock, StageTimings* timings) {
  RingMesh r;
  r.weld = weld_tolerance_relative >= 0.0
               ? weld_vertices(mesh.vertices.data(), mesh.vertices.size(),
                               weld_tolerance(mesh, weld_tolerance_relative), threads, timings)
               : identity_weld(mesh.vertices.size(), threads);
  clock.lap("weld");
  const UninitializedVector<glm::vec3> merged_position = merged_positions(mesh, r.weld, threads);
  clock.lap("merged positions");
  const UninitializedVector<std::uint32_t> vertex_rank =  // merged -> new
      inverse(morton_order(merged_position, threads), threads);
  // Composed once: one look-up per corner below instead of two dependent ones.
  r.new_vertex.resize(mesh.vertices.size());
  parallel_for(r.new_vertex.size(), kGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t v = begin; v < end; ++v) r.new_vertex[v] = vertex_rank[r.weld.merged[v]];
  });
  clock.lap("vertex order");
  const std::size_t m = mesh.triangles.size();
  r.face_order =
      faces ? morton_order(centroids(mesh, threads), threads) : identity_order(m, threads);
  clock.lap("face order");
  r.triangles.resize(m);
  parallel_for(m, kGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t f = begin; f < end; ++f) {
      const glm::uvec3 t = mesh.triangles[r.face_order[f]];
      r.triangles[f] = glm::uvec3(r.new_vertex[t.x], r.new_vertex[t.y], r.new_vertex[t.z]);
    }
  });
  clock.lap("triangles");
  r.faces_of_vertices = faces_of_vertices(r.triangles.data(), m, r.weld.count, threads);
  clock.lap("faces of vertices");
  r.vertex_neighbours = vertex_neighbours(r.triangles.data(), r.faces_of_vertices, threads);
  clock.lap("vertex neighbours");
  return r;
}

// Per input vertex, 1 where a face uses it.
std::unique_ptr<std::atomic<std::uint8_t>[]> used_vertices(const Mesh& mesh, unsigned threads) {
  std::unique_ptr<std::atomic<std::uint8_t>[]> used(
      new std::atomic<std::uint8_t>[mesh.vertices.size()]());
  parallel_for(mesh.triangles.size(), kGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t f = begin; f < end; ++f)
      for (int k = 0; k < 3; ++k) used[mesh.triangles[f][k]].store(1, std::memory_order_relaxed);
  });
  return used;
}

// Per merged vertex (new_vertex: input vertex -> its merged vertex in the new numbering), the
// mean of its input vertices' values within [lo, hi], summed in double in index order. The
// first input vertex of each starts its sum in parallel; the others (a few percent: seams) are
// added after, in index order, as the serial loop this replaced added them all. Vertices no
// face uses take no part where a used one merged with them: they cast nothing, and their
// values are stand-ins (compute() fills them), which a vertex at their position would take in
// (a review: the back of a double-sided mesh, left out of the cast, 6.6x at worst). A merged
// vertex of unused ones only takes its first one's value.
UninitializedVector<float> merged_values(const float* values, std::size_t n, const Weld& weld,
                                         const UninitializedVector<std::uint32_t>& new_vertex,
                                         const std::atomic<std::uint8_t>* used, float lo, float hi,
                                         unsigned threads) {
  UninitializedVector<double> sum(weld.count);
  UninitializedVector<std::uint32_t> count(weld.count);
  auto is_used = [&](std::uint32_t v) { return used[v].load(std::memory_order_relaxed) != 0; };
  parallel_for(weld.count, kGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t w = begin; w < end; ++w) {
      const std::uint32_t v = weld.first[w];
      sum[new_vertex[v]] = 0.0 + static_cast<double>(values[v]);  // -0 as 0 + -0 makes it
      count[new_vertex[v]] = is_used(v) ? 1 : 0;
    }
  });
  const std::vector<std::uint32_t> joined =
      indices_where(n, threads, [&](std::size_t v) { return weld.first[weld.merged[v]] != v; });
  for (const std::uint32_t v : joined) {
    if (!is_used(v)) continue;
    std::uint32_t& c = count[new_vertex[v]];
    sum[new_vertex[v]] = c == 0 ? 0.0 + static_cast<double>(values[v])  // an unused first
                                : sum[new_vertex[v]] + values[v];
    ++c;
  }
  UninitializedVector<float> mean(weld.count);
  parallel_for(weld.count, kGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t w = begin; w < end; ++w)
      mean[w] = std::min(hi, std::max(lo, static_cast<float>(sum[w] / std::max(count[w], 1u))));
  });
  return mean;
}

// ---- Rings with corner preservation: one walk per point (kernel style: flat arrays). ----
// Scratch: `stamp` has one entry per item walked (vertex or face); an item is visited in the
// current walk when stamp[item] == epoch, so nothing is cleared between points. `queue` holds
// the items of the walk, ring after ring.

// Weight of a step between two points whose unit normals are a and b: exp(-1/2 (angle /
// corner)^2), 1 where a normal is undefined (zero).
float corner_step(const glm::vec3 a, const glm::vec3 b, float inv_corner) {
  if (a == glm::vec3(0.0f) || b == glm::vec3(0.0f)) return 1.0f;
  const float angle = std::acos(std::min(1.0f, std::max(-1.0f, glm::dot(a, b))));
  const float x = angle * inv_corner;
  return std::exp(-0.5f * x * x);
}

// Rings with corner preservation, for either kind: neighbours of item q are
// items[offsets[...]] reached through `hops` (vertices: its edge neighbours; faces: the faces
// around each of its 3 corners). Each item carries the best product of step weights from the
// centre through consecutive rings; `ring_of` and `factor` are per-item scratch valid where
// stamp == epoch.
struct CornerWalk {
  const std::uint32_t* triangles;  // faces only: welded corners, 3 per face
  const std::uint32_t* offsets;    // vertices: edge neighbours; faces: faces around a vertex
  const std::uint32_t* items;
  const glm::vec3* normals;  // unit, per item (zero = undefined)
  bool faces;
};

double kring_corner_mean(std::uint32_t center, int k, const float* ring_weight,
                         const CornerWalk* walk, float inv_corner, const float* values,
                         std::uint32_t* stamp, std::uint32_t epoch, std::uint32_t* queue,
                         std::uint8_t* ring_of, float* factor, float* low, float* high) {
  std::uint32_t begin = 0, end = 1;
  queue[0] = center;
  stamp[center] = epoch;
  ring_of[center] = 0;
  factor[center] = 1.0f;
  for (int r = 0; r < k; ++r) {
    const std::uint32_t ring_end = end;
    for (std::uint32_t i = begin; i < ring_end; ++i) {
      const std::uint32_t q = queue[i];
      const int lists = walk->faces ? 3 : 1;
      for (int c = 0; c < lists; ++c) {
        const std::uint32_t key = walk->faces ? walk->triangles[3 * q + c] : q;
        for (std::uint32_t j = walk->offsets[key]; j < walk->offsets[key + 1]; ++j) {
          const std::uint32_t g = walk->items[j];
          if (stamp[g] == epoch && ring_of[g] != r + 1) continue;  // an earlier ring
          const float f = factor[q] * corner_step(walk->normals[q], walk->normals[g], inv_corner);
          if (stamp[g] != epoch) {
            stamp[g] = epoch;
            ring_of[g] = static_cast<std::uint8_t>(r + 1);
            factor[g] = f;
            queue[end++] = g;
          } else if (f > factor[g]) {
            factor[g] = f;  // a smoother path from ring r
          }
        }
      }
    }
    begin = ring_end;
    if (begin == end) break;
  }
  double sum = 0.0, weight = 0.0;
  float lo = values[center], hi = values[center];
  for (std::uint32_t i = 0; i < end; ++i) {
    const std::uint32_t g = queue[i];
    const double w = static_cast<double>(ring_weight[ring_of[g]]) * factor[g];
    if (!(w > 0.0)) continue;  // underflowed across a crease: contributes nothing
    const float x = values[g];
    sum += w * static_cast<double>(x);
    weight += w;
    lo = std::min(lo, x);
    hi = std::max(hi, x);
  }
  *low = lo;
  *high = hi;
  return sum / weight;  // the centre always weighs ring_weight[0] * 1 > 0
}

// ---- Host side ----

// Scratch of the corner walk (items are faces or vertices, by the kind).
struct Scratch {
  std::vector<std::uint32_t> stamp, queue;
  std::vector<std::uint8_t> ring_of;
  std::vector<float> factor;
  std::uint32_t epoch = 0;
  // Next walk's epoch; on wrap-around every stamp is cleared so no old mark looks current.
  std::uint32_t next_epoch() {
    if (++epoch == 0) {
      std::fill(stamp.begin(), stamp.end(), 0u);
      epoch = 1;
    }
    return epoch;
  }
};

// One scratch per concurrent chunk, made on first need and reused by later chunks.
template <class S>
class ScratchPool {
 public:
  explicit ScratchPool(std::function<std::unique_ptr<S>()> make) : make_(std::move(make)) {}
  std::unique_ptr<S> acquire() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (!free_.empty()) {
        std::unique_ptr<S> s = std::move(free_.back());
        free_.pop_back();
        return s;
      }
    }
    return make_();
  }
  void release(std::unique_ptr<S> s) {
    std::lock_guard<std::mutex> lock(mutex_);
    free_.push_back(std::move(s));
  }

 private:
  std::function<std::unique_ptr<S>()> make_;
  std::mutex mutex_;
  std::vector<std::unique_ptr<S>> free_;
};

glm::vec3 unit_or_zero(glm::vec3 v) {
  const float len = glm::length(v);
  if (!(len > 1e-30f) || !std::isfinite(len)) return glm::vec3(0.0f);
  return v / len;
}

// Unit normals of the points for corner preservation: of the faces (in the new order), or of
// the merged vertices, the area-weighted mean of the faces around. A vertex sums its faces in
// increasing order, once per corner it is (the order of the serial scatter over the faces this
// replaced, so the same sums).
UninitializedVector<glm::vec3> unit_normals(const Mesh& mesh,
                                            const UninitializedVector<std::uint32_t>& face_order,
                                            const glm::uvec3* tris, const Adjacency& vf, bool faces,
                                            unsigned threads) {
  const std::size_t m = mesh.triangles.size();
  UninitializedVector<glm::vec3> face_normal(m);
  parallel_for(m, kGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t f = begin; f < end; ++f)
      face_normal[f] = face_area_normal(mesh, face_order[f]);
  });
  if (faces) {
    parallel_for(m, kGrain, threads, [&](std::size_t begin, std::size_t end) {
      for (std::size_t f = begin; f < end; ++f) face_normal[f] = unit_or_zero(face_normal[f]);
    });
    return face_normal;
  }
  UninitializedVector<glm::vec3> normal(vf.size());
  parallel_for(vf.size(), kGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t v = begin; v < end; ++v) {
      glm::vec3 sum(0.0f);
      for (std::uint32_t i = vf.offsets[v]; i < vf.offsets[v + 1]; ++i)
        for (int c = 0; c < 3; ++c)
          if (tris[vf.items[i]][c] == v) sum += face_normal[vf.items[i]];
      normal[v] = unit_or_zero(sum);
    }
  });
  return normal;
}

}  // namespace

int default_kring_k(std::size_t face_count) {
  if (face_count == 0) return 1;
  const double k =
      std::round(2.0 + 3.0 * std::log(static_cast<double>(face_count) / 20000.0) / std::log(25.0));
  return static_cast<int>(std::min(16.0, std::max(1.0, k)));
}

void smooth_kring_into(const Mesh& mesh, PointKind kind, const float* values,
                       const KringOptions& options, float* out, const ProgressFn& progress,
                       double progress_from, double progress_to, StageTimings* timings) {
  StageClock clock(timings);
  const bool faces = kind == PointKind::Faces;
  const std::size_t n = faces ? mesh.triangles.size() : mesh.vertices.size();
  const int k = options.k < 0 ? default_kring_k(mesh.triangles.size()) : options.k;
  if (k > 255) throw std::invalid_argument("k must be at most 255, got " + std::to_string(k));
  if (!(options.sigma >= 0.0) || !std::isfinite(options.sigma))
    throw std::invalid_argument("sigma must be a finite number >= 0");
  if (!(options.corner_angle >= 0.0) || !std::isfinite(options.corner_angle))
    throw std::invalid_argument("corner_angle must be a finite number of degrees >= 0");

  auto unchanged = [&] { std::copy(values, values + n, out); };
  if (k == 0 || n == 0) return unchanged();
  const ValueRange range = value_range(values, n, options.threads, not_finite);
  if (range.first_bad < n)
    throw std::invalid_argument("value " + std::to_string(range.first_bad) + " is not finite");
  const float lo = range.lo, hi = range.hi;
  if (lo == hi) return unchanged();  // constant: exactly unchanged
  clock.lap("checks");

  if (progress && !progress(progress_from)) throw Cancelled();
  const unsigned threads = options.threads;
  const RingMesh ring = ring_mesh(mesh, faces, options.weld_tolerance, threads, clock, timings);
  const Weld& weld = ring.weld;
  const UninitializedVector<std::uint32_t>& face_order = ring.face_order;
  const UninitializedVector<std::uint32_t>& new_vertex = ring.new_vertex;
  const UninitializedVector<glm::uvec3>& tris = ring.triangles;
  const Adjacency& vf = ring.faces_of_vertices;
  const Adjacency& vv = ring.vertex_neighbours;

  // Values in the new numbering; a merged vertex takes the mean of its duplicates' values.
  const std::size_t points = faces ? n : weld.count;
  UninitializedVector<float> point_values;
  if (faces) {
    point_values.resize(n);
    parallel_for(n, kGrain, threads, [&](std::size_t begin, std::size_t end) {
      for (std::size_t f = begin; f < end; ++f) point_values[f] = values[face_order[f]];
    });
  } else {
    point_values = merged_values(values, n, weld, new_vertex, used_vertices(mesh, threads).get(),
                                 lo, hi, threads);
  }

  const double sigma = options.sigma > 0.0 ? options.sigma : 0.5 * k;
  std::vector<float> ring_weight(k + 1);
  for (int r = 0; r <= k; ++r)
    ring_weight[r] = static_cast<float>(std::exp(-0.5 * (r / sigma) * (r / sigma)));

  const bool corner = options.corner_angle > 0.0;
  const float inv_corner =
      corner ? static_cast<float>(180.0 / (options.corner_angle * 3.14159265358979323846)) : 0.0f;
  const UninitializedVector<glm::vec3> normals =
      corner ? unit_normals(mesh, face_order, tris.data(), vf, faces, threads)
             : UninitializedVector<glm::vec3>();
  const CornerWalk walk = {reinterpret_cast<const std::uint32_t*>(tris.data()),
                           faces ? vf.offsets.data() : vv.offsets.data(),
                           faces ? vf.items.data() : vv.items.data(), normals.data(), faces};
  clock.lap("point values");

  UninitializedVector<float> smoothed(points);
  if (corner) {
    const std::size_t items = faces ? n : weld.count;
    ScratchPool<Scratch> pool([items] {
      auto s = std::make_unique<Scratch>();
      s->stamp.assign(items, 0u);
      s->queue.resize(items);
      s->ring_of.resize(items);
      s->factor.resize(items);
      return s;
    });
    parallel_for(
        points, 512, options.threads,
        [&](std::size_t begin, std::size_t end) {
          std::unique_ptr<Scratch> s = pool.acquire();
          for (std::size_t p = begin; p < end; ++p) {
            const std::uint32_t epoch = s->next_epoch();
            float local_lo, local_hi;
            const double mean = kring_corner_mean(
                static_cast<std::uint32_t>(p), k, ring_weight.data(), &walk, inv_corner,
                point_values.data(), s->stamp.data(), epoch, s->queue.data(), s->ring_of.data(),
                s->factor.data(), &local_lo, &local_hi);
            // A weighted mean lies within what it averages; the clamp only removes rounding.
            smoothed[p] = std::min(local_hi, std::max(local_lo, static_cast<float>(mean)));
          }
          pool.release(std::move(s));
        },
        progress, progress_from, progress_to);
  } else {
    const std::size_t vertex_count = weld.count, face_count = faces ? n : 0;
    ScratchPool<BatchScratch> pool([vertex_count, face_count] {
      auto s = std::make_unique<BatchScratch>();
      s->vertex_stamp.assign(vertex_count, 0u);
      s->vertex_local.resize(vertex_count);
      s->face_stamp.assign(face_count, 0u);
      return s;
    });
    const std::size_t batches = (points + kBatch - 1) / kBatch;
    parallel_for(
        batches, 16, options.threads,
        [&](std::size_t begin, std::size_t end) {
          std::unique_ptr<BatchScratch> s = pool.acquire();
          double sum[kBatch] = {}, weight[kBatch] = {};  // all 64 read by add_ring_avx512
          std::uint32_t batch[kBatch];
          for (std::size_t b = begin; b < end; ++b) {
            const int count = static_cast<int>(std::min<std::size_t>(kBatch, points - b * kBatch));
            for (int i = 0; i < count; ++i) batch[i] = static_cast<std::uint32_t>(b * kBatch + i);
            if (faces)
              kring_face_batch(batch, count, k, ring_weight.data(), tris.data(), vf, vv,
                               point_values.data(), *s, sum, weight);
            else
              kring_vertex_batch(batch, count, k, ring_weight.data(), vv, point_values.data(), *s,
                                 sum, weight);
            // Sums in double, then one rounding to float: a constant region gives back its
            // value exactly; the clamp only guards the input's range.
            for (int i = 0; i < count; ++i)
              smoothed[batch[i]] =
                  std::min(hi, std::max(lo, static_cast<float>(sum[i] / weight[i])));
          }
          pool.release(std::move(s));
        },
        progress, progress_from, progress_to);
  }
  if (progress && !progress(progress_to)) throw Cancelled();
  clock.lap("rings");

  if (faces) {
    parallel_for(n, kGrain, threads, [&](std::size_t begin, std::size_t end) {
      for (std::size_t f = begin; f < end; ++f) out[face_order[f]] = smoothed[f];
    });
  } else {
    parallel_for(n, kGrain, threads, [&](std::size_t begin, std::size_t end) {
      for (std::size_t v = begin; v < end; ++v) out[v] = smoothed[new_vertex[v]];
    });
  }
  clock.lap("write back");
}

std::vector<float> smooth_kring(const Mesh& mesh, PointKind kind, const float* values,
                                const KringOptions& options, const ProgressFn& progress,
                                double progress_from, double progress_to) {
  std::vector<float> out(kind == PointKind::Faces ? mesh.triangles.size() : mesh.vertices.size());
  smooth_kring_into(mesh, kind, values, options, out.data(), progress, progress_from, progress_to);
  return out;
}

}  // namespace sdf
