// SPDX-License-Identifier: GPL-3.0-or-later
#include "post/smoothing_texture.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>

#include "post/value_range.h"
#include "smooth/sdf_smooth_texture.h"
#include "util/radix_sort.h"
#include "util/stopwatch.h"
#include "util/uninitialized_vector.h"

namespace sdf {

namespace {

constexpr int kMaxSize = 16384;

// ---- Per-face and per-texel work: loops over kernels/smooth/sdf_smooth_texture.h (kernel style).
// ----

constexpr std::size_t kFaceGrain = 1 << 12;
constexpr std::size_t kTexelGrain = 1 << 16;

// What one pass over the UVs finds, once they are known to be finite.
struct UvCheck {
  // Faces whose UVs lie wholly outside the [0, 1] square (UDIM tiles, offset layouts): no
  // texel is theirs.
  std::size_t faces_outside = 0;
  double largest_face_texels = 0.0;  // the most texels one face's UV box covers, clipped
};

// Throws naming the first UV that is not finite.
UvCheck check_uvs(const float* uvs, std::size_t m, int width, int height, unsigned threads) {
  constexpr std::size_t kGrain = kTexelGrain / 6;
  const std::size_t chunks = (m + kGrain - 1) / kGrain;
  std::vector<std::size_t> first_bad(chunks, 6 * m);
  std::vector<UvCheck> per_chunk(chunks);
  parallel_for(m, kGrain, threads, [&](std::size_t begin, std::size_t end) {
    UvCheck found;
    for (std::size_t f = begin; f < end; ++f) {
      const float* uv = uvs + 6 * f;
      float lo[2] = {uv[0], uv[1]}, hi[2] = {uv[0], uv[1]};
      for (int i = 0; i < 6; ++i) {
        if (!std::isfinite(uv[i])) {
          first_bad[begin / kGrain] = 6 * f + i;
          return;
        }
        lo[i & 1] = std::min(lo[i & 1], uv[i]);
        hi[i & 1] = std::max(hi[i & 1], uv[i]);
      }
      found.faces_outside += hi[0] < 0.0f || lo[0] > 1.0f || hi[1] < 0.0f || lo[1] > 1.0f;
      auto span = [&](int axis, int size) {
        const double clipped = std::min<double>(hi[axis], 1.0) - std::max<double>(lo[axis], 0.0);
        return std::min(double(size), std::max(0.0, clipped * size) + 1.0);
      };
      found.largest_face_texels =
          std::max(found.largest_face_texels, span(0, width) * span(1, height));
    }
    per_chunk[begin / kGrain] = found;
  });
  UvCheck all;
  for (std::size_t c = 0; c < chunks; ++c) {
    if (first_bad[c] < 6 * m)
      throw std::invalid_argument("the UV of face " + std::to_string(first_bad[c] / 6) +
                                  " corner " + std::to_string((first_bad[c] / 2) % 3) +
                                  " is not finite");
    all.faces_outside += per_chunk[c].faces_outside;
    all.largest_face_texels = std::max(all.largest_face_texels, per_chunk[c].largest_face_texels);
  }
  return all;
}

void check_size(const TextureOptions& options) {
  if (options.width < 1 || options.height < 1 || options.width > kMaxSize ||
      options.height > kMaxSize)
    throw std::invalid_argument("the texture size must be in [1, " + std::to_string(kMaxSize) +
                                "] texels, got " + std::to_string(options.width) + " x " +
                                std::to_string(options.height));
}

// Corners are numbered 3 f + c in 32 bits (UV islands, read-back), one value kept free.
void check_face_count(std::size_t m) {
  if (m >= (std::size_t{1} << 32) / 3)
    throw std::invalid_argument("texture smoothing takes at most " +
                                std::to_string((std::size_t{1} << 32) / 3 - 1) + " faces, got " +
                                std::to_string(m));
}

// Step 2 on the CPU threads, in one pass: every face offers (rank, value) to its texels
// (kernels/smooth/sdf_smooth_texture.h: sdf_face_offers_next) as a 64-bit key, high word the rank,
// low word the value's bits, and each texel keeps the largest by atomic maximum; a texel gets
// one offer per face, so the image is the one a serial loop in face order gives, whatever the
// threads (a device does the same in two passes of 32-bit maxima).
void rasterise(const Mesh& mesh, PointKind kind, const float* values, const float* uvs,
               const std::vector<std::int32_t>& face_island, int width, int height, float lo,
               float hi, unsigned threads, std::vector<std::int32_t>& island,
               std::vector<float>& value, const ProgressFn& progress, double progress_from,
               double progress_to) {
  // Every pass over the texels or faces checks for a cancel (a 4096^2 image took 0.5 s to
  // draw, too long to wait after Esc).
  const double third = (progress_to - progress_from) / 3.0;
  static_assert(sizeof(glm::uvec3) == 3 * sizeof(std::uint32_t), "uvec3 is 3 packed uint32");
  const std::uint32_t m = static_cast<std::uint32_t>(mesh.triangles.size());
  const std::size_t texels = static_cast<std::size_t>(width) * height;
  std::unique_ptr<std::atomic<std::uint64_t>[]> owner(new std::atomic<std::uint64_t>[texels]);
  parallel_for(
      texels, kTexelGrain, threads,
      [&](std::size_t begin, std::size_t end) {
        for (std::size_t t = begin; t < end; ++t) owner[t].store(0, std::memory_order_relaxed);
      },
      progress, progress_from, progress_from + third);
  auto offer = [&](std::size_t t, std::uint32_t rank, float x) {
    std::uint32_t bits;
    std::memcpy(&bits, &x, sizeof bits);
    const std::uint64_t key = (std::uint64_t{rank} << 32) | bits;
    std::uint64_t seen = owner[t].load(std::memory_order_relaxed);
    while (seen < key && !owner[t].compare_exchange_weak(seen, key, std::memory_order_relaxed)) {
    }
  };
  const std::uint32_t* corners =
      kind == PointKind::Faces ? nullptr
                               : reinterpret_cast<const std::uint32_t*>(mesh.triangles.data());
  parallel_for(
      m, kFaceGrain, threads,
      [&](std::size_t begin, std::size_t end) {
        for (std::uint32_t f = static_cast<std::uint32_t>(begin); f < end; ++f) {
          const kern::SdfFaceDraw d = kern::sdf_face_draw(f, values, corners);
          kern::SdfFaceOffers o;
          kern::sdf_face_offers_start(f, m, uvs, width, height, &o);
          while (kern::sdf_face_offers_next(&o))
            offer(o.texel, o.rank, kern::sdf_face_draw_offer(&d, &o, lo, hi));
        }
      },
      progress, progress_from + third, progress_from + 2 * third);
  island.resize(texels);
  value.resize(texels);
  parallel_for(
      texels, kTexelGrain, threads,
      [&](std::size_t begin, std::size_t end) {
        for (std::size_t t = begin; t < end; ++t) {
          const std::uint64_t key = owner[t].load(std::memory_order_relaxed);
          if (key == 0) {
            island[t] = -1;
            value[t] = 0.0f;
            continue;
          }
          const std::uint32_t rank = static_cast<std::uint32_t>(key >> 32);
          const std::uint32_t f = rank > m ? rank - m - 1 : m - rank;
          const std::uint32_t bits = static_cast<std::uint32_t>(key);
          island[t] = face_island[f];
          std::memcpy(&value[t], &bits, sizeof bits);
        }
      },
      progress, progress_from + 2 * third, progress_to);
}

// Steps 3 and 4 on the CPU threads: dilates island and value in place and returns the
// blurred image.
std::vector<float> filter_cpu(const TextureFilter& f, std::vector<std::int32_t>& island,
                              std::vector<float>& value, unsigned threads,
                              const ProgressFn& progress, double progress_from,
                              double progress_to) {
  const int width = f.width, height = f.height, taps = f.taps;
  const std::size_t texels = static_cast<std::size_t>(width) * height;
  auto at = [&](double fraction) {
    return progress_from + (progress_to - progress_from) * fraction;
  };
  // Dilate: one ring a pass, each pass reading the last.
  if (f.margin > 0) {
    std::vector<std::int32_t> island2(texels);
    std::vector<float> value2(texels);
    for (int ring = 0; ring < f.margin; ++ring) {
      const double ring_from = at(0.1 + 0.05 * ring / f.margin);
      parallel_for(
          height, 16, threads,
          [&](std::size_t begin, std::size_t end) {
            for (std::size_t y = begin; y < end; ++y)
              for (int x = 0; x < width; ++x)
                kern::sdf_dilate_texel(x, static_cast<int>(y), width, height, island.data(),
                                       value.data(), island2.data(), value2.data());
          },
          progress, ring_from, at(0.1 + 0.05 * (ring + 1) / f.margin));
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
            kern::sdf_blur_texel(x, width, 1, island.data() + o, value.data() + o, nullptr, kernel,
                                 taps, f.inv_range, &row_value[o + x], &row_weight[o + x]);
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

// Step 5 for face values (kernels/smooth/sdf_smooth_texture.h: sdf_texture_read_face); out holds
// the input, which faces with nothing to read keep.
void read_back_faces(const float* uvs, const std::vector<std::int32_t>& face_island, int width,
                     int height, const std::vector<std::int32_t>& island,
                     const std::vector<float>& blurred, float lo, float hi, unsigned threads,
                     float* out, const ProgressFn& progress, double progress_from,
                     double progress_to) {
  parallel_for(
      face_island.size(), kFaceGrain, threads,
      [&](std::size_t begin, std::size_t end) {
        for (std::uint32_t f = static_cast<std::uint32_t>(begin); f < end; ++f)
          out[f] = kern::sdf_texture_read_face(f, uvs, width, height, face_island[f], island.data(),
                                               blurred.data(), lo, hi, out[f]);
      },
      progress, progress_from, progress_to);
}

// Step 5 for vertex values: a bilinear read at every corner (taps of the corner's island),
// then each vertex the mean over its merged vertex's corners, in face order, so the copies of
// a vertex split at a UV seam agree.
void read_back_vertices(const Mesh& mesh, const float* uvs, const UvIslands& islands,
                        const CornerGroups& groups, int width, int height,
                        const std::vector<std::int32_t>& island, const std::vector<float>& blurred,
                        float lo, float hi, unsigned threads, float* out,
                        const ProgressFn& progress, double progress_from, double progress_to) {
  const std::size_t m = mesh.triangles.size();
  UninitializedVector<float> samples(3 * m);
  parallel_for(
      m, kFaceGrain, threads,
      [&](std::size_t begin, std::size_t end) {
        for (std::size_t f = begin; f < end; ++f)
          for (int c = 0; c < 3; ++c)
            samples[3 * f + c] = kern::sdf_texture_sample_corner(
                uvs[6 * f + 2 * c], uvs[6 * f + 2 * c + 1], width, height, islands.face_island[f],
                island.data(), blurred.data());
      },
      progress, progress_from, progress_to);
  parallel_for(mesh.vertices.size(), kFaceGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t v = begin; v < end; ++v) {
      const std::uint32_t k =
          islands.merged.empty() ? static_cast<std::uint32_t>(v) : islands.merged[v];
      out[v] = kern::sdf_texture_vertex_mean(groups.first[k], groups.first[k + 1],
                                             groups.corners.data(), samples.data(), lo, hi, out[v]);
    }
  });
}

void check_filter_options(const TextureOptions& options) {
  if (!std::isfinite(options.radius))
    throw std::invalid_argument("radius must be a finite number of texels");
  if (options.margin < 0 || options.margin > kMaxSize)
    throw std::invalid_argument("margin must be in [0, " + std::to_string(kMaxSize) + "]");
  if (options.bilateral && !(options.range_sigma > 0.0 && std::isfinite(options.range_sigma)))
    throw std::invalid_argument("range_sigma must be a finite number > 0");
}

// The dilation and blur for these options over values in [lo, hi]: a Gaussian of deviation
// radius / 2 over floor(radius) taps each way (radius < 0: 2 texels per 256 of the larger side).
TextureFilter make_filter(const TextureOptions& options, float lo, float hi) {
  const double radius =
      options.radius < 0.0 ? 2.0 * std::max(options.width, options.height) / 256.0 : options.radius;
  TextureFilter f;
  f.width = options.width;
  f.height = options.height;
  f.margin = options.margin;
  f.taps = std::max(0, static_cast<int>(std::floor(radius)));
  f.lo = lo;
  f.hi = hi;
  if (f.taps >= 1) {
    const double sigma = 0.5 * radius;
    f.kernel.resize(f.taps + 1);
    for (int j = 0; j <= f.taps; ++j)
      f.kernel[j] = static_cast<float>(std::exp(-0.5 * (j / sigma) * (j / sigma)));
    f.inv_range = options.bilateral && hi > lo
                      ? static_cast<float>(1.0 / (options.range_sigma * (hi - lo)))
                      : 0.0f;
  }
  return f;
}

// What the image steps share: where they read and write, and the progress span they cover.
struct TextureRun {
  const Mesh& mesh;
  PointKind kind;
  const float* values;
  const float* uvs;
  const UvIslands& islands;
  const CornerGroups* groups;  // vertex values only
  const TextureFilter& filter;
  unsigned threads;
  const ProgressFn& progress;
  double from, to;
  double at(double fraction) const { return from + (to - from) * fraction; }
};

// Draw, dilate and blur, read back, on the CPU threads: `into` per point; the island per
// texel and the blurred image stay in `island` and `blurred`.
void smooth_on_cpu(const TextureRun& r, float* into, std::vector<std::int32_t>& island,
                   std::vector<float>& blurred, Stopwatch& clock, StageTimings& timings) {
  const TextureFilter& f = r.filter;
  std::vector<float> value;
  rasterise(r.mesh, r.kind, r.values, r.uvs, r.islands.face_island, f.width, f.height, f.lo, f.hi,
            r.threads, island, value, r.progress, r.from, r.at(0.1));
  if (r.progress && !r.progress(r.at(0.1))) throw Cancelled();
  timings.emplace_back("rasterise", clock.lap());
  blurred = filter_cpu(f, island, value, r.threads, r.progress, r.from, r.to);
  timings.emplace_back("filter", clock.lap());
  if (r.kind == PointKind::Faces)
    read_back_faces(r.uvs, r.islands.face_island, f.width, f.height, island, blurred, f.lo, f.hi,
                    r.threads, into, r.progress, r.at(0.85), r.at(1.0));
  else
    read_back_vertices(r.mesh, r.uvs, r.islands, *r.groups, f.width, f.height, island, blurred,
                       f.lo, f.hi, r.threads, into, r.progress, r.at(0.85), r.at(1.0));
}

// The image kept: the blurred values and the mask of texels an island covers.
void keep_image(TextureSmoothing& out, const TextureRun& r, const std::vector<std::int32_t>& island,
                std::vector<float>& blurred) {
  const std::size_t texels = blurred.size();
  out.width = r.filter.width;
  out.height = r.filter.height;
  out.mask.resize(texels);
  parallel_for(
      texels, kTexelGrain, r.threads,
      [&](std::size_t begin, std::size_t end) {
        for (std::size_t t = begin; t < end; ++t) out.mask[t] = island[t] >= 0 ? 1 : 0;
      },
      r.progress, r.at(1.0), r.at(1.0));
  out.image = std::move(blurred);
}

// smooth_texture's work once the UVs are checked; islands and groups (vertex values): made
// already, or null.
TextureSmoothing smooth_checked(const Mesh& mesh, PointKind kind, const float* values,
                                const float* uvs, const TextureOptions& options, bool keep,
                                const ProgressFn& progress, double progress_from,
                                double progress_to, const TextureDeviceFn& device,
                                const UvIslands* given_islands, const CornerGroups* given_groups,
                                float* into, Stopwatch& clock, StageTimings& timings) {
  check_filter_options(options);
  const unsigned threads = options.threads;
  const bool faces = kind == PointKind::Faces;
  const std::size_t n = faces ? mesh.triangles.size() : mesh.vertices.size();
  const ValueRange range = value_range(values, n, threads, not_finite);
  if (range.first_bad < n)
    throw std::invalid_argument("value " + std::to_string(range.first_bad) + " is not finite");
  auto report = [&](double fraction) {
    if (progress && !progress(progress_from + (progress_to - progress_from) * fraction))
      throw Cancelled();
  };
  report(0.0);
  timings.emplace_back("checks", clock.lap());
  UvIslands found;
  if (!given_islands) {
    // Vertex values are averaged over merged vertices: those need the weld whatever the
    // islands.
    found = label_uv_islands(mesh, uvs, options.weld_tolerance, !faces, threads);
    timings.emplace_back(found.merged.empty() ? "islands" : "islands (welded)", clock.lap());
  }
  const UvIslands& islands = given_islands ? *given_islands : found;
  CornerGroups made_groups;
  if (!faces && !given_groups) {
    made_groups = group_corners(mesh, islands, threads);
    timings.emplace_back("corner groups", clock.lap());
  }
  const CornerGroups* groups = faces ? nullptr : given_groups ? given_groups : &made_groups;
  const TextureFilter f = make_filter(options, range.lo, range.hi);
  const TextureRun run{mesh, kind,    values,   uvs,           islands,    groups,
                       f,    threads, progress, progress_from, progress_to};

  TextureSmoothing out;
  // On the CPU threads the result starts as the input (points nothing reaches keep it),
  // copied on the threads; a device reads every value back itself.
  if (!into) {
    out.values.resize(n);
    into = out.values.data();
  }
  std::vector<std::int32_t> island;
  std::vector<float> blurred;
  if (device) {
    TextureJob job;
    job.mesh = &mesh;
    job.kind = kind;
    job.values = values;
    job.uvs = uvs;
    job.face_island = islands.face_island.data();
    job.islands = &islands;
    job.groups = groups;
    job.filter = f;
    job.threads = threads;
    device(job, keep, into, island, blurred, timings);
    report(0.85);
    clock.lap();
  } else {
    parallel_for(n, kTexelGrain, threads, [&](std::size_t begin, std::size_t end) {
      std::copy(values + begin, values + end, into + begin);
    });
    smooth_on_cpu(run, into, island, blurred, clock, timings);
  }
  report(1.0);
  if (!device) timings.emplace_back("read back", clock.lap());
  if (keep) keep_image(out, run, island, blurred);
  timings.emplace_back("image", clock.lap());
  out.timings = std::move(timings);
  return out;
}

}  // namespace

CornerGroups group_corners(const Mesh& mesh, const UvIslands& islands, unsigned threads) {
  const std::size_t m = mesh.triangles.size();
  const std::uint32_t keys = islands.merged.empty()
                                 ? static_cast<std::uint32_t>(mesh.vertices.size())
                                 : islands.merged_count;
  auto key_of = [&](std::size_t corner) {
    const std::uint32_t v = mesh.triangles[corner / 3][corner % 3];
    return islands.merged.empty() ? v : islands.merged[v];
  };
  // A counting sort by group, stable, in two levels so that it runs in parallel: one radix
  // pass by the group's top 8 bits into blocks, then each block on its own thread counts its
  // groups (at most 2^shift of them), places their starts, and scatters its corners in order.
  int key_bits = 1;
  while (key_bits < 32 && (std::uint64_t{1} << key_bits) < keys) ++key_bits;
  const int block_bits = std::min(key_bits, 8);
  const int shift = key_bits - block_bits;  // block of group k: k >> shift
  UninitializedVector<std::uint64_t> items(3 * m);
  parallel_for(m, kFaceGrain, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t corner = 3 * begin; corner < 3 * end; ++corner)
      items[corner] = std::uint64_t{key_of(corner)} << 32 | corner;
  });
  radix_sort_by_bits(items, 32 + shift, block_bits, threads);
  CornerGroups groups;
  groups.corners.resize(3 * m);
  groups.first.resize(std::size_t{keys} + 1);
  groups.first[keys] = static_cast<std::uint32_t>(3 * m);
  const std::size_t blocks = std::size_t{1} << block_bits;
  parallel_for(blocks, 1, threads, [&](std::size_t b0, std::size_t b1) {
    auto first_of = [&](std::size_t block) {
      return static_cast<std::size_t>(std::lower_bound(items.begin(), items.end(), block,
                                                       [&](std::uint64_t item, std::size_t b) {
                                                         return (item >> (32 + shift)) < b;
                                                       }) -
                                      items.begin());
    };
    std::vector<std::uint32_t> at;
    for (std::size_t b = b0; b < b1; ++b) {
      const std::size_t lo = first_of(b), hi = first_of(b + 1);
      const std::uint64_t k0 = std::uint64_t{b} << shift;
      const std::uint64_t k1 = std::min<std::uint64_t>(keys, (std::uint64_t{b} + 1) << shift);
      if (k0 >= k1) continue;
      at.assign(k1 - k0 + 1, 0);
      for (std::size_t j = lo; j < hi; ++j) ++at[(items[j] >> 32) - k0 + 1];
      at[0] = static_cast<std::uint32_t>(lo);
      for (std::size_t g = 1; g < at.size(); ++g) at[g] += at[g - 1];
      for (std::uint64_t k = k0; k < k1; ++k) groups.first[k] = at[k - k0];
      for (std::size_t j = lo; j < hi; ++j)
        groups.corners[at[(items[j] >> 32) - k0]++] = static_cast<std::uint32_t>(items[j]);
    }
  });
  return groups;
}

TextureSmoothing smooth_texture(const Mesh& mesh, PointKind kind, const float* values,
                                const float* uvs, const TextureOptions& options, bool keep_image,
                                const ProgressFn& progress, double progress_from,
                                double progress_to, const TextureDeviceFn& device, float* into) {
  Stopwatch clock;
  StageTimings timings;
  check_size(options);
  check_face_count(mesh.triangles.size());
  const UvCheck uv =
      check_uvs(uvs, mesh.triangles.size(), options.width, options.height, options.threads);
  const bool on_device = device && uv.largest_face_texels <= kMostTexelsPerDeviceFace;
  TextureSmoothing out = smooth_checked(mesh, kind, values, uvs, options, keep_image, progress,
                                        progress_from, progress_to, on_device ? device : nullptr,
                                        nullptr, nullptr, into, clock, timings);
  out.faces_outside = uv.faces_outside;
  out.kept_off_device = device && !on_device;
  return out;
}

TextureSmoothing smooth_texture_on_islands(const Mesh& mesh, PointKind kind, const float* values,
                                           const float* uvs, const UvIslands& islands,
                                           const CornerGroups* groups,
                                           const TextureOptions& options, bool keep_image,
                                           const ProgressFn& progress, float* into) {
  Stopwatch clock;
  StageTimings timings;
  check_texture_input(uvs, mesh.triangles.size(), options);
  if (islands.face_island.size() != mesh.triangles.size() ||
      (kind == PointKind::Vertices && (!groups || !islands.need_merged)))
    throw std::invalid_argument("the UV islands were made for other faces or for face values");
  return smooth_checked(mesh, kind, values, uvs, options, keep_image, progress, 0.0, 1.0, nullptr,
                        &islands, groups, into, clock, timings);
}

void check_texture_input(const float* uvs, std::size_t m, const TextureOptions& options) {
  check_size(options);
  check_face_count(m);
  (void)check_uvs(uvs, m, options.width, options.height, options.threads);
}

PreparedTexture prepare_texture(Mesh mesh, const float* uvs, const TextureOptions& options,
                                bool need_merged, const UvIslands* islands) {
  Stopwatch clock;
  check_size(options);
  const std::size_t m = mesh.triangles.size();
  check_face_count(m);
  const UvCheck uv = check_uvs(uvs, m, options.width, options.height, options.threads);
  PreparedTexture prepared;
  prepared.faces_outside = uv.faces_outside;
  prepared.largest_face_texels = uv.largest_face_texels;
  prepared.uvs = uvs;
  prepared.width = options.width;
  prepared.height = options.height;
  prepared.timings.emplace_back("checks", clock.lap());
  if (islands) {
    prepared.islands = *islands;
  } else {
    prepared.islands =
        label_uv_islands(mesh, uvs, options.weld_tolerance, need_merged, options.threads);
    prepared.timings.emplace_back("islands", clock.lap());
  }
  if (need_merged) {
    prepared.groups = group_corners(mesh, prepared.islands, options.threads);
    prepared.timings.emplace_back("corner groups", clock.lap());
  }
  prepared.mesh = std::move(mesh);
  return prepared;
}

TextureSmoothing smooth_texture(const PreparedTexture& prepared, PointKind kind,
                                const float* values, const TextureOptions& options, bool keep_image,
                                const ProgressFn& progress, double progress_from,
                                double progress_to, const TextureDeviceFn& device, float* into) {
  Stopwatch clock;
  StageTimings timings;
  const UvIslands& islands = prepared.islands;
  if (options.width != prepared.width || options.height != prepared.height ||
      options.weld_tolerance != islands.weld_tolerance ||
      (kind == PointKind::Vertices && !islands.need_merged))
    throw std::invalid_argument(
        "the texture was prepared for other options (size, weld tolerance, vertex values)");
  const bool on_device = device && prepared.largest_face_texels <= kMostTexelsPerDeviceFace;
  TextureSmoothing out = smooth_checked(
      prepared.mesh, kind, values, prepared.uvs, options, keep_image, progress, progress_from,
      progress_to, on_device ? device : nullptr, &islands, &prepared.groups, into, clock, timings);
  out.faces_outside = prepared.faces_outside;
  out.kept_off_device = device && !on_device;
  return out;
}

}  // namespace sdf
