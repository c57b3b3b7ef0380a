// SPDX-License-Identifier: GPL-3.0-or-later
#include "util/cpu_features.h"

#if SDF_X86_SIMD
#include <cpuid.h>
#endif

namespace sdf {

namespace {

constexpr std::uint32_t bit(int i) { return std::uint32_t{1} << i; }

// XCR0: the register state the OS saves. SSE (1) and AVX's upper halves (2) for YMM; the
// opmask registers (5), the upper halves of ZMM0-15 (6) and ZMM16-31 (7) for AVX-512.
constexpr std::uint64_t kXcr0Ymm = 0x6;
constexpr std::uint64_t kXcr0Zmm = 0xE0;

#if SDF_X86_SIMD
CpuidWords read_cpuid() {
  CpuidWords w;
  unsigned eax = 0, ebx = 0, ecx = 0, edx = 0;
  if (!__get_cpuid(0, &eax, &ebx, &ecx, &edx)) return w;
  w.max_leaf = eax;
  if (w.max_leaf >= 1 && __get_cpuid(1, &eax, &ebx, &ecx, &edx)) w.leaf1_ecx = ecx;
  if (w.max_leaf >= 7) {
    __cpuid_count(7, 0, eax, ebx, ecx, edx);
    w.leaf7_ebx = ebx;
  }
  // XGETBV faults where the OS has not enabled XSAVE (OSXSAVE clear): read it only when set.
  // Written as the instruction, not _xgetbv, which needs the file compiled for XSAVE.
  if (w.leaf1_ecx & bit(27)) {
    unsigned lo = 0, hi = 0;
    __asm__ volatile("xgetbv" : "=a"(lo), "=d"(hi) : "c"(0));
    w.xcr0 = (std::uint64_t{hi} << 32) | lo;
  }
  return w;
}
#endif

}  // namespace

CpuFeatures decode_cpu_features(const CpuidWords& w) {
  CpuFeatures f;
  const bool osxsave = (w.leaf1_ecx & bit(27)) != 0;
  const bool os_ymm = osxsave && (w.xcr0 & kXcr0Ymm) == kXcr0Ymm;
  const bool os_zmm = os_ymm && (w.xcr0 & kXcr0Zmm) == kXcr0Zmm;
  const bool avx = (w.leaf1_ecx & bit(28)) != 0;
  const bool fma = (w.leaf1_ecx & bit(12)) != 0;
  const bool leaf7 = w.max_leaf >= 7;
  const bool avx2 = leaf7 && (w.leaf7_ebx & bit(5)) != 0;
  const bool avx512f = leaf7 && (w.leaf7_ebx & bit(16)) != 0;
  f.avx2 = os_ymm && avx && avx2;
  f.fma = os_ymm && avx && fma;
  f.avx512f = os_zmm && avx && avx512f;
  return f;
}

const CpuFeatures& cpu_features() {
#if SDF_X86_SIMD
  static const CpuFeatures features = decode_cpu_features(read_cpuid());
#else
  static const CpuFeatures features;
#endif
  return features;
}

}  // namespace sdf
