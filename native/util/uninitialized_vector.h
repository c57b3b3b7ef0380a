// SPDX-License-Identifier: GPL-3.0-or-later
// std::vector whose resize() leaves trivially constructible elements uninitialised. The host
// stages fill large arrays (tens of MiB for a million faces) in parallel loops right after
// sizing them; a plain vector would first zero them on one thread, a pass as slow as the
// work itself, and fault every page in on that thread.
// Large arrays are also asked to live in transparent huge pages (Linux, where the system
// allows it on request, as Debian and Ubuntu do by default): a fresh array is faulted in 2 MiB
// at a time instead of 4 KiB, and the page faults of a million-face run's arrays (hundreds of
// MiB) were a tenth of its host time.
#pragma once

#include <cstddef>
#include <cstdlib>
#include <memory>
#include <new>
#include <type_traits>
#include <utility>
#include <vector>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace sdf {

namespace huge_pages {

constexpr std::size_t kPage = std::size_t(2) << 20;
// Arrays from this size on are placed on huge page boundaries (rounding up wastes at most a
// page in 4 beyond the array).
constexpr std::size_t kThreshold = 4 * kPage;

inline bool wanted(std::size_t bytes) {
#if defined(__linux__)
  return bytes >= kThreshold;
#else
  (void)bytes;
  return false;
#endif
}

// Memory for `bytes` (>= kThreshold) on a 2 MiB boundary, advised into huge pages; the
// advice is a hint the kernel may ignore. Freed with std::free.
inline void* allocate(std::size_t bytes) {
#if defined(__linux__)
  const std::size_t rounded = (bytes + kPage - 1) / kPage * kPage;
  void* p = std::aligned_alloc(kPage, rounded);
  if (!p) throw std::bad_alloc();
  madvise(p, rounded, MADV_HUGEPAGE);
  return p;
#else
  (void)bytes;  // never called: wanted() is false
  throw std::bad_alloc();
#endif
}

}  // namespace huge_pages

template <class T>
struct DefaultInitAllocator : std::allocator<T> {
  template <class U>
  struct rebind {
    using other = DefaultInitAllocator<U>;
  };
  DefaultInitAllocator() noexcept = default;
  template <class U>
  DefaultInitAllocator(const DefaultInitAllocator<U>&) noexcept {}
  T* allocate(std::size_t n) {
    if (huge_pages::wanted(n * sizeof(T)))
      return static_cast<T*>(huge_pages::allocate(n * sizeof(T)));
    return std::allocator<T>::allocate(n);
  }
  void deallocate(T* p, std::size_t n) noexcept {
    if (huge_pages::wanted(n * sizeof(T))) {
      std::free(p);
    } else {
      std::allocator<T>::deallocate(p, n);
    }
  }
  // Default-initialisation: nothing is written for trivial types.
  template <class U>
  void construct(U* p) noexcept(std::is_nothrow_default_constructible<U>::value) {
    ::new (static_cast<void*>(p)) U;
  }
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
};

template <class T>
using UninitializedVector = std::vector<T, DefaultInitAllocator<T>>;

}  // namespace sdf
