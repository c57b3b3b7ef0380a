// SPDX-License-Identifier: GPL-3.0-or-later
#include "smoothing_texture.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>

#include "../kernels/sdf_smooth_texture.h"
#include "mesh_weld.h"

namespace sdf {

namespace {

constexpr int kMaxSize = 16384;

// Seconds since the previous lap (or construction).
class Stopwatch {
 public:
  double lap() {
    const auto now = std::chrono::steady_clock::now();
    const double s = std::chrono::duration<double>(now - last_).count();
    last_ = now;
    return s;
  }

 private:
  std::chrono::steady_clock::time_point last_ = std::chrono::steady_clock::now();
};

// Union-find over faces with path halving; the root of a set is its smallest face.
std::uint32_t find_root(std::vector<std::uint32_t>& parent, std::uint32_t f) {
  while (parent[f] != f) {
    parent[f] = parent[parent[f]];
    f = parent[f];
  }
  return f;
}

void unite(std::vector<std::uint32_t>& parent, std::uint32_t a, std::uint32_t b) {
  a = find_root(parent, a);
  b = find_root(parent, b);
  if (a == b) return;
  if (a < b) parent[b] = a;
  else parent[a] = b;
}

Weld weld_or_identity(const Mesh& mesh, double relative_tolerance) {
  if (relative_tolerance >= 0.0)
    return weld_vertices(mesh.vertices.data(), mesh.vertices.size(),
                         weld_tolerance(mesh, relative_tolerance));
  Weld weld;
  weld.merged.resize(mesh.vertices.size());
  for (std::size_t v = 0; v < weld.merged.size(); ++v) weld.merged[v] = static_cast<std::uint32_t>(v);
  weld.count = static_cast<std::uint32_t>(weld.merged.size());
  return weld;
}

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
  const int xmin = std::max(0, static_cast<int>(std::ceil(std::min(x[0], std::min(x[1], x[2])) - 0.5)));
  const int xmax = std::min(width - 1, static_cast<int>(std::floor(std::max(x[0], std::max(x[1], x[2])) - 0.5)));
  const int ymin = std::max(0, static_cast<int>(std::ceil(std::min(y[0], std::min(y[1], y[2])) - 0.5)));
  const int ymax = std::min(height - 1, static_cast<int>(std::floor(std::max(y[0], std::max(y[1], y[2])) - 0.5)));
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

// One ring of dilation for row y (kernels/sdf_smooth_texture.h, per texel).
void dilate_row(int y, int width, int height, const std::int32_t* island, const float* value,
                std::int32_t* island_out, float* value_out) {
  for (int x = 0; x < width; ++x)
    kern::sdf_dilate_texel(x, y, width, height, island, value, island_out, value_out);
}

// One 1-D pass of the island-masked Gaussian over a line of `count` texels `stride` apart
// (kernels/sdf_smooth_texture.h, per texel).
void blur_line(int count, std::size_t stride, const std::int32_t* island, const float* value_sum,
               const float* weight_sum, const float* taps, int radius, float inv_range,
               float* value_out, float* weight_out) {
  for (int i = 0; i < count; ++i) {
    const std::size_t t = i * stride;
    kern::sdf_blur_texel(i, count, stride, island, value_sum, weight_sum, taps, radius, inv_range,
                         value_out + t, weight_out + t);
  }
}

// Steps 3 and 4 on the CPU threads: dilates island and value in place and returns the
// blurred image.
std::vector<float> filter_cpu(const TextureFilter& f, std::vector<std::int32_t>& island,
                              std::vector<float>& value, unsigned threads,
                              const ProgressFn& progress, double progress_from,
                              double progress_to) {
  const int width = f.width, height = f.height, taps = f.taps;
  const std::size_t texels = static_cast<std::size_t>(width) * height;
  auto report = [&](double fraction) {
    if (progress && !progress(progress_from + (progress_to - progress_from) * fraction))
      throw Cancelled();
  };
  // Dilate.
  {
    std::vector<std::int32_t> island2(texels);
    std::vector<float> value2(texels);
    for (int ring = 0; ring < f.margin; ++ring) {
      parallel_for(height, 16, threads, [&](std::size_t begin, std::size_t end) {
        for (std::size_t y = begin; y < end; ++y)
          dilate_row(static_cast<int>(y), width, height, island.data(), value.data(),
                     island2.data(), value2.data());
      });
      island.swap(island2);
      value.swap(value2);
    }
  }
  report(0.15);

  // Blur: rows, then columns.
  std::vector<float> blurred = value;
  if (taps >= 1) {
    const float* kernel = f.kernel.data();
    std::vector<float> ones(texels, 1.0f), row_value(texels), row_weight(texels), col_weight(texels);
    parallel_for(
        height, 8, threads,
        [&](std::size_t begin, std::size_t end) {
          for (std::size_t y = begin; y < end; ++y) {
            const std::size_t o = y * width;
            blur_line(width, 1, island.data() + o, value.data() + o, ones.data() + o,
                      kernel, taps, f.inv_range, row_value.data() + o, row_weight.data() + o);
          }
        },
        progress, progress_from + 0.15 * (progress_to - progress_from),
        progress_from + 0.5 * (progress_to - progress_from));
    parallel_for(
        width, 8, threads,
        [&](std::size_t begin, std::size_t end) {
          for (std::size_t x = begin; x < end; ++x)
            blur_line(height, width, island.data() + x, row_value.data() + x,
                      row_weight.data() + x, kernel, taps, f.inv_range, blurred.data() + x,
                      col_weight.data() + x);
        },
        progress, progress_from + 0.5 * (progress_to - progress_from),
        progress_from + 0.85 * (progress_to - progress_from));
    for (std::size_t t = 0; t < texels; ++t)
      if (island[t] >= 0) blurred[t] = kern::sdf_blur_normalize(blurred[t], col_weight[t], f.lo, f.hi);
  }
  return blurred;
}

}  // namespace

std::vector<std::int32_t> uv_islands(const Mesh& mesh, const float* uvs, double weld_tolerance) {
  const std::size_t m = mesh.triangles.size();
  const Weld weld = weld_or_identity(mesh, weld_tolerance);
  const std::vector<glm::uvec3> tris = welded_triangles(mesh, weld);
  const Adjacency vf = faces_of_vertices(tris, weld.count);
  std::vector<std::uint32_t> parent(m);
  for (std::uint32_t f = 0; f < m; ++f) parent[f] = f;

  // Corners around each merged vertex, sorted by UV: runs of equal UV join their faces.
  struct Corner {
    float u, v;
    std::uint32_t face;
  };
  std::vector<Corner> corners;
  for (std::uint32_t v = 0; v < weld.count; ++v) {
    corners.clear();
    for (std::uint32_t i = vf.offsets[v]; i < vf.offsets[v + 1]; ++i) {
      const std::uint32_t f = vf.items[i];
      for (int c = 0; c < 3; ++c)
        if (tris[f][c] == v) {
          corners.push_back({uvs[6 * f + 2 * c] + 0.0f, uvs[6 * f + 2 * c + 1] + 0.0f, f});
          break;
        }
    }
    std::sort(corners.begin(), corners.end(), [](const Corner& a, const Corner& b) {
      return a.u < b.u || (a.u == b.u && a.v < b.v);
    });
    for (std::size_t i = 1; i < corners.size(); ++i)
      if (corners[i].u == corners[i - 1].u && corners[i].v == corners[i - 1].v)
        unite(parent, corners[i].face, corners[i - 1].face);
  }
  std::vector<std::int32_t> island(m), id_of_root(m, -1);
  std::int32_t next = 0;
  for (std::uint32_t f = 0; f < m; ++f) {
    const std::uint32_t root = find_root(parent, f);
    if (id_of_root[root] < 0) id_of_root[root] = next++;
    island[f] = id_of_root[root];
  }
  return island;
}

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
  const bool faces = kind == PointKind::Faces;
  const std::size_t m = mesh.triangles.size();
  const std::size_t n = faces ? m : mesh.vertices.size();
  float lo = std::numeric_limits<float>::infinity(), hi = -lo;
  for (std::size_t i = 0; i < n; ++i) {
    if (!std::isfinite(values[i]))
      throw std::invalid_argument("value " + std::to_string(i) + " is not finite");
    lo = std::min(lo, values[i]);
    hi = std::max(hi, values[i]);
  }
  for (std::size_t i = 0; i < 6 * m; ++i)
    if (!std::isfinite(uvs[i]))
      throw std::invalid_argument("the UV of face " + std::to_string(i / 6) + " corner " +
                                  std::to_string((i / 2) % 3) + " is not finite");
  const double radius = options.radius < 0.0 ? 2.0 * std::max(width, height) / 256.0 : options.radius;
  auto report = [&](double fraction) {
    if (progress && !progress(progress_from + (progress_to - progress_from) * fraction))
      throw Cancelled();
  };

  report(0.0);
  timings.emplace_back("checks", clock.lap());
  const std::vector<std::int32_t> face_island = uv_islands(mesh, uvs, options.weld_tolerance);
  timings.emplace_back("islands", clock.lap());
  const std::size_t texels = static_cast<std::size_t>(width) * height;
  std::vector<std::int32_t> island(texels, -1);
  std::vector<float> value(texels, 0.0f);

  // Rasterise, then give faces that covered no texel centre the texel under their centroid.
  std::vector<std::uint32_t> coverage(m);
  for (std::size_t f = 0; f < m; ++f) {
    const float* uv = uvs + 6 * f;
    const std::int32_t id = face_island[f];
    if (faces) {
      const float x = values[f];
      coverage[f] = for_each_texel(uv, width, height, [&](std::size_t t, double, double, double) {
        island[t] = id;
        value[t] = x;
      });
    } else {
      const glm::uvec3 tri = mesh.triangles[f];
      const float a = values[tri.x], b = values[tri.y], c = values[tri.z];
      const float vmin = std::min(a, std::min(b, c)), vmax = std::max(a, std::max(b, c));
      coverage[f] = for_each_texel(uv, width, height, [&](std::size_t t, double b0, double b1, double b2) {
        island[t] = id;
        value[t] = std::min(vmax, std::max(vmin, static_cast<float>(b0 * a + b1 * b + b2 * c)));
      });
    }
  }
  for (std::size_t f = 0; f < m; ++f) {
    if (coverage[f] > 0) continue;
    const float* uv = uvs + 6 * f;
    const std::int64_t t = texel_at((uv[0] + uv[2] + uv[4]) / 3.0f, (uv[1] + uv[3] + uv[5]) / 3.0f,
                                    width, height);
    if (t < 0 || island[t] >= 0) continue;
    island[t] = face_island[f];
    if (faces) {
      value[t] = values[f];
    } else {
      const glm::uvec3 tri = mesh.triangles[f];
      value[t] = std::min(hi, std::max(lo, (values[tri.x] + values[tri.y] + values[tri.z]) / 3.0f));
    }
  }
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
    blurred = filter_cpu(f, island, value, options.threads, progress, progress_from, progress_to);
  }
  timings.emplace_back("filter", clock.lap());

  // Read back.
  TextureSmoothing out;
  out.values.assign(values, values + n);
  if (faces) {
    parallel_for(m, 256, options.threads, [&](std::size_t begin, std::size_t end) {
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
          out.values[f] = std::min(hi, std::max(lo, static_cast<float>(sum / count)));
          continue;
        }
        const float* uv = uvs + 6 * f;
        const std::int64_t t = texel_at((uv[0] + uv[2] + uv[4]) / 3.0f,
                                        (uv[1] + uv[3] + uv[5]) / 3.0f, width, height);
        if (t >= 0 && island[t] == id) out.values[f] = blurred[t];
      }
    });
  } else {
    // Bilinear reads at every corner, then the mean over each merged vertex's corners, so the
    // copies of a vertex split at a UV seam agree.
    std::vector<float> sample(3 * m);
    std::vector<std::uint8_t> sampled(3 * m, 0);
    parallel_for(m, 256, options.threads, [&](std::size_t begin, std::size_t end) {
      for (std::size_t f = begin; f < end; ++f) {
        const std::int32_t id = face_island[f];
        for (int c = 0; c < 3; ++c) {
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
    const Weld weld = weld_or_identity(mesh, options.weld_tolerance);
    std::vector<double> sum(weld.count, 0.0);
    std::vector<std::uint32_t> count(weld.count, 0);
    for (std::size_t f = 0; f < m; ++f)
      for (int c = 0; c < 3; ++c) {
        if (!sampled[3 * f + c]) continue;
        const std::uint32_t w = weld.merged[mesh.triangles[f][c]];
        sum[w] += sample[3 * f + c];
        ++count[w];
      }
    for (std::size_t v = 0; v < n; ++v) {
      const std::uint32_t w = weld.merged[v];
      if (count[w] > 0) out.values[v] = std::min(hi, std::max(lo, static_cast<float>(sum[w] / count[w])));
    }
  }
  report(1.0);
  timings.emplace_back("read back", clock.lap());

  if (keep_image) {
    out.width = width;
    out.height = height;
    out.mask.resize(texels);
    for (std::size_t t = 0; t < texels; ++t) out.mask[t] = island[t] >= 0 ? 1 : 0;
    out.image = std::move(blurred);
  }
  timings.emplace_back("image", clock.lap());
  out.timings = std::move(timings);
  return out;
}

}  // namespace sdf
