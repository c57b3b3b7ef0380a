// SPDX-License-Identifier: GPL-3.0-or-later
#include "post/fill.h"

#include <algorithm>
#include <vector>

namespace sdf {

namespace {

// Compressed lists: the items of key k are items[offsets[k] .. offsets[k + 1]).
struct Csr {
  std::vector<std::uint32_t> offsets, items;
};

// The faces around each vertex of `wanted` (in face order, a face twice where it uses the
// vertex twice), for those vertices only: list_of[v] is v's list, kNoList for the others.
// Only the points being filled ask for their lists, usually a few percent of the mesh, so
// this is two sequential passes over the faces with a lookup in a byte per vertex, where
// lists for every vertex cost scattered counters over the whole mesh.
constexpr std::uint32_t kNoList = 0xffffffffu;

struct FacesAround {
  std::vector<std::uint32_t> list_of;
  Csr lists;
};

FacesAround faces_around(const Mesh& mesh, const std::vector<char>& wanted) {
  FacesAround out;
  out.list_of.assign(mesh.vertices.size(), kNoList);
  std::uint32_t count = 0;
  for (std::size_t v = 0; v < wanted.size(); ++v)
    if (wanted[v]) out.list_of[v] = count++;
  Csr& csr = out.lists;
  csr.offsets.assign(count + 1, 0);
  for (const glm::uvec3& t : mesh.triangles)
    for (int k = 0; k < 3; ++k)
      if (wanted[t[k]]) ++csr.offsets[out.list_of[t[k]] + 1];
  for (std::size_t i = 0; i < count; ++i) csr.offsets[i + 1] += csr.offsets[i];
  csr.items.resize(csr.offsets.back());
  std::vector<std::uint32_t> cursor(csr.offsets.begin(), csr.offsets.end() - 1);
  for (std::uint32_t f = 0; f < mesh.triangles.size(); ++f)
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t v = mesh.triangles[f][k];
      if (wanted[v]) csr.items[cursor[out.list_of[v]]++] = f;
    }
  return out;
}

// Calls visit(neighbour) for each neighbour of point p (a point may be visited twice).
// Only for points still without a value (whose lists faces_around built).
template <class Visit>
void for_each_neighbour(const Mesh& mesh, PointKind kind, const FacesAround& around,
                        std::uint32_t p, Visit&& visit) {
  const Csr& vf = around.lists;
  if (kind == PointKind::Faces) {
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t v = around.list_of[mesh.triangles[p][k]];
      for (std::uint32_t i = vf.offsets[v]; i < vf.offsets[v + 1]; ++i)
        if (vf.items[i] != p) visit(vf.items[i]);
    }
  } else {
    const std::uint32_t v = around.list_of[p];
    for (std::uint32_t i = vf.offsets[v]; i < vf.offsets[v + 1]; ++i) {
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
  std::size_t with_value = 0;
  for (std::size_t i = 0; i < n; ++i) {
    known[i] = valid_rays[i] > 0;
    with_value += known[i];
  }
  if (with_value == n) return FillResult::NothingToFill;
  if (with_value == 0) {
    std::fill(raw, raw + n, 0.0f);
    return FillResult::NoValueAnywhere;
  }

  // The vertices whose face lists the filling reads: those of the points without a value.
  std::vector<char> wanted(mesh.vertices.size(), 0);
  for (std::size_t p = 0; p < n; ++p) {
    if (known[p]) continue;
    if (kind == PointKind::Vertices) {
      wanted[p] = 1;
    } else {
      for (int k = 0; k < 3; ++k) wanted[mesh.triangles[p][k]] = 1;
    }
  }
  const FacesAround vf = faces_around(mesh, wanted);
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

  // Parts of the mesh with no value anywhere take the median of the values cast. Found only
  // when there are such parts: the selection over a million values costs more than the rest
  // of the filling.
  if (std::find(known.begin(), known.end(), 0) == known.end()) return FillResult::Filled;
  std::vector<float> values;
  values.reserve(with_value);
  for (std::size_t p = 0; p < n; ++p)
    if (valid_rays[p] > 0) values.push_back(raw[p]);
  std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
  const float median = values[values.size() / 2];
  for (std::size_t p = 0; p < n; ++p)
    if (!known[p]) raw[p] = median;
  return FillResult::Filled;
}

}  // namespace sdf
