// SPDX-License-Identifier: GPL-3.0-or-later
// Which SIMD paths this build has and this CPU may run. The x86-64 paths are compiled per
// function by attribute (target("avx2,fma"), target("avx512f")) and chosen at run time from
// the CPU's own answer (CPUID) and the operating system's (XGETBV: whether it saves the wider
// registers on a context switch), read here rather than through the compiler's
// __builtin_cpu_supports, which some toolchains answer with a constant 0. Every other
// machine (aarch64, ...) takes the portable paths, which give the same values.
#pragma once

#include <cstdint>

// x86-64 built by GCC or Clang: the SSE baseline, the per-function target attributes and
// <cpuid.h> are there. Elsewhere (aarch64, or MSVC, which has no such attributes) the portable
// paths alone are compiled.
#if (defined(__x86_64__) || defined(_M_X64)) && (defined(__GNUC__) || defined(__clang__))
#define SDF_X86_SIMD 1
#else
#define SDF_X86_SIMD 0
#endif

namespace sdf {

// Each: the CPU has it and the OS saves the registers it uses (YMM; ZMM and masks).
struct CpuFeatures {
  bool avx2 = false;
  bool fma = false;
  bool avx512f = false;  // AVX-512 Foundation
};

// What CPUID and XGETBV said, the words the decision reads.
struct CpuidWords {
  std::uint32_t max_leaf = 0;   // leaf 0, EAX
  std::uint32_t leaf1_ecx = 0;  // leaf 1, ECX: FMA (12), OSXSAVE (27), AVX (28)
  std::uint32_t leaf7_ebx = 0;  // leaf 7 subleaf 0, EBX: AVX2 (5), AVX512F (16)
  std::uint64_t xcr0 = 0;       // XGETBV(0), read only where OSXSAVE is set
};

// The decision alone, from given words (tests feed it CPUs and systems they do not have).
CpuFeatures decode_cpu_features(const CpuidWords& words);

// This machine's features, read once (all false where SDF_X86_SIMD is 0).
const CpuFeatures& cpu_features();

}  // namespace sdf
