// SPDX-License-Identifier: GPL-3.0-or-later
#include "pipeline/twins_step.h"

#include <algorithm>

namespace sdf {

TwinsCut::TwinsCut(const MeshArrays& mesh, const ReversedTwins& twins, const float* uvs)
    : given_(mesh), twins_(twins) {
  const std::size_t m = mesh.triangle_count, n = mesh.vertex_count;
  kept_.assign(m, 1);
  for (std::uint32_t f : twins.dropped) kept_[f] = 0;
  std::vector<std::uint8_t> used(n, 0);
  lonely_.assign(n, 0);
  for (std::size_t f = 0; f < m; ++f)
    for (int c = 0; c < 3; ++c) (kept_[f] ? used : lonely_)[mesh.triangles[3 * f + c]] = 1;
  bool any_lonely = false;
  for (std::size_t i = 0; i < n; ++i) {
    lonely_[i] = lonely_[i] && !used[i];
    any_lonely = any_lonely || lonely_[i];
  }
  // The kept vertices renumbered in order (the identity where none is left out).
  std::vector<std::int64_t> number(n);
  std::int64_t next = 0;
  for (std::size_t i = 0; i < n; ++i) number[i] = lonely_[i] ? -1 : next++;
  if (any_lonely) {
    vertices_.reserve(3 * static_cast<std::size_t>(next));
    for (std::size_t i = 0; i < n; ++i)
      if (!lonely_[i])
        vertices_.insert(vertices_.end(), mesh.vertices + 3 * i, mesh.vertices + 3 * i + 3);
  }
  triangles_.reserve(3 * (m - twins.dropped.size()));
  for (std::size_t f = 0; f < m; ++f) {
    if (!kept_[f]) continue;
    for (int c = 0; c < 3; ++c) triangles_.push_back(number[mesh.triangles[3 * f + c]]);
    if (uvs) uvs_.insert(uvs_.end(), uvs + 6 * f, uvs + 6 * f + 6);
  }
}

MeshArrays TwinsCut::mesh() const {
  if (vertices_.empty())
    return {given_.vertices, given_.vertex_count, triangles_.data(), triangles_.size() / 3};
  return {vertices_.data(), vertices_.size() / 3, triangles_.data(), triangles_.size() / 3};
}

template <class T>
std::vector<T> TwinsCut::whole(const std::vector<T>& part, bool faces) const {
  const std::vector<std::uint8_t>& skipped = faces ? kept_ : lonely_;
  std::vector<T> out(skipped.size());
  std::size_t next = 0;
  for (std::size_t i = 0; i < out.size(); ++i)
    if (faces ? skipped[i] != 0 : skipped[i] == 0) out[i] = part[next++];
  const std::int64_t* t = given_.triangles;
  for (std::size_t i = 0; i < twins_.dropped.size(); ++i) {
    const std::size_t own = twins_.dropped[i], theirs = twins_.twin[i];
    if (faces) {
      out[own] = out[theirs];
      continue;
    }
    // Corner k of the dropped face lies at the twin's corner (corner - k) mod 3.
    for (int k = 0; k < 3; ++k) {
      const std::int64_t vertex = t[3 * own + k];
      if (lonely_[vertex]) out[vertex] = out[t[3 * theirs + (twins_.corner[i] + 3 - k) % 3]];
    }
  }
  return out;
}

template std::vector<float> TwinsCut::whole(const std::vector<float>&, bool) const;
template std::vector<std::int32_t> TwinsCut::whole(const std::vector<std::int32_t>&, bool) const;

std::vector<std::uint8_t> TwinsCut::whole_faces_or_zero(
    const std::vector<std::uint8_t>& part) const {
  std::vector<std::uint8_t> out(kept_.size(), 0);
  std::size_t next = 0;
  for (std::size_t f = 0; f < out.size(); ++f)
    if (kept_[f]) out[f] = part[next++];
  return out;
}

}  // namespace sdf
