// SPDX-License-Identifier: GPL-3.0-or-later
// Disjoint sets that threads join concurrently, each item carrying one bit relative to its
// set's root (orientation's patches: whether a face winds opposite to the patch's first face).
// Built like ConcurrentUnionFind (concurrent_union_find.h): roots are linked under smaller
// roots by a compare-and-swap and finds halve paths, so a set's root is its smallest item
// whatever the order of the unions. Parent and bit share one 64-bit word, so every word read
// is a true statement, "my bit differs from this ancestor's by this much", that no later
// union can make false: a halving that lands late still stores a true one.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <utility>

#include "util/parallel.h"
#include "util/prefetch.h"
#include "util/uninitialized_vector.h"

namespace sdf {

class ConcurrentParityUnionFind {
 public:
  struct Found {
    std::uint32_t root;
    std::uint32_t parity;  // the item's bit relative to the root's (0 or 1)
  };

  // Every item of [0, n) its own set.
  ConcurrentParityUnionFind(std::size_t n, unsigned threads) : word_(n) {
    parallel_for(n, kGrain, threads, [&](std::size_t begin, std::size_t end) {
      for (std::size_t i = begin; i < end; ++i)
        word_[i].store(pack(static_cast<std::uint32_t>(i), 0), std::memory_order_relaxed);
    });
  }

  void prefetch_word(std::uint32_t x) const { prefetch(&word_[x]); }

  Found find(std::uint32_t x) const {
    std::uint32_t parity = 0;
    for (;;) {
      const std::uint64_t w = word_[x].load(std::memory_order_relaxed);
      const std::uint32_t p = parent(w);
      if (p == x) return {x, parity};
      const std::uint64_t pw = word_[p].load(std::memory_order_relaxed);
      const std::uint32_t grand = parent(pw);
      if (grand == p) return {p, parity ^ bit(w)};  // p is the root: nothing to halve
      // Path halving; a plain store: x is no root, so no link writes its word.
      const std::uint32_t to_grand = bit(w) ^ bit(pw);
      word_[x].store(pack(grand, to_grand), std::memory_order_relaxed);
      parity ^= to_grand;
      x = grand;
    }
  }

  // Joins the sets of a and b so that their bits differ by `differ`. Returns false when they
  // already share a set whose bits say otherwise (an odd cycle: no assignment satisfies all).
  bool unite(std::uint32_t a, std::uint32_t b, std::uint32_t differ) {
    for (;;) {
      Found fa = find(a), fb = find(b);
      if (fa.root == fb.root) return (fa.parity ^ fb.parity) == differ;
      if (fa.root < fb.root) std::swap(fa, fb);
      // fa.root is still a root: hang it under fb.root with the bit that makes a and b differ
      // by `differ`.
      std::uint64_t expected = pack(fa.root, 0);
      const std::uint64_t link = pack(fb.root, fa.parity ^ fb.parity ^ differ);
      if (word_[fa.root].compare_exchange_weak(expected, link, std::memory_order_acq_rel))
        return true;
    }
  }

 private:
  static constexpr std::size_t kGrain = 1 << 14;
  static std::uint64_t pack(std::uint32_t parent, std::uint32_t bit) {
    return std::uint64_t{parent} | std::uint64_t{bit} << 32;
  }
  static std::uint32_t parent(std::uint64_t w) { return static_cast<std::uint32_t>(w); }
  static std::uint32_t bit(std::uint64_t w) { return static_cast<std::uint32_t>(w >> 32); }

  // mutable: a find halves paths, which changes no set and no item's bit.
  mutable UninitializedVector<std::atomic<std::uint64_t>> word_;
};

}  // namespace sdf
