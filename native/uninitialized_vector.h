// SPDX-License-Identifier: GPL-3.0-or-later
// std::vector whose resize() leaves trivially constructible elements uninitialised. The host
// stages fill large arrays (tens of MiB for a million faces) in parallel loops right after
// sizing them; a plain vector would first zero them on one thread, a pass as slow as the
// work itself, and fault every page in on that thread.
//
// Blocks of 2 MiB and more are also asked for transparent huge pages (Linux madvise): the
// first touch of a 4 KiB page costs about 3 us in the VMs we measure on, ~9 ms per 24 MiB
// array on 2 threads against ~1 ms in 2 MiB pages, and the host stages of one smoothing or
// one cast touch tens of MiB of fresh arrays per call.
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

namespace detail {

constexpr std::size_t kHugePage = std::size_t{2} << 20;

// Huge-page-aligned memory for large blocks (a hint: without THP it is plain memory), the
// global operator new for the rest. Released by release_block with the same size and
// alignment.
inline void* allocate_block(std::size_t bytes, std::size_t alignment) {
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  if (bytes >= kHugePage && alignment <= kHugePage) {
    const std::size_t rounded = (bytes + kHugePage - 1) / kHugePage * kHugePage;
    void* p = std::aligned_alloc(kHugePage, rounded);
    if (!p) throw std::bad_alloc();
    madvise(p, rounded, MADV_HUGEPAGE);
    return p;
  }
#endif
  return ::operator new(bytes, std::align_val_t(alignment));
}

inline void release_block(void* p, std::size_t bytes, std::size_t alignment) noexcept {
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  if (bytes >= kHugePage && alignment <= kHugePage) {
    std::free(p);
    return;
  }
#endif
  (void)bytes;
  ::operator delete(p, std::align_val_t(alignment));
}

}  // namespace detail

template <class T>
struct DefaultInitAllocator : std::allocator<T> {
  using value_type = T;
  T* allocate(std::size_t n) {
    if (n > static_cast<std::size_t>(-1) / sizeof(T)) throw std::bad_array_new_length();
    return static_cast<T*>(detail::allocate_block(n * sizeof(T), alignof(T)));
  }
  void deallocate(T* p, std::size_t n) noexcept {
    detail::release_block(p, n * sizeof(T), alignof(T));
  }
  template <class U>
  struct rebind {
    using other = DefaultInitAllocator<U>;
  };
  DefaultInitAllocator() noexcept = default;
  template <class U>
  DefaultInitAllocator(const DefaultInitAllocator<U>&) noexcept {}
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
