// SPDX-License-Identifier: GPL-3.0-or-later
#include "fill.h"

#include <algorithm>
#include <vector>

namespace sdf {

namespace {

// Compressed lists: the items of key k are items[offsets[k] .. offsets[k + 1]).
struct Csr {
  std::vector<std::uint32_t> offsets, items;
};

Csr faces_of_vertices(const Mesh& mesh) {
  Csr csr;
  csr.offsets.assign(mesh.vertices.size() + 1, 0);
  for (const glm::uvec3& t : mesh.triangles)
    for (int k = 0; k < 3; ++k) ++csr.offsets[t[k] + 1];
  for (std::size_t v = 0; v < mesh.vertices.size(); ++v) csr.offsets[v + 1] += csr.offsets[v];
  csr.items.resize(csr.offsets.back());
  std::vector<std::uint32_t> cursor(csr.offsets.begin(), csr.offsets.end() - 1);
  for (std::uint32_t f = 0; f < mesh.triangles.size(); ++f)
    for (int k = 0; k < 3; ++k) csr.items[cursor[mesh.triangles[f][k]]++] = f;
  return csr;
}

// Calls visit(neighbour) for each neighbour of point p (a point may be visited twice).
template <class Visit>
void for_each_neighbour(const Mesh& mesh, PointKind kind, const Csr& vf, std::uint32_t p,
                        Visit&& visit) {
  if (kind == PointKind::Faces) {
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t v = mesh.triangles[p][k];
      for (std::uint32_t i = vf.offsets[v]; i < vf.offsets[v + 1]; ++i)
        if (vf.items[i] != p) visit(vf.items[i]);
    }
  } else {
    for (std::uint32_t i = vf.offsets[p]; i < vf.offsets[p + 1]; ++i) {
      const glm::uvec3 t = mesh.triangles[vf.items[i]];
      for (int k = 0; k < 3; ++k)
        if (t[k] != p) visit(t[k]);
    }
  }
}

}  // namespace

FillResult fill_missing(const Mesh& mesh, PointKind kind, float* raw,
                        const std::int32_t* valid_rays) {
  const std::size_t n = kind == PointKind::Faces ? mesh.triangles.size() : mesh.vertices.size();
  std::vector<char> known(n);
  std::vector<float> values;
  for (std::size_t i = 0; i < n; ++i) {
    known[i] = valid_rays[i] > 0;
    if (known[i]) values.push_back(raw[i]);
  }
  if (values.size() == n) return FillResult::NothingToFill;
  if (values.empty()) {
    std::fill(raw, raw + n, 0.0f);
    return FillResult::NoValueAnywhere;
  }

  const Csr vf = faces_of_vertices(mesh);
  std::vector<std::uint32_t> layer;
  std::vector<char> queued(n, 0);
  for (std::uint32_t p = 0; p < n; ++p) {
    if (known[p]) continue;
    bool next_to_value = false;
    for_each_neighbour(mesh, kind, vf, p, [&](std::uint32_t q) { next_to_value |= known[q] != 0; });
    if (next_to_value) {
      layer.push_back(p);
      queued[p] = 1;
    }
  }
  std::vector<float> layer_values;
  while (!layer.empty()) {
    // Values of a layer come from earlier layers only, so the order within it does not matter.
    layer_values.assign(layer.size(), 0.0f);
    for (std::size_t i = 0; i < layer.size(); ++i) {
      double sum = 0.0;
      int count = 0;
      for_each_neighbour(mesh, kind, vf, layer[i], [&](std::uint32_t q) {
        if (known[q]) {
          sum += raw[q];
          ++count;
        }
      });
      layer_values[i] = static_cast<float>(sum / count);
    }
    std::vector<std::uint32_t> next;
    for (std::size_t i = 0; i < layer.size(); ++i) {
      raw[layer[i]] = layer_values[i];
      known[layer[i]] = 1;
    }
    for (std::uint32_t p : layer) {
      for_each_neighbour(mesh, kind, vf, p, [&](std::uint32_t q) {
        if (!known[q] && !queued[q]) {
          queued[q] = 1;
          next.push_back(q);
        }
      });
    }
    layer.swap(next);
  }

  std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
  const float median = values[values.size() / 2];
  for (std::size_t p = 0; p < n; ++p)
    if (!known[p]) raw[p] = median;
  return FillResult::Filled;
}

}  // namespace sdf
