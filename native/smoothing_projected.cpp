// SPDX-License-Identifier: GPL-3.0-or-later
#include "smoothing_projected.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "morton.h"
#include "prefetch.h"
#include "radix_sort.h"
#include "smoothing_projected_avx2.h"
#include "uninitialized_vector.h"
#include "value_range.h"

namespace sdf {

namespace {

constexpr int kMaxDepth = SDF_POINT_MAX_DEPTH;  // 3 bits per level in a 64-bit Morton key
// Points per chunk of the per-point loops. Per-chunk results (member counts, boxes, value
// ranges) are stored by chunk index, so merging them does not depend on which thread ran what.
constexpr std::size_t kGrain = 1 << 14;
// Sorted values per block of the block minima that the branch-on-minimum test reads: a node's
// minimum then costs its two partial end blocks plus one read per whole block (the old scan of
// every point of every tested node cost points x depth).
constexpr std::size_t kMinBlock = 256;
static_assert(kGrain % kMinBlock == 0, "a chunk holds whole minimum blocks");

std::size_t chunk_count(std::size_t n) { return (n + kGrain - 1) / kGrain; }

void check_options(const ProjectedOptions& options) {
  if (options.max_depth < 0 || options.max_depth > kMaxDepth)
    throw std::invalid_argument("max_depth must be in [0, " + std::to_string(kMaxDepth) +
                                "], got " + std::to_string(options.max_depth));
  if (!(options.min_points >= 0.0 && options.min_points <= 1.0))
    throw std::invalid_argument("min_points must be a fraction in [0, 1]");
  if (!(options.node_size_ratio >= 0.0) || !std::isfinite(options.node_size_ratio))
    throw std::invalid_argument("node_size_ratio must be a finite number >= 0");
}

// The two kinds of input the builder takes: plain arrays (build_point_octree), and the
// smoothing's packed points (xyz projected, w value) with a flag for the points that have an
// inward axis (the others stay out of the tree).
struct ArrayPoints {
  const glm::vec3* points;
  const float* values;
  std::size_t count;
  std::size_t size() const { return count; }
  glm::vec3 point(std::size_t i) const { return points[i]; }
  float value(std::size_t i) const { return values[i]; }
  bool member(std::size_t) const { return true; }
  void prefetch(std::size_t i) const { sdf::prefetch(values + i); }
};

struct PackedPoints {
  const glm::vec4* points;
  const std::uint8_t* members;
  std::size_t count;
  std::size_t size() const { return count; }
  glm::vec3 point(std::size_t i) const { return glm::vec3(points[i]); }
  float value(std::size_t i) const { return points[i].w; }
  bool member(std::size_t i) const { return members[i] != 0; }
  void prefetch(std::size_t i) const { sdf::prefetch(points + i); }
};

// The root cube and each point's Morton key at the deepest level (3 bits a level).
struct RootCube {
  glm::vec3 center, corner;
  float side;
  double cells;  // 2^depth per axis

  // Bounding cube of a box, a little larger so every point falls strictly inside, and never
  // of zero size (all points may coincide, as on a sphere).
  RootCube(glm::vec3 lo, glm::vec3 hi, int depth) {
    const glm::vec3 extent = hi - lo;
    side = std::max(extent.x, std::max(extent.y, extent.z));
    const float magnitude = std::max(glm::length(lo), glm::length(hi));
    side = std::max(side * (1.0f + 1.0f / 1024.0f), std::max(magnitude * 1e-6f, 1e-30f));
    center = 0.5f * (lo + hi);
    cells = std::ldexp(1.0, depth);
    corner = center - glm::vec3(0.5f * side);
  }

  std::uint64_t key(glm::vec3 p) const {
    std::uint64_t key = 0;
    for (int a = 0; a < 3; ++a) {
      const double c = std::floor((p[a] - corner[a]) / side * cells);
      const std::uint64_t cell = static_cast<std::uint64_t>(std::min(cells - 1.0, std::max(0.0, c)));
      key |= spread_bits_21(cell) << a;
    }
    return key;
  }
};

// The members in Morton order, ties in index order (so the order, and every sum over it, is
// the same on any thread count): index(k) is the k-th member's point index, key(k) its key.
// Keys of up to 32 bits (depth <= 10) travel in the sort's items; deeper keys are sorted in
// two stable passes, low 32 bits then the rest, and kept in an array of their own.
struct MortonOrder {
  UninitializedVector<std::uint64_t> items;      // (key << 32) | index, or index alone
  UninitializedVector<std::uint64_t> deep_keys;  // depth > 10 only
  std::uint32_t index(std::size_t k) const { return static_cast<std::uint32_t>(items[k]); }
  std::uint64_t key(std::size_t k) const { return deep_keys.empty() ? items[k] >> 32 : deep_keys[k]; }
};

template <class Points>
MortonOrder morton_order(const Points& points, const RootCube& cube, int key_bits,
                         const std::vector<std::size_t>& first_member, std::size_t members,
                         unsigned threads) {
  const std::size_t n = points.size();
  MortonOrder order;
  order.items.resize(members);
  const bool deep = key_bits > 32;
  parallel_for(n, kGrain, threads, [&](std::size_t begin, std::size_t end) {
    std::size_t to = first_member[begin / kGrain];
    for (std::size_t i = begin; i < end; ++i)
      if (points.member(i)) {
        const std::uint64_t key = cube.key(points.point(i));
        order.items[to++] = (deep ? key & 0xffffffffull : key) << 32 | i;
      }
  });
  radix_sort_by_bits(order.items, 32, std::min(key_bits, 32), threads);
  if (!deep) return order;
  // By the high bits, stably: items of the second pass hold the first pass's position.
  UninitializedVector<std::uint64_t> high(members);
  parallel_for(members, kGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t k = begin; k < end; ++k)
      high[k] = (cube.key(points.point(order.index(k))) >> 32) << 32 | k;
  });
  radix_sort_by_bits(high, 32, key_bits - 32, threads);
  UninitializedVector<std::uint64_t> items(members);
  order.deep_keys.resize(members);
  parallel_for(members, kGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t k = begin; k < end; ++k) {
      const std::uint64_t first = order.items[static_cast<std::uint32_t>(high[k])];
      items[k] = first & 0xffffffffull;
      order.deep_keys[k] = (high[k] >> 32) << 32 | first >> 32;
    }
  });
  order.items.swap(items);
  return order;
}

// Sums and minima of the values over runs of the Morton order.
struct RunValues {
  // prefix[k]: the values of the first k points in Morton order summed one by one in double,
  // as the serial builder did (a run's sum is a difference of two of them: the same bits).
  UninitializedVector<double> prefix;
  UninitializedVector<float> sorted;     // branch on minimum only: values in Morton order
  UninitializedVector<float> block_min;  // ... and the minimum of each kMinBlock of them

  double sum(std::uint32_t begin, std::uint32_t end) const { return prefix[end] - prefix[begin]; }

  float min(std::size_t begin, std::size_t end) const {
    float m = std::numeric_limits<float>::infinity();
    std::size_t k = begin;
    for (; k < end && k % kMinBlock != 0; ++k) m = std::min(m, sorted[k]);
    for (; k + kMinBlock <= end; k += kMinBlock) m = std::min(m, block_min[k / kMinBlock]);
    for (; k < end; ++k) m = std::min(m, sorted[k]);
    return m;
  }
};

template <class Points>
RunValues run_values(const Points& points, const MortonOrder& order, bool by_min,
                     unsigned threads) {
  const std::size_t m = order.items.size();
  RunValues runs;
  runs.prefix.resize(m + 1);
  if (by_min) {
    runs.sorted.resize(m);
    runs.block_min.resize((m + kMinBlock - 1) / kMinBlock);
  }
  parallel_for(m, kGrain, threads, [&](std::size_t begin, std::size_t end) {
    // Reads in Morton order from points in mesh order: each a cache miss once the points
    // outgrow the last-level cache (1.5M points: 90 ms on one thread of the H100 machine's
    // Xeon, 7 on a 128 MiB-L3 EPYC), so the reads are asked for ahead.
    constexpr std::size_t kAhead = 32;
    for (std::size_t k = begin; k < end; ++k) {
      if (k + kAhead < end) points.prefetch(order.index(k + kAhead));
      runs.prefix[k + 1] = points.value(order.index(k));
    }
    if (!by_min) return;
    for (std::size_t block = begin; block < end; block += kMinBlock) {
      float low = std::numeric_limits<float>::infinity();
      for (std::size_t k = block; k < std::min(end, block + kMinBlock); ++k) {
        runs.sorted[k] = static_cast<float>(runs.prefix[k + 1]);
        low = std::min(low, runs.sorted[k]);
      }
      runs.block_min[block / kMinBlock] = low;
    }
  });
  // The one serial pass: a running double sum rounds differently in any other order, and
  // the node means must keep their bits (about 1 ns a point).
  runs.prefix[0] = 0.0;
  for (std::size_t k = 0; k < m; ++k) runs.prefix[k + 1] = runs.prefix[k] + runs.prefix[k + 1];
  return runs;
}

// The nodes, top-down in the serial builder's order (a stack, children in octant order), so
// the array is the same node for node. Work per tested node: eight binary searches (and a
// minimum over block minima), so the loop is short next to the passes above.
std::vector<PointOctreeNode> grow_nodes(const MortonOrder& order, const RunValues& runs,
                                        const RootCube& cube, const ProjectedOptions& options) {
  const std::uint32_t count = static_cast<std::uint32_t>(order.items.size());
  const int depth = options.max_depth;
  const bool by_min = options.branch_on == ProjectedOptions::Branch::Min;
  auto make_node = [&](glm::vec3 c, float half, std::uint32_t begin, std::uint32_t end) {
    PointOctreeNode node;
    node.center[0] = c.x;
    node.center[1] = c.y;
    node.center[2] = c.z;
    node.half_side = half;
    node.count = end - begin;
    node.mean = static_cast<float>(runs.sum(begin, end) / node.count);
    node.first_child = -1;
    node.child_count = 0;
    return node;
  };

  const double branch_above = options.min_points * static_cast<double>(count);
  struct Task {
    std::uint32_t node, begin, end;
    int level;
  };
  std::vector<PointOctreeNode> nodes;
  std::vector<Task> stack;
  nodes.push_back(make_node(cube.center, 0.5f * cube.side, 0, count));
  stack.push_back({0, 0, count, 0});
  while (!stack.empty()) {
    const Task t = stack.back();
    stack.pop_back();
    const PointOctreeNode node = nodes[t.node];
    if (t.level >= depth || !(static_cast<double>(node.count) > branch_above)) continue;
    const float test_value = by_min ? runs.min(t.begin, t.end) : node.mean;
    const bool branch = test_value <= options.node_size_ratio * 2.0 * node.half_side;
    if (!branch) continue;
    const int shift = 3 * (depth - t.level - 1);
    const std::uint32_t first = static_cast<std::uint32_t>(nodes.size());
    std::uint32_t begin = t.begin;
    for (std::uint32_t octant = 0; octant < 8 && begin < t.end; ++octant) {
      // The end of this octant's run: the first key past it (binary search).
      std::uint32_t low = begin, high = t.end;
      while (low < high) {
        const std::uint32_t mid = low + (high - low) / 2;
        if (((order.key(mid) >> shift) & 7u) <= octant) low = mid + 1;
        else high = mid;
      }
      const std::uint32_t end = low;
      if (end == begin) continue;
      const float q = 0.5f * node.half_side;
      const glm::vec3 c(node.center[0] + ((octant & 1) ? q : -q),
                        node.center[1] + ((octant & 2) ? q : -q),
                        node.center[2] + ((octant & 4) ? q : -q));
      stack.push_back({static_cast<std::uint32_t>(nodes.size()), begin, end, t.level + 1});
      nodes.push_back(make_node(c, q, begin, end));
      begin = end;
    }
    nodes[t.node].first_child = static_cast<std::int32_t>(first);
    nodes[t.node].child_count = static_cast<std::uint32_t>(nodes.size()) - first;
  }
  return nodes;
}

// Per chunk of kGrain points: how many are members, and their box. The projection pass of
// the smoothing makes it as it writes the points (one pass less over them);
// build_point_octree() makes it with summarize().
struct ChunkSummary {
  // What one chunk's thread gathers in registers (writing to the shared arrays for every point
  // would bounce their cache lines between threads), then stores once.
  struct Chunk {
    std::size_t members = 0;
    glm::vec3 lo{std::numeric_limits<float>::infinity()};
    glm::vec3 hi{-std::numeric_limits<float>::infinity()};
    void add(glm::vec3 p) {
      ++members;
      lo = glm::min(lo, p);
      hi = glm::max(hi, p);
    }
  };
  std::vector<std::size_t> first_member;  // members before chunk c, for c <= chunks
  std::vector<glm::vec3> lo, hi;

  explicit ChunkSummary(std::size_t n)
      : first_member(chunk_count(n) + 1, 0), lo(chunk_count(n)), hi(chunk_count(n)) {}
  // By the thread that handled the chunk starting at point `begin`.
  void store(std::size_t begin, const Chunk& chunk) {
    first_member[begin / kGrain + 1] = chunk.members;
    lo[begin / kGrain] = chunk.lo;
    hi[begin / kGrain] = chunk.hi;
  }
  void finish() {
    for (std::size_t c = 1; c < first_member.size(); ++c) first_member[c] += first_member[c - 1];
  }
};

template <class Points>
ChunkSummary summarize(const Points& points, unsigned threads) {
  ChunkSummary summary(points.size());
  parallel_for(points.size(), kGrain, threads, [&](std::size_t begin, std::size_t end) {
    ChunkSummary::Chunk chunk;
    for (std::size_t i = begin; i < end; ++i)
      if (points.member(i)) chunk.add(points.point(i));
    summary.store(begin, chunk);
  });
  summary.finish();
  return summary;
}

// The nodes, and the members in the Morton order they were built from (the CPU gather walks
// the points in that order).
struct PointOctree {
  std::vector<PointOctreeNode> nodes;
  MortonOrder order;
};

// Options must have been checked.
template <class Points>
PointOctree build_octree(const Points& points, const ChunkSummary& summary,
                         const ProjectedOptions& options, StageTimings* timings = nullptr) {
  const std::size_t members = summary.first_member.back();
  if (members == 0) return {};
  if (members > std::numeric_limits<std::uint32_t>::max())
    throw std::invalid_argument("too many points for the octree");
  // min and max are exact: the chunks' boxes merge to the same box in any order.
  glm::vec3 lo(std::numeric_limits<float>::infinity()), hi(-std::numeric_limits<float>::infinity());
  for (std::size_t c = 0; c < summary.lo.size(); ++c) {
    lo = glm::min(lo, summary.lo[c]);
    hi = glm::max(hi, summary.hi[c]);
  }
  const RootCube cube(lo, hi, options.max_depth);
  PointOctree tree;
  Stopwatch clock;
  tree.order = morton_order(points, cube, 3 * options.max_depth, summary.first_member, members,
                            options.threads);
  add_time(timings, "octree: Morton order", clock.lap());
  const RunValues runs = run_values(points, tree.order,
                                    options.branch_on == ProjectedOptions::Branch::Min,
                                    options.threads);
  add_time(timings, "octree: sums", clock.lap());
  tree.nodes = grow_nodes(tree.order, runs, cube, options);
  add_time(timings, "octree: nodes", clock.lap());
  return tree;
}

// Where each point starts and which way is inward: recomputed from the mesh for faces (no
// arrays kept: a million faces' origins and axes are 24 MB to write and read back), read from
// sample_points() for vertices (their axes sum the faces around them).
class PointFrames {
 public:
  PointFrames(const Mesh& mesh, PointKind kind, unsigned threads)
      : mesh_(mesh), faces_(kind == PointKind::Faces) {
    if (!faces_) samples_ = sample_points(mesh, kind, threads);
  }
  // Asks for face i's corners ahead of use (prefetch_corners).
  void prefetch(std::size_t i) const {
    if (faces_) prefetch_corners(mesh_, i);
  }
  void frame(std::size_t i, glm::vec3* origin, glm::vec3* axis) const {
    if (faces_) {
      face_point(mesh_, i, origin, axis);
    } else {
      *origin = samples_.origins[i];
      *axis = samples_.axes[i];
    }
  }

 private:
  const Mesh& mesh_;
  bool faces_;
  SamplePoints samples_;
};

std::size_t point_count(const Mesh& mesh, PointKind kind) {
  return kind == PointKind::Faces ? mesh.triangles.size() : mesh.vertices.size();
}

}  // namespace

std::vector<PointOctreeNode> build_point_octree(const glm::vec3* points, const float* values,
                                                std::size_t count,
                                                const ProjectedOptions& options) {
  check_options(options);
  const ArrayPoints input{points, values, count};
  return build_octree(input, summarize(input, options.threads), options).nodes;
}

// ---- Per-point work: kernels/sdf_smooth_projected.h (shared with the OpenCL kernels). ----
float cube_fraction_in_sphere(float side, float distance, float radius) {
  return kern::sdf_cube_fraction_in_sphere(side, distance, radius);
}

bool gather_sphere(const PointOctreeNode* nodes, glm::vec3 center, float radius, float* mean) {
  return kern::sdf_gather_sphere(nodes, center, radius, mean) != 0;
}

void smooth_projected_into(const Mesh& mesh, PointKind kind, const float* values,
                           const ProjectedOptions& options, float* out,
                           const ProgressFn& progress, double progress_from, double progress_to,
                           const ProjectedGatherFn& gather, StageTimings* timings) {
  Stopwatch clock;
  if (options.iterations < 0)
    throw std::invalid_argument("iterations must be >= 0, got " +
                                std::to_string(options.iterations));
  const std::size_t n = point_count(mesh, kind);
  const ValueRange range = value_range(values, n, options.threads, [](float x) {
    return !std::isfinite(x) || x < 0.0f;
  });
  if (range.first_bad < n)
    throw std::invalid_argument("value " + std::to_string(range.first_bad) +
                                " is negative or not finite (projected smoothing needs the "
                                "SDF, a length >= 0)");
  check_options(options);  // even when there is nothing to do
  auto unchanged = [&] { std::copy(values, values + n, out); };
  if (n == 0 || range.lo == range.hi || options.iterations == 0) return unchanged();

  add_time(timings, "checks", clock.lap());
  if (progress && !progress(progress_from)) throw Cancelled();
  const PointFrames frames(mesh, kind, options.threads);
  add_time(timings, "frames", clock.lap());
  // points[i]: point i moved inward by half its value (xyz) and that value (w). Points with no
  // inward axis (zero-area faces, lone vertices) are not moved: they stay out of the tree
  // (member 0), but still gather around their own position.
  UninitializedVector<glm::vec4> points(n);
  UninitializedVector<std::uint8_t> member(n);
  const double span = (progress_to - progress_from) / options.iterations;
  const bool packets = projected_avx2_supported();
  for (int it = 0; it < options.iterations; ++it) {
    // Each iteration smooths the last one's result, in `out` (read here only: from here on
    // the values travel in points[i].w, and the gather overwrites `out`).
    const float* current = it == 0 ? values : out;
    ChunkSummary summary(n);
    parallel_for(n, kGrain, options.threads, [&](std::size_t begin, std::size_t end) {
      ChunkSummary::Chunk chunk;
      for (std::size_t i = begin; i < end; ++i) {
        frames.prefetch(i + kPrefetchFacesAhead);
        glm::vec3 origin, axis;
        frames.frame(i, &origin, &axis);
        const glm::vec3 p = origin + axis * (0.5f * current[i]);
        points[i] = glm::vec4(p, current[i]);
        member[i] = axis != glm::vec3(0.0f);
        if (member[i]) chunk.add(p);
      }
      summary.store(begin, chunk);
    });
    summary.finish();
    add_time(timings, "points", clock.lap());
    const PointOctree tree =
        build_octree(PackedPoints{points.data(), member.data(), n}, summary, options, timings);
    const std::vector<PointOctreeNode>& nodes = tree.nodes;
    clock.lap();  // the octree's stages were added by build_octree
    if (nodes.empty()) return unchanged();  // no point has an axis (then on the first iteration)
    if (gather) {  // it adds its own stages
      gather(nodes, points.data(), n, range.lo, range.hi, out);
      clock.lap();
      if (progress && !progress(progress_from + (it + 1) * span)) throw Cancelled();
      continue;
    }
    auto smooth_point = [&](std::size_t i) {
      out[i] = kern::sdf_smooth_projected_point(nodes.data(), glm::vec3(points[i]), points[i].w,
                                                range.lo, range.hi);
    };
    // Members in Morton order: consecutive points take nearly the same path through the
    // tree, which the branch predictor learns (measured 12-17% faster than mesh order at
    // 1.5M faces, the scattered reads and writes included). The same values either way.
    // On AVX2, eight of them at a time (smoothing_projected_avx2.h): the same bits.
    const std::size_t members = tree.order.items.size();
    parallel_for(
        members, 1024, options.threads,
        [&](std::size_t begin, std::size_t end) {
          if (!packets) {
            for (std::size_t k = begin; k < end; ++k) smooth_point(tree.order.index(k));
            return;
          }
          std::uint32_t index[8];
          for (std::size_t k = begin; k < end; k += 8) {
            const int lanes = static_cast<int>(std::min<std::size_t>(8, end - k));
            for (int l = 0; l < lanes; ++l) index[l] = tree.order.index(k + l);
            smooth_packet_avx2(nodes.data(), points.data(), index, lanes, range.lo, range.hi, out);
          }
        },
        progress, progress_from + it * span, progress_from + (it + 1) * span);
    if (members < n)  // the points with no axis (few: zero-area faces, lone vertices)
      parallel_for(n, kGrain, options.threads, [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i)
          if (!member[i]) smooth_point(i);
      });
    add_time(timings, "gather", clock.lap());
  }
  if (progress && !progress(progress_to)) throw Cancelled();
}

std::vector<float> smooth_projected(const Mesh& mesh, PointKind kind, const float* values,
                                    const ProjectedOptions& options, const ProgressFn& progress,
                                    double progress_from, double progress_to,
                                    const ProjectedGatherFn& gather) {
  std::vector<float> out(point_count(mesh, kind));
  smooth_projected_into(mesh, kind, values, options, out.data(), progress, progress_from,
                        progress_to, gather);
  return out;
}

}  // namespace sdf
