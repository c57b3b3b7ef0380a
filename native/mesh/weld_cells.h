// SPDX-License-Identifier: GPL-3.0-or-later
// The hash grid of the vertex weld (mesh_weld.cpp): integer cell keys, their hash, an
// open-addressing table from a cell to the first kept vertex in it, and exact positions as
// keys. Shared with the serial weld the tests keep as the parallel one's reference.
#pragma once

#include <cstdint>
#include <cstring>
#include <limits>
#include <vector>

namespace sdf::weld_cells {

struct CellKey {
  std::int64_t x, y, z;
  bool operator==(const CellKey& o) const { return x == o.x && y == o.y && z == o.z; }
};

inline std::uint64_t hash_key(const CellKey& k) {
  // Large odd multipliers spread neighbouring cells over the table (Teschner et al. 2003 use
  // primes the same way); the final mix folds the high bits down.
  std::uint64_t h = static_cast<std::uint64_t>(k.x) * 0x9E3779B97F4A7C15ull ^
                    static_cast<std::uint64_t>(k.y) * 0xC2B2AE3D27D4EB4Full ^
                    static_cast<std::uint64_t>(k.z) * 0x165667B19E3779F9ull;
  return h ^ (h >> 29);
}

// Open addressing: cell -> the first kept vertex in it (more follow through `next`).
class CellTable {
 public:
  explicit CellTable(std::size_t items) {
    std::size_t capacity = 16;
    while (capacity < 2 * items) capacity *= 2;
    keys_.resize(capacity);
    heads_.assign(capacity, kEmpty);
    mask_ = capacity - 1;
  }
  // Head of the cell's list, or kEmpty.
  std::uint32_t find(const CellKey& key) const {
    for (std::size_t i = hash_key(key) & mask_;; i = (i + 1) & mask_) {
      if (heads_[i] == kEmpty) return kEmpty;
      if (keys_[i] == key) return heads_[i];
    }
  }
  // Slot of the cell, created empty if missing.
  std::uint32_t& slot(const CellKey& key) {
    for (std::size_t i = hash_key(key) & mask_;; i = (i + 1) & mask_) {
      if (heads_[i] == kEmpty) {
        keys_[i] = key;
        return heads_[i];
      }
      if (keys_[i] == key) return heads_[i];
    }
  }
  static constexpr std::uint32_t kEmpty = std::numeric_limits<std::uint32_t>::max();

 private:
  std::vector<CellKey> keys_;
  std::vector<std::uint32_t> heads_;
  std::size_t mask_ = 0;
};

inline std::int64_t float_bits(float f) {
  if (f == 0.0f) f = 0.0f;  // -0 and +0 are the same position
  std::int32_t bits;
  std::memcpy(&bits, &f, sizeof bits);
  return bits;
}

}  // namespace sdf::weld_cells
