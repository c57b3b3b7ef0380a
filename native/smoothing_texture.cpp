// SPDX-License-Identifier: GPL-3.0-or-later
#include "smoothing_texture.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>

#include "../kernels/sdf_smooth_texture.h"
#include "radix_sort.h"
#include "stopwatch.h"
#include "uninitialized_vector.h"
#include "value_range.h"

namespace sdf {

namespace {

constexpr int kMaxSize = 16384;

// Seconds since the previous lap (or construction).
// ---- Per-texel and per-face work: plain loops over flat arrays (kernel style). ----

// A face's UV triangle in texel units (u * width, v * height) and its covered texels: those
// whose centre (x + 0.5, y + 0.5) lies inside. A centre on an edge belongs to one side only:
// the triangle is turned counter-clockwise, and an edge claims its points when its direction
// (dx, dy) has dy > 0, or dy == 0 and dx < 0; the neighbour across it sees (-dx, -dy). The
// edge functions are evaluated the same way from both sides, so the tie is exact, and a texel
// is never written by two faces of one island. Calls visit(texel index, b0, b1, b2) with the
// barycentric coordinates; returns how many texels.
template <class Visit>
std::uint32_t for_each_texel(const float* uv, int width, int height, Visit&& visit) {
  double x[3], y[3];
  for (int c = 0; c < 3; ++c) {
    x[c] = uv[2 * c] * double(width);
    y[c] = uv[2 * c + 1] * double(height);
  }
  // Texels whose centre may lie inside. Most faces of a dense mesh cover no centre at all:
  // they leave here, before the edge set-up.
  // (Clamped in double: a UV far outside [0, 1] would overflow an int.)
  auto first = [](double lowest, int size) {
    return static_cast<int>(std::max(0.0, std::min(double(size), std::ceil(lowest - 0.5))));
  };
  auto last = [](double highest, int size) {
    return static_cast<int>(std::max(-1.0, std::min(size - 1.0, std::floor(highest - 0.5))));
  };
  const int xmin = first(std::min(x[0], std::min(x[1], x[2])), width);
  const int xmax = last(std::max(x[0], std::max(x[1], x[2])), width);
  const int ymin = first(std::min(y[0], std::min(y[1], y[2])), height);
  const int ymax = last(std::max(y[0], std::max(y[1], y[2])), height);
  if (xmin > xmax || ymin > ymax) return 0;
  double area = (x[1] - x[0]) * (y[2] - y[0]) - (x[2] - x[0]) * (y[1] - y[0]);
  if (!(std::fabs(area) > 0.0)) return 0;
  int order[3] = {0, 1, 2};
  if (area < 0.0) {  // clockwise (a mirrored island): walk it the other way round
    order[1] = 2;
    order[2] = 1;
    area = -area;
  }
  // Edge i runs from corner order[i + 1] to order[i + 2] and is opposite corner order[i].
  double ax[3], ay[3], dx[3], dy[3];
  bool claims[3];
  for (int i = 0; i < 3; ++i) {
    const int a = order[(i + 1) % 3], b = order[(i + 2) % 3];
    ax[i] = x[a];
    ay[i] = y[a];
    dx[i] = x[b] - x[a];
    dy[i] = y[b] - y[a];
    claims[i] = dy[i] > 0.0 || (dy[i] == 0.0 && dx[i] < 0.0);
  }
  const double inv = 1.0 / area;
  std::uint32_t covered = 0;
  for (int py = ymin; py <= ymax; ++py) {
    const double cy = py + 0.5;
    for (int px = xmin; px <= xmax; ++px) {
      const double cx = px + 0.5;
      double e[3];
      bool inside = true;
      for (int i = 0; i < 3 && inside; ++i) {
        // Twice the area of (edge start, edge end, centre): > 0 on the inner side.
        e[i] = dx[i] * (cy - ay[i]) - dy[i] * (cx - ax[i]);
        inside = e[i] > 0.0 || (e[i] == 0.0 && claims[i]);
      }
      if (!inside) continue;
      double b[3];
      for (int i = 0; i < 3; ++i) b[order[i]] = e[i] * inv;
      visit(static_cast<std::size_t>(py) * width + px, b[0], b[1], b[2]);
      ++covered;
    }
  }
  return covered;
}


// Texel under a UV point, or -1 outside the image.
std::int64_t texel_at(float u, float v, int width, int height) {
  const double x = std::floor(u * double(width)), y = std::floor(v * double(height));
  if (!(x >= 0.0 && x < width && y >= 0.0 && y < height)) return -1;
  return static_cast<std::int64_t>(y) * width + static_cast<std::int64_t>(x);
}

constexpr std::size_t kFaceGrain = 1 << 12;
constexpr std::size_t kTexelGrain = 1 << 16;

// The values' range, after checking that values and UVs are finite (the first bad one named).
void check_inputs(const float* values, std::size_t n, const float* uvs, std::size_t m,
                  unsigned threads, float& lo, float& hi) {
  const ValueRange range = value_range(values, n, threads, not_finite);
  if (range.first_bad < n)
    throw std::invalid_argument("value " + std::to_string(range.first_bad) + " is not finite");
  lo = range.lo;
  hi = range.hi;
  const std::size_t floats = 6 * m;
  const std::size_t uv_chunks = (floats + kTexelGrain - 1) / kTexelGrain;
  std::vector<std::size_t> uv_bad(uv_chunks, floats);
  parallel_for(floats, kTexelGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i)
      if (!std::isfinite(uvs[i])) {
        uv_bad[begin / kTexelGrain] = i;
        return;
      }
  });
  for (std::size_t c = 0; c < uv_chunks; ++c)
    if (uv_bad[c] < floats)
      throw std::invalid_argument("the UV of face " + std::to_string(uv_bad[c] / 6) + " corner " +
                                  std::to_string((uv_bad[c] / 2) % 3) + " is not finite");
}

// Step 2 on the CPU threads. Every face offers its value to the texels it covers (a face
// covering none, to the texel under its centroid) as a 64-bit key, kept by atomic maximum:
// high word the rank, low word the value's bits. Covering faces rank m + 1 + f (above any
// centroid, the later face winning), centroid faces m - f (the earlier winning, and only
// where no face covers): the image the serial loop in face order gives, whatever the threads.
void rasterise(const Mesh& mesh, PointKind kind, const float* values, const float* uvs,
               const std::vector<std::int32_t>& face_island, int width, int height, float lo,
               float hi, unsigned threads, std::vector<std::int32_t>& island,
               std::vector<float>& value) {
  const bool faces = kind == PointKind::Faces;
  const std::size_t m = mesh.triangles.size();
  if (m >= (std::size_t{1} << 31)) throw std::invalid_argument("too many faces for the texture");
  const std::size_t texels = static_cast<std::size_t>(width) * height;
  std::unique_ptr<std::atomic<std::uint64_t>[]> owner(new std::atomic<std::uint64_t>[texels]);
  parallel_for(texels, kTexelGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t t = begin; t < end; ++t) owner[t].store(0, std::memory_order_relaxed);
  });
  auto offer = [&](std::size_t t, std::uint64_t rank, float x) {
    std::uint32_t bits;
    std::memcpy(&bits, &x, sizeof bits);
    const std::uint64_t key = (rank << 32) | bits;
    std::uint64_t seen = owner[t].load(std::memory_order_relaxed);
    while (seen < key && !owner[t].compare_exchange_weak(seen, key, std::memory_order_relaxed)) {
    }
  };
  parallel_for(m, kFaceGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t f = begin; f < end; ++f) {
      const float* uv = uvs + 6 * f;
      const std::uint64_t rank = m + 1 + f;
      std::uint32_t covered;
      if (faces) {
        const float x = values[f];
        covered = for_each_texel(uv, width, height,
                                 [&](std::size_t t, double, double, double) { offer(t, rank, x); });
      } else {
        const glm::uvec3 tri = mesh.triangles[f];
        const float a = values[tri.x], b = values[tri.y], c = values[tri.z];
        const float vmin = std::min(a, std::min(b, c)), vmax = std::max(a, std::max(b, c));
        covered = for_each_texel(uv, width, height, [&](std::size_t t, double b0, double b1, double b2) {
          offer(t, rank, std::min(vmax, std::max(vmin, static_cast<float>(b0 * a + b1 * b + b2 * c))));
        });
      }
      if (covered > 0) continue;
      const std::int64_t t = texel_at((uv[0] + uv[2] + uv[4]) / 3.0f, (uv[1] + uv[3] + uv[5]) / 3.0f,
                                      width, height);
      if (t < 0) continue;
      float x;
      if (faces) {
        x = values[f];
      } else {
        const glm::uvec3 tri = mesh.triangles[f];
        x = std::min(hi, std::max(lo, (values[tri.x] + values[tri.y] + values[tri.z]) / 3.0f));
      }
      offer(static_cast<std::size_t>(t), m - f, x);
    }
  });
  island.resize(texels);
  value.resize(texels);
  parallel_for(texels, kTexelGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t t = begin; t < end; ++t) {
      const std::uint64_t key = owner[t].load(std::memory_order_relaxed);
      if (key == 0) {
        island[t] = -1;
        value[t] = 0.0f;
        continue;
      }
      const std::uint64_t rank = key >> 32;
      const std::size_t f = rank > m ? rank - m - 1 : m - rank;
      const std::uint32_t bits = static_cast<std::uint32_t>(key);
      island[t] = face_island[f];
      std::memcpy(&value[t], &bits, sizeof bits);
    }
  });
}

// Steps 3 and 4 on the CPU threads: dilates island and value in place and returns the
// blurred image.
std::vector<float> filter_cpu(const TextureFilter& f, std::vector<std::int32_t>& island,
                              std::vector<float>& value, unsigned threads,
                              const ProgressFn& progress, double progress_from,
                              double progress_to) {
  const int width = f.width, height = f.height, taps = f.taps;
  const std::size_t texels = static_cast<std::size_t>(width) * height;
  auto at = [&](double fraction) { return progress_from + (progress_to - progress_from) * fraction; };
  // Dilate: one ring a pass, each pass reading the last.
  if (f.margin > 0) {
    std::vector<std::int32_t> island2(texels);
    std::vector<float> value2(texels);
    for (int ring = 0; ring < f.margin; ++ring) {
      parallel_for(height, 16, threads, [&](std::size_t begin, std::size_t end) {
        for (std::size_t y = begin; y < end; ++y)
          for (int x = 0; x < width; ++x)
            kern::sdf_dilate_texel(x, static_cast<int>(y), width, height, island.data(),
                                   value.data(), island2.data(), value2.data());
      });
      island.swap(island2);
      value.swap(value2);
    }
  }
  if (progress && !progress(at(0.15))) throw Cancelled();
  if (taps < 1) return std::move(value);

  // Blur: rows (each texel weighing 1), then columns, each texel normalised as it is done.
  const float* kernel = f.kernel.data();
  UninitializedVector<float> row_value(texels), row_weight(texels);
  std::vector<float> blurred(texels);
  parallel_for(
      height, 8, threads,
      [&](std::size_t begin, std::size_t end) {
        for (std::size_t y = begin; y < end; ++y) {
          const std::size_t o = y * width;
          for (int x = 0; x < width; ++x)
            kern::sdf_blur_texel(x, width, 1, island.data() + o, value.data() + o, nullptr,
                                 kernel, taps, f.inv_range, &row_value[o + x], &row_weight[o + x]);
        }
      },
      progress, at(0.15), at(0.5));
  parallel_for(
      width, 8, threads,
      [&](std::size_t begin, std::size_t end) {
        for (std::size_t x = begin; x < end; ++x)
          for (int y = 0; y < height; ++y) {
            float sv, sw;
            kern::sdf_blur_texel(y, height, width, island.data() + x, row_value.data() + x,
                                 row_weight.data() + x, kernel, taps, f.inv_range, &sv, &sw);
            const std::size_t t = static_cast<std::size_t>(y) * width + x;
            blurred[t] = island[t] >= 0 ? kern::sdf_blur_normalize(sv, sw, f.lo, f.hi) : sv;
          }
      },
      progress, at(0.5), at(0.85));
  return blurred;
}

// Step 5 for face values: the mean of the blurred texels a face covers (of its island), else
// the texel under its centroid; faces with neither keep their value (out holds the input).
void read_back_faces(const float* uvs, const std::vector<std::int32_t>& face_island, int width,
                     int height, const std::vector<std::int32_t>& island,
                     const std::vector<float>& blurred, float lo, float hi, unsigned threads,
                     std::vector<float>& out) {
  parallel_for(face_island.size(), kFaceGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t f = begin; f < end; ++f) {
      const std::int32_t id = face_island[f];
      double sum = 0.0;
      std::uint32_t count = 0;
      for_each_texel(uvs + 6 * f, width, height, [&](std::size_t t, double, double, double) {
        if (island[t] != id) return;
        sum += blurred[t];
        ++count;
      });
      if (count > 0) {
        out[f] = std::min(hi, std::max(lo, static_cast<float>(sum / count)));
        continue;
      }
      const float* uv = uvs + 6 * f;
      const std::int64_t t = texel_at((uv[0] + uv[2] + uv[4]) / 3.0f,
                                      (uv[1] + uv[3] + uv[5]) / 3.0f, width, height);
      if (t >= 0 && island[t] == id) out[f] = blurred[t];
    }
  });
}

// Step 5 for vertex values: a bilinear read at every corner (taps of the corner's island),
// then the mean over each merged vertex's corners, in face order, so the copies of a vertex
// split at a UV seam agree.
void read_back_vertices(const Mesh& mesh, const float* uvs, const UvIslands& islands, int width,
                        int height, const std::vector<std::int32_t>& island,
                        const std::vector<float>& blurred, float lo, float hi, unsigned threads,
                        std::vector<float>& out) {
  const std::size_t m = mesh.triangles.size();
  UninitializedVector<float> sample(3 * m);
  UninitializedVector<std::uint8_t> sampled(3 * m);
  parallel_for(m, kFaceGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t f = begin; f < end; ++f) {
      const std::int32_t id = islands.face_island[f];
      for (int c = 0; c < 3; ++c) {
        sampled[3 * f + c] = 0;
        const float u = uvs[6 * f + 2 * c], v = uvs[6 * f + 2 * c + 1];
        const double x = u * double(width) - 0.5, y = v * double(height) - 0.5;
        const double fx = std::floor(x), fy = std::floor(y);
        const int x0 = static_cast<int>(std::max(-2.0, std::min(fx, double(width))));
        const int y0 = static_cast<int>(std::max(-2.0, std::min(fy, double(height))));
        const double ax = x - fx, ay = y - fy;
        double sum = 0.0, weight = 0.0;
        for (int k = 0; k < 4; ++k) {
          const int tx = x0 + (k & 1), ty = y0 + (k >> 1);
          if (tx < 0 || ty < 0 || tx >= width || ty >= height) continue;
          const std::size_t t = static_cast<std::size_t>(ty) * width + tx;
          if (island[t] != id) continue;
          const double w = ((k & 1) ? ax : 1.0 - ax) * ((k >> 1) ? ay : 1.0 - ay);
          sum += w * blurred[t];
          weight += w;
        }
        if (weight > 0.0) {
          sample[3 * f + c] = static_cast<float>(sum / weight);
          sampled[3 * f + c] = 1;
          continue;
        }
        const std::int64_t t = texel_at(u, v, width, height);
        if (t >= 0 && island[t] == id) {
          sample[3 * f + c] = blurred[t];
          sampled[3 * f + c] = 1;
        }
      }
    }
  });
  // The sums in face order per merged vertex, in parallel: the sampled corners are
  // partitioned (stably, one radix pass) into blocks of consecutive keys, and each block sums
  // its own keys walking its corners in order.
  const std::uint32_t keys = islands.merged_count;
  auto key_of = [&](std::size_t corner) {
    const std::uint32_t v = mesh.triangles[corner / 3][corner % 3];
    return islands.merged.empty() ? v : islands.merged[v];
  };
  int key_bits = 1;
  while (key_bits < 32 && (std::uint64_t{1} << key_bits) < keys) ++key_bits;
  const int block_bits = std::min(key_bits, 8);
  const int shift = key_bits - block_bits;  // block of key k: k >> shift
  UninitializedVector<std::uint64_t> items(3 * m);
  parallel_for(m, kFaceGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t corner = 3 * begin; corner < 3 * end; ++corner)
      items[corner] = (std::uint64_t{key_of(corner)} << 32) | corner;
  });
  radix_sort_by_bits(items, 32 + shift, block_bits, threads);
  std::vector<double> sum(keys, 0.0);
  std::vector<std::uint32_t> count(keys, 0);
  const std::size_t blocks = std::size_t{1} << block_bits;
  parallel_for(blocks, 1, threads, [&](std::size_t b0, std::size_t b1) {
    auto first_of = [&](std::size_t block) {
      return std::lower_bound(items.begin(), items.end(), block, [&](std::uint64_t item, std::size_t b) {
        return (item >> (32 + shift)) < b;
      });
    };
    for (auto it = first_of(b0), end = first_of(b1); it != end; ++it) {
      const std::uint32_t corner = static_cast<std::uint32_t>(*it);
      if (!sampled[corner]) continue;
      const std::uint32_t k = static_cast<std::uint32_t>(*it >> 32);
      sum[k] += sample[corner];
      ++count[k];
    }
  });
  parallel_for(mesh.vertices.size(), kFaceGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t v = begin; v < end; ++v) {
      const std::uint32_t k = islands.merged.empty() ? static_cast<std::uint32_t>(v) : islands.merged[v];
      if (count[k] > 0) out[v] = std::min(hi, std::max(lo, static_cast<float>(sum[k] / count[k])));
    }
  });
}

}  // namespace

TextureSmoothing smooth_texture(const Mesh& mesh, PointKind kind, const float* values,
                                const float* uvs, const TextureOptions& options, bool keep_image,
                                const ProgressFn& progress, double progress_from,
                                double progress_to, const TextureFilterFn& filter) {
  const int width = options.width, height = options.height;
  if (width < 1 || height < 1 || width > kMaxSize || height > kMaxSize)
    throw std::invalid_argument("the texture size must be in [1, " + std::to_string(kMaxSize) +
                                "] texels, got " + std::to_string(width) + " x " +
                                std::to_string(height));
  if (!std::isfinite(options.radius))
    throw std::invalid_argument("radius must be a finite number of texels");
  if (options.margin < 0 || options.margin > kMaxSize)
    throw std::invalid_argument("margin must be in [0, " + std::to_string(kMaxSize) + "]");
  if (options.bilateral && !(options.range_sigma > 0.0 && std::isfinite(options.range_sigma)))
    throw std::invalid_argument("range_sigma must be a finite number > 0");
  Stopwatch clock;
  std::vector<std::pair<std::string, double>> timings;
  const unsigned threads = options.threads;
  const bool faces = kind == PointKind::Faces;
  const std::size_t m = mesh.triangles.size();
  const std::size_t n = faces ? m : mesh.vertices.size();
  // Corners are numbered 3 f + c in 32 bits (UV islands, read-back), one value kept free.
  if (m >= (std::size_t{1} << 32) / 3)
    throw std::invalid_argument("texture smoothing takes at most " +
                                std::to_string((std::size_t{1} << 32) / 3 - 1) + " faces, got " +
                                std::to_string(m));
  float lo, hi;
  check_inputs(values, n, uvs, m, threads, lo, hi);
  const double radius = options.radius < 0.0 ? 2.0 * std::max(width, height) / 256.0 : options.radius;
  auto report = [&](double fraction) {
    if (progress && !progress(progress_from + (progress_to - progress_from) * fraction))
      throw Cancelled();
  };

  report(0.0);
  timings.emplace_back("checks", clock.lap());
  // Vertex values are averaged over merged vertices: those need the weld whatever the islands.
  const UvIslands islands = label_uv_islands(mesh, uvs, options.weld_tolerance, !faces, threads);
  timings.emplace_back(islands.merged.empty() ? "islands" : "islands (welded)", clock.lap());
  std::vector<std::int32_t> island;
  std::vector<float> value;
  rasterise(mesh, kind, values, uvs, islands.face_island, width, height, lo, hi, threads, island,
            value);
  report(0.1);
  timings.emplace_back("rasterise", clock.lap());

  // Dilate and blur: on the CPU threads, or by `filter` on another device.
  TextureFilter f;
  f.width = width;
  f.height = height;
  f.margin = options.margin;
  f.taps = std::max(0, static_cast<int>(std::floor(radius)));
  f.lo = lo;
  f.hi = hi;
  if (f.taps >= 1) {
    const double sigma = 0.5 * radius;
    f.kernel.resize(f.taps + 1);
    for (int j = 0; j <= f.taps; ++j)
      f.kernel[j] = static_cast<float>(std::exp(-0.5 * (j / sigma) * (j / sigma)));
    f.inv_range =
        options.bilateral && hi > lo ? static_cast<float>(1.0 / (options.range_sigma * (hi - lo))) : 0.0f;
  }
  std::vector<float> blurred;
  if (filter) {
    filter(f, island, value);
    blurred.swap(value);
    report(0.85);
  } else {
    blurred = filter_cpu(f, island, value, threads, progress, progress_from, progress_to);
  }
  timings.emplace_back("filter", clock.lap());

  TextureSmoothing out;
  out.values.assign(values, values + n);
  if (faces)
    read_back_faces(uvs, islands.face_island, width, height, island, blurred, lo, hi, threads,
                    out.values);
  else
    read_back_vertices(mesh, uvs, islands, width, height, island, blurred, lo, hi, threads,
                       out.values);
  report(1.0);
  timings.emplace_back("read back", clock.lap());

  if (keep_image) {
    const std::size_t texels = blurred.size();
    out.width = width;
    out.height = height;
    out.mask.resize(texels);
    parallel_for(texels, kTexelGrain, threads, [&](std::size_t begin, std::size_t end) {
      for (std::size_t t = begin; t < end; ++t) out.mask[t] = island[t] >= 0 ? 1 : 0;
    });
    out.image = std::move(blurred);
  }
  timings.emplace_back("image", clock.lap());
  out.timings = std::move(timings);
  return out;
}

}  // namespace sdf
