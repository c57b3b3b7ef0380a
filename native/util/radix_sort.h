// SPDX-License-Identifier: GPL-3.0-or-later
// A stable, parallel LSD radix sort for the host preparation stages (Morton order), where
// std::sort of a million keys took longer than the rest of the stage.
#pragma once

#include <cstdint>
#include <vector>

#include "util/uninitialized_vector.h"

namespace sdf {

// Sorts items by bits [low_bit, low_bit + key_bits) of each item, stably: items with equal
// keys keep their order. Items packed as (key << 32) | index, in index order, thus come out
// exactly as std::sort of (key, index) pairs would put them, whatever the thread count.
void radix_sort_by_bits(UninitializedVector<std::uint64_t>& items, int low_bit, int key_bits,
                        unsigned threads);

}  // namespace sdf
