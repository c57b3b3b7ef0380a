// SPDX-License-Identifier: GPL-3.0-or-later
// The serial weld that native/mesh/mesh_weld.cpp replaced (greedy in index order over a hash grid),
// kept as the reference its parallel version must match exactly (the hash grid it shares:
// weld_cells.h).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

#include "mesh/mesh_weld.h"
#include "mesh/weld_cells.h"

namespace sdf::test_reference {

using weld_cells::CellKey;
using weld_cells::CellTable;
using weld_cells::float_bits;

inline Weld reference_weld_vertices(const glm::vec3* positions, std::size_t count,
                                    float tolerance) {
  Weld weld;
  weld.merged.resize(count);
  if (count == 0) return weld;

  // Cells at least twice the tolerance wide, so the ball of radius `tolerance` around a point
  // meets at most 2 cells per axis; up to 64 times wider while that keeps about one vertex per
  // cell on a surface (side extent / sqrt(count)): then most balls lie in one cell and a query
  // looks up one cell, not 8. Coordinates too large for the grid fall back to exact merging
  // (a tolerance below float resolution merges only equal positions anyway).
  bool exact = !(tolerance > 0.0f);
  double cell = 2.0 * static_cast<double>(tolerance);
  if (!exact) {
    glm::vec3 lo(std::numeric_limits<float>::infinity()), hi(-lo);
    for (std::size_t i = 0; i < count; ++i) {
      lo = glm::min(lo, positions[i]);
      hi = glm::max(hi, positions[i]);
    }
    const glm::vec3 size = hi - lo;
    const double extent = std::max(size.x, std::max(size.y, size.z));
    cell = std::max(cell, std::min(64.0 * tolerance, extent / std::sqrt(double(count))));
    const double largest = std::max(glm::length(lo), glm::length(hi));
    exact = !(largest / cell < 1e15) || !std::isfinite(cell);
  }
  const float tolerance2 = tolerance * tolerance;
  // The ball's cell range per axis, from p - reach to p + reach: a hair wider than the
  // tolerance, so that rounding in the division cannot drop a cell holding a point at
  // exactly the tolerance.
  const double reach = static_cast<double>(tolerance) * (1.0 + 1e-6);

  CellTable table(count);
  std::vector<std::uint32_t> next;  // per kept vertex: the next kept vertex in its cell
  std::vector<std::uint32_t> kept;  // merged id -> input vertex
  for (std::size_t i = 0; i < count; ++i) {
    const glm::vec3 p = positions[i];
    std::uint32_t found = CellTable::kEmpty;
    CellKey home;
    if (exact) {
      home = {float_bits(p.x), float_bits(p.y), float_bits(p.z)};
      found = table.find(home);  // every position in a cell is equal to p
    } else {
      std::int64_t k[3], first[3], last[3];
      for (int a = 0; a < 3; ++a) {
        k[a] = static_cast<std::int64_t>(std::floor(p[a] / cell));
        first[a] = static_cast<std::int64_t>(std::floor((p[a] - reach) / cell));
        last[a] = static_cast<std::int64_t>(std::floor((p[a] + reach) / cell));
      }
      home = {k[0], k[1], k[2]};
      for (std::int64_t x = first[0]; x <= last[0]; ++x)
        for (std::int64_t y = first[1]; y <= last[1]; ++y)
          for (std::int64_t z = first[2]; z <= last[2]; ++z)
            for (std::uint32_t m = table.find({x, y, z}); m != CellTable::kEmpty; m = next[m]) {
              const glm::vec3 d = positions[kept[m]] - p;
              // The lowest merged id wins, whatever order the cells were searched in.
              if (glm::dot(d, d) <= tolerance2 && m < found) found = m;
            }
    }
    if (found != CellTable::kEmpty) {
      weld.merged[i] = found;
      continue;
    }
    const std::uint32_t id = static_cast<std::uint32_t>(kept.size());
    kept.push_back(static_cast<std::uint32_t>(i));
    std::uint32_t& head = table.slot(home);
    next.push_back(head);
    head = id;
    weld.merged[i] = id;
  }
  weld.count = static_cast<std::uint32_t>(kept.size());
  return weld;
}

}  // namespace sdf::test_reference
