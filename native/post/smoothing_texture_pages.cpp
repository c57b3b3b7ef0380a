// SPDX-License-Identifier: GPL-3.0-or-later
#include "post/smoothing_texture_pages.h"

#include <algorithm>
#include <string>
#include <utility>

namespace sdf {

namespace {

constexpr std::size_t kGrain = 1 << 14;

// Lays page image `from` over tile image `to` where `from` holds a value.
void lay_over(TextureTile& to, TextureSmoothing& from) {
  if (to.image.empty()) {
    to.image = std::move(from.image);
    to.mask = std::move(from.mask);
    to.width = from.width;
    to.height = from.height;
    return;
  }
  for (std::size_t t = 0; t < to.image.size(); ++t)
    if (from.mask[t]) {
      to.image[t] = from.image[t];
      to.mask[t] = 1;
    }
}

std::string page_name(const UvPage& page) {
  return "tile " + std::to_string(page.tile) +
         (page.layer ? " layer " + std::to_string(page.layer) : std::string()) + ": ";
}

void add_counts(const UvLayout& layout, TextureSmoothing& out) {
  out.faces_outside = layout.faces_outside;
  out.faces_spanning = layout.faces_spanning;
  out.faces_overlapping = layout.faces_overlapping;
  out.overlaps_unparted = layout.overlaps_unparted;
  out.pages = layout.pages.size();
}

}  // namespace

TextureSmoothing smooth_texture_pages(const Mesh& mesh, PointKind kind, const float* values,
                                      const float* uvs, const UvLayout& layout, bool keep_image,
                                      unsigned threads, const ProgressFn& progress,
                                      const TexturePageFn& run_page, float* into) {
  TextureSmoothing out;
  if (layout.single_square()) {
    TextureSmoothing done = run_page(uvs, keep_image, progress, into);
    out.timings = std::move(done.timings);
    out.kept_off_device = done.kept_off_device;
    if (keep_image) {
      out.tiles.emplace_back();
      out.tiles.back().tile = kFirstTile;
      lay_over(out.tiles.back(), done);
    }
    add_counts(layout, out);
    return out;
  }
  const bool faces = kind == PointKind::Faces;
  const std::size_t m = mesh.triangles.size();
  const std::size_t n = faces ? m : mesh.vertices.size();
  std::copy(values, values + n, into);
  std::vector<float> page_out(n);
  std::vector<double> sum(faces ? 0 : n, 0.0);
  std::vector<std::uint32_t> count(faces ? 0 : n, 0);
  const std::size_t pages = layout.pages.size();
  for (std::size_t p = 0; p < pages; ++p) {
    const UvPage& page = layout.pages[p];
    const std::vector<float> page_uv = page_uvs(layout, uvs, static_cast<int>(p), threads);
    ProgressFn part;
    if (progress) part = [&](double x) { return progress((static_cast<double>(p) + x) / pages); };
    TextureSmoothing done = run_page(page_uv.data(), keep_image, part, page_out.data());
    for (auto& [name, seconds] : done.timings)
      out.timings.emplace_back(page_name(page) + name, seconds);
    out.kept_off_device |= done.kept_off_device;
    if (faces) {
      parallel_for(m, kGrain, threads, [&](std::size_t begin, std::size_t end) {
        for (std::size_t f = begin; f < end; ++f)
          if (layout.face_page[f] == static_cast<std::int32_t>(p)) into[f] = page_out[f];
      });
    } else {
      for (std::size_t f = 0; f < m; ++f)
        if (layout.face_page[f] == static_cast<std::int32_t>(p))
          for (int c = 0; c < 3; ++c) {
            sum[mesh.triangles[f][c]] += page_out[mesh.triangles[f][c]];
            ++count[mesh.triangles[f][c]];
          }
    }
    if (keep_image) {
      if (out.tiles.empty() || out.tiles.back().tile != page.tile) {
        out.tiles.emplace_back();
        out.tiles.back().tile = page.tile;
      }
      lay_over(out.tiles.back(), done);
    }
  }
  if (!faces)
    for (std::size_t v = 0; v < n; ++v)
      if (count[v]) into[v] = static_cast<float>(sum[v] / count[v]);
  add_counts(layout, out);
  return out;
}

}  // namespace sdf
