// SPDX-License-Identifier: GPL-3.0-or-later
// Disjoint sets that threads join concurrently (orientation's parts, texture smoothing's UV
// islands). A root is linked under a smaller root by a compare-and-swap and finds halve paths;
// parents only ever move toward smaller items, so no cycle can form and a parent read late is
// still an ancestor. Started from singletons, a set's root is its smallest item whatever the
// order of the unions, so results do not depend on the thread count.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <utility>

#include "util/parallel.h"
#include "util/prefetch.h"
#include "util/uninitialized_vector.h"

namespace sdf {

class ConcurrentUnionFind {
 public:
  // Every item of [0, n) its own set.
  ConcurrentUnionFind(std::size_t n, unsigned threads) : parent_(n) {
    parallel_for(n, kGrain, threads, [&](std::size_t begin, std::size_t end) {
      for (std::size_t i = begin; i < end; ++i)
        parent_[i].store(static_cast<std::uint32_t>(i), std::memory_order_relaxed);
    });
  }
  // Starts from `parent`: each item's parent must be a root (its own parent). Roots are then
  // the smallest items of their sets only if each given parent is no larger than its item.
  ConcurrentUnionFind(const UninitializedVector<std::uint32_t>& parent, unsigned threads)
      : parent_(parent.size()) {
    parallel_for(parent.size(), kGrain, threads, [&](std::size_t begin, std::size_t end) {
      for (std::size_t i = begin; i < end; ++i)
        parent_[i].store(parent[i], std::memory_order_relaxed);
    });
  }
  void prefetch_parent(std::uint32_t x) const { prefetch(&parent_[x]); }
  std::uint32_t find(std::uint32_t x) const {
    for (;;) {
      const std::uint32_t p = parent_[x].load(std::memory_order_relaxed);
      if (p == x) return x;
      // Path halving. A plain store: x is no root, so no link writes parent_[x], and a
      // grandparent stays an ancestor even when another thread's halving lands later.
      const std::uint32_t grand = parent_[p].load(std::memory_order_relaxed);
      if (grand != p) parent_[x].store(grand, std::memory_order_relaxed);
      x = grand;
    }
  }
  void unite(std::uint32_t a, std::uint32_t b) {
    for (;;) {
      a = find(a);
      b = find(b);
      if (a == b) return;
      if (a < b) std::swap(a, b);
      std::uint32_t expected = a;  // a is still a root: hang it under b
      if (parent_[a].compare_exchange_weak(expected, b, std::memory_order_acq_rel)) return;
    }
  }

 private:
  static constexpr std::size_t kGrain = 1 << 14;
  // mutable: a find halves paths, which changes no set.
  mutable UninitializedVector<std::atomic<std::uint32_t>> parent_;
};

}  // namespace sdf
