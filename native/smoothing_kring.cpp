// SPDX-License-Identifier: GPL-3.0-or-later
#include "smoothing_kring.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>

#include "mesh_weld.h"

namespace sdf {

namespace {

// ---- Per-point work: plain loops over flat arrays (kernel style: no STL, no references). ----
// Scratch: `stamp` has one entry per item walked (vertex or face); an item is visited in the
// current walk when stamp[item] == epoch, so nothing is cleared between points. `queue` holds
// the items of the walk, ring after ring.

// Vertex rings: Gaussian-weighted mean over the vertices at edge distance 0..k from `center`.
double kring_vertex_mean(std::uint32_t center, int k, const float* ring_weight,
                         const std::uint32_t* vv_offsets, const std::uint32_t* vv_items,
                         const float* values, std::uint32_t* stamp, std::uint32_t epoch,
                         std::uint32_t* queue, float* low, float* high) {
  std::uint32_t begin = 0, end = 1;
  queue[0] = center;
  stamp[center] = epoch;
  double sum = ring_weight[0] * static_cast<double>(values[center]);
  double weight = ring_weight[0];
  float lo = values[center], hi = values[center];
  for (int r = 1; r <= k; ++r) {
    const std::uint32_t ring_end = end;
    for (std::uint32_t i = begin; i < ring_end; ++i) {
      const std::uint32_t v = queue[i];
      for (std::uint32_t j = vv_offsets[v]; j < vv_offsets[v + 1]; ++j) {
        const std::uint32_t u = vv_items[j];
        if (stamp[u] == epoch) continue;
        stamp[u] = epoch;
        queue[end++] = u;
        const float x = values[u];
        sum += ring_weight[r] * static_cast<double>(x);
        weight += ring_weight[r];
        lo = std::min(lo, x);
        hi = std::max(hi, x);
      }
    }
    begin = ring_end;
    if (begin == end) break;  // the component is exhausted
  }
  *low = lo;
  *high = hi;
  return sum / weight;
}

// Face rings (faces sharing a vertex) through the identity in the header: a multi-source walk
// over vertices from the centre face's corners to distance k - 1; the faces around a vertex at
// distance d that are new belong to ring d + 1.
double kring_face_mean(std::uint32_t center, int k, const float* ring_weight,
                       const std::uint32_t* triangles, const std::uint32_t* vf_offsets,
                       const std::uint32_t* vf_items, const std::uint32_t* vv_offsets,
                       const std::uint32_t* vv_items, const float* values,
                       std::uint32_t* vertex_stamp, std::uint32_t* face_stamp,
                       std::uint32_t epoch, std::uint32_t* queue, float* low, float* high) {
  face_stamp[center] = epoch;
  double sum = ring_weight[0] * static_cast<double>(values[center]);
  double weight = ring_weight[0];
  float lo = values[center], hi = values[center];
  std::uint32_t end = 0;
  for (int c = 0; c < 3; ++c) {
    const std::uint32_t v = triangles[3 * center + c];
    if (vertex_stamp[v] == epoch) continue;
    vertex_stamp[v] = epoch;
    queue[end++] = v;
  }
  std::uint32_t begin = 0;
  for (int d = 0; d < k; ++d) {
    const std::uint32_t ring_end = end;
    const double w = ring_weight[d + 1];
    for (std::uint32_t i = begin; i < ring_end; ++i) {
      const std::uint32_t v = queue[i];
      for (std::uint32_t j = vf_offsets[v]; j < vf_offsets[v + 1]; ++j) {
        const std::uint32_t g = vf_items[j];
        if (face_stamp[g] == epoch) continue;
        face_stamp[g] = epoch;
        const float x = values[g];
        sum += w * static_cast<double>(x);
        weight += w;
        lo = std::min(lo, x);
        hi = std::max(hi, x);
      }
      if (d + 1 < k) {
        for (std::uint32_t j = vv_offsets[v]; j < vv_offsets[v + 1]; ++j) {
          const std::uint32_t u = vv_items[j];
          if (vertex_stamp[u] == epoch) continue;
          vertex_stamp[u] = epoch;
          queue[end++] = u;
        }
      }
    }
    begin = ring_end;
    if (begin == end) break;
  }
  *low = lo;
  *high = hi;
  return sum / weight;
}

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
  const glm::vec3* normals;        // unit, per item (zero = undefined)
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

struct Scratch {
  std::vector<std::uint32_t> vertex_stamp, face_stamp, queue;
  std::vector<std::uint8_t> ring_of;
  std::vector<float> factor;
  std::uint32_t epoch = 0;
  // Next walk's epoch; on wrap-around every stamp is cleared so no old mark looks current.
  std::uint32_t next_epoch() {
    if (++epoch == 0) {
      std::fill(vertex_stamp.begin(), vertex_stamp.end(), 0u);
      std::fill(face_stamp.begin(), face_stamp.end(), 0u);
      epoch = 1;
    }
    return epoch;
  }
};

// One scratch per concurrent chunk, made on first need and reused by later chunks.
class ScratchPool {
 public:
  ScratchPool(std::size_t vertices, std::size_t faces, bool corner)
      : vertices_(vertices), faces_(faces), corner_(corner) {}
  std::unique_ptr<Scratch> acquire() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (!free_.empty()) {
        std::unique_ptr<Scratch> s = std::move(free_.back());
        free_.pop_back();
        return s;
      }
    }
    auto s = std::make_unique<Scratch>();
    s->vertex_stamp.assign(vertices_, 0u);
    s->face_stamp.assign(faces_, 0u);
    const std::size_t items = std::max(vertices_, faces_);
    s->queue.resize(items);
    if (corner_) {
      s->ring_of.resize(items);
      s->factor.resize(items);
    }
    return s;
  }
  void release(std::unique_ptr<Scratch> s) {
    std::lock_guard<std::mutex> lock(mutex_);
    free_.push_back(std::move(s));
  }

 private:
  std::size_t vertices_, faces_;
  bool corner_;
  std::mutex mutex_;
  std::vector<std::unique_ptr<Scratch>> free_;
};

glm::vec3 unit_or_zero(glm::vec3 v) {
  const float len = glm::length(v);
  if (!(len > 1e-30f) || !std::isfinite(len)) return glm::vec3(0.0f);
  return v / len;
}

}  // namespace

int default_kring_k(std::size_t face_count) {
  if (face_count == 0) return 1;
  const double k =
      std::round(2.0 + 3.0 * std::log(static_cast<double>(face_count) / 20000.0) / std::log(25.0));
  return static_cast<int>(std::min(16.0, std::max(1.0, k)));
}

std::vector<float> smooth_kring(const Mesh& mesh, PointKind kind, const float* values,
                                const KringOptions& options, const ProgressFn& progress,
                                double progress_from, double progress_to) {
  const bool faces = kind == PointKind::Faces;
  const std::size_t n = faces ? mesh.triangles.size() : mesh.vertices.size();
  const int k = options.k < 0 ? default_kring_k(mesh.triangles.size()) : options.k;
  if (k > 255) throw std::invalid_argument("k must be at most 255, got " + std::to_string(k));
  if (!(options.sigma >= 0.0) || !std::isfinite(options.sigma))
    throw std::invalid_argument("sigma must be a finite number >= 0");
  if (!(options.corner_angle >= 0.0) || !std::isfinite(options.corner_angle))
    throw std::invalid_argument("corner_angle must be a finite number of degrees >= 0");

  std::vector<float> out(values, values + n);
  if (k == 0 || n == 0) return out;
  float lo = std::numeric_limits<float>::infinity(), hi = -lo;
  for (std::size_t i = 0; i < n; ++i) {
    if (!std::isfinite(values[i]))
      throw std::invalid_argument("value " + std::to_string(i) + " is not finite");
    lo = std::min(lo, values[i]);
    hi = std::max(hi, values[i]);
  }
  if (lo == hi) return out;  // constant: exactly unchanged

  if (progress && !progress(progress_from)) throw Cancelled();
  // Merged mesh and its adjacency.
  Weld weld;
  if (options.weld_tolerance >= 0.0) {
    weld = weld_vertices(mesh.vertices.data(), mesh.vertices.size(),
                         weld_tolerance(mesh, options.weld_tolerance));
  } else {
    weld.merged.resize(mesh.vertices.size());
    for (std::size_t v = 0; v < weld.merged.size(); ++v) weld.merged[v] = static_cast<std::uint32_t>(v);
    weld.count = static_cast<std::uint32_t>(weld.merged.size());
  }
  const std::vector<glm::uvec3> tris = welded_triangles(mesh, weld);
  const Adjacency vf = faces_of_vertices(tris, weld.count);
  const Adjacency vv = vertex_neighbours(tris, vf);

  // Vertex values live on merged vertices: the mean of the duplicates' values.
  std::vector<float> merged_values;
  const float* point_values = values;
  if (!faces) {
    std::vector<double> sum(weld.count, 0.0);
    std::vector<std::uint32_t> count(weld.count, 0);
    for (std::size_t v = 0; v < n; ++v) {
      sum[weld.merged[v]] += values[v];
      ++count[weld.merged[v]];
    }
    merged_values.resize(weld.count);
    for (std::size_t w = 0; w < weld.count; ++w)
      merged_values[w] = std::min(hi, std::max(lo, static_cast<float>(sum[w] / count[w])));
    point_values = merged_values.data();
  }
  const std::size_t points = faces ? n : weld.count;

  const double sigma = options.sigma > 0.0 ? options.sigma : 0.5 * k;
  std::vector<float> ring_weight(k + 1);
  for (int r = 0; r <= k; ++r) ring_weight[r] = static_cast<float>(std::exp(-0.5 * (r / sigma) * (r / sigma)));

  const bool corner = options.corner_angle > 0.0;
  const float inv_corner = corner ? static_cast<float>(180.0 / (options.corner_angle * 3.14159265358979323846)) : 0.0f;
  std::vector<glm::vec3> normals;
  if (corner) {
    // Face normals; vertex normals are the area-weighted mean of the merged faces around.
    std::vector<glm::vec3> face_normals(mesh.triangles.size());
    for (std::size_t f = 0; f < face_normals.size(); ++f) face_normals[f] = face_area_normal(mesh, f);
    if (faces) {
      normals.resize(n);
      for (std::size_t f = 0; f < n; ++f) normals[f] = unit_or_zero(face_normals[f]);
    } else {
      normals.assign(weld.count, glm::vec3(0.0f));
      for (std::size_t f = 0; f < tris.size(); ++f)
        for (int c = 0; c < 3; ++c) normals[tris[f][c]] += face_normals[f];
      for (glm::vec3& v : normals) v = unit_or_zero(v);
    }
  }
  const CornerWalk walk = {reinterpret_cast<const std::uint32_t*>(tris.data()),
                           faces ? vf.offsets.data() : vv.offsets.data(),
                           faces ? vf.items.data() : vv.items.data(), normals.data(), faces};

  std::vector<float> smoothed(points);
  ScratchPool pool(weld.count, faces ? n : 0, corner);
  parallel_for(
      points, 512, options.threads,
      [&](std::size_t begin, std::size_t end) {
        std::unique_ptr<Scratch> s = pool.acquire();
        for (std::size_t p = begin; p < end; ++p) {
          const std::uint32_t epoch = s->next_epoch();
          const std::uint32_t c = static_cast<std::uint32_t>(p);
          float local_lo, local_hi;
          double mean;
          if (corner) {
            std::uint32_t* stamp = faces ? s->face_stamp.data() : s->vertex_stamp.data();
            mean = kring_corner_mean(c, k, ring_weight.data(), &walk, inv_corner, point_values,
                                     stamp, epoch, s->queue.data(), s->ring_of.data(),
                                     s->factor.data(), &local_lo, &local_hi);
          } else if (faces) {
            mean = kring_face_mean(c, k, ring_weight.data(), walk.triangles, vf.offsets.data(),
                                   vf.items.data(), vv.offsets.data(), vv.items.data(),
                                   point_values, s->vertex_stamp.data(), s->face_stamp.data(),
                                   epoch, s->queue.data(), &local_lo, &local_hi);
          } else {
            mean = kring_vertex_mean(c, k, ring_weight.data(), vv.offsets.data(), vv.items.data(),
                                     point_values, s->vertex_stamp.data(), epoch, s->queue.data(),
                                     &local_lo, &local_hi);
          }
          // A weighted mean lies within the values it averages; the clamp only removes rounding.
          smoothed[p] = std::min(local_hi, std::max(local_lo, static_cast<float>(mean)));
        }
        pool.release(std::move(s));
      },
      progress, progress_from, progress_to);
  if (progress && !progress(progress_to)) throw Cancelled();

  if (faces) return smoothed;
  for (std::size_t v = 0; v < n; ++v) out[v] = smoothed[weld.merged[v]];
  return out;
}

}  // namespace sdf
