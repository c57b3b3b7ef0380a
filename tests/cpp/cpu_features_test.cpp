// SPDX-License-Identifier: GPL-3.0-or-later
// CPU feature detection: the decision from CPUID and XGETBV words (CPUs and operating systems
// this machine is not), and this machine's answer against what Linux lists in /proc/cpuinfo.
#include <gtest/gtest.h>

#include <fstream>
#include <set>
#include <sstream>
#include <string>

#include "accel/bvh8.h"
#include "util/cpu_features.h"

namespace sdf {
namespace {

constexpr std::uint32_t kFma = 1u << 12, kOsxsave = 1u << 27, kAvx = 1u << 28;
constexpr std::uint32_t kAvx2 = 1u << 5, kAvx512f = 1u << 16;

// A Haswell-like CPU under an OS that saves SSE and AVX state.
CpuidWords avx2_machine() {
  CpuidWords w;
  w.max_leaf = 13;
  w.leaf1_ecx = kFma | kOsxsave | kAvx;
  w.leaf7_ebx = kAvx2;
  w.xcr0 = 0x7;  // x87, SSE, AVX
  return w;
}

TEST(CpuFeatures, Avx2AndFmaWhereTheCpuHasThemAndTheOsSavesYmm) {
  const CpuFeatures f = decode_cpu_features(avx2_machine());
  EXPECT_TRUE(f.avx2);
  EXPECT_TRUE(f.fma);
  EXPECT_FALSE(f.avx512f);
}

TEST(CpuFeatures, NothingWideWhereTheOsDoesNotSaveYmm) {
  CpuidWords no_osxsave = avx2_machine();
  no_osxsave.leaf1_ecx &= ~kOsxsave;
  no_osxsave.xcr0 = 0;  // never read without OSXSAVE
  CpuidWords sse_only = avx2_machine();
  sse_only.xcr0 = 0x3;  // the OS saves x87 and SSE, not the upper halves
  for (const CpuidWords& w : {no_osxsave, sse_only}) {
    const CpuFeatures f = decode_cpu_features(w);
    EXPECT_FALSE(f.avx2);
    EXPECT_FALSE(f.fma);
  }
}

TEST(CpuFeatures, EachBitCounts) {
  CpuidWords no_avx2 = avx2_machine();
  no_avx2.leaf7_ebx = 0;
  EXPECT_FALSE(decode_cpu_features(no_avx2).avx2);
  EXPECT_TRUE(decode_cpu_features(no_avx2).fma);
  CpuidWords no_fma = avx2_machine();
  no_fma.leaf1_ecx &= ~kFma;
  EXPECT_TRUE(decode_cpu_features(no_fma).avx2);
  EXPECT_FALSE(decode_cpu_features(no_fma).fma);
  CpuidWords old_cpu = avx2_machine();
  old_cpu.max_leaf = 6;  // leaf 7 does not exist: its word is not AVX2
  EXPECT_FALSE(decode_cpu_features(old_cpu).avx2);
}

TEST(CpuFeatures, Avx512NeedsTheOsToSaveZmmAndMasks) {
  CpuidWords w = avx2_machine();
  w.leaf7_ebx |= kAvx512f;
  EXPECT_FALSE(decode_cpu_features(w).avx512f) << "XCR0 0x7";
  w.xcr0 = 0xE7;
  EXPECT_TRUE(decode_cpu_features(w).avx512f) << "XCR0 0xE7";
  w.xcr0 = 0x67;  // ZMM16-31 not saved
  EXPECT_FALSE(decode_cpu_features(w).avx512f) << "XCR0 0x67";
}

// The flags of the first processor in /proc/cpuinfo (Linux on x86 lists a feature there only
// where the kernel also saves its registers); empty where there is no such file or line.
std::set<std::string> cpuinfo_flags() {
  std::ifstream in("/proc/cpuinfo");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("flags", 0) != 0) continue;
    std::istringstream words(line.substr(line.find(':') + 1));
    std::set<std::string> flags;
    for (std::string w; words >> w;) flags.insert(w);
    return flags;
  }
  return {};
}

TEST(CpuFeatures, ThisMachineAgreesWithProcCpuinfo) {
#if SDF_X86_SIMD
  const std::set<std::string> flags = cpuinfo_flags();
  if (flags.empty()) GTEST_SKIP() << "no flags line in /proc/cpuinfo to compare with";
  const CpuFeatures& f = cpu_features();
  EXPECT_EQ(f.avx2, flags.count("avx2") == 1);
  EXPECT_EQ(f.fma, flags.count("fma") == 1);
  EXPECT_EQ(f.avx512f, flags.count("avx512f") == 1);
  EXPECT_EQ(bvh8_supported(), flags.count("avx2") == 1 && flags.count("fma") == 1);
#else
  // Not an x86-64 build (an emulator's /proc/cpuinfo may well be the x86 host's): no path
  // of x86 instructions may be chosen.
  const CpuFeatures& f = cpu_features();
  EXPECT_FALSE(f.avx2 || f.fma || f.avx512f);
  EXPECT_FALSE(bvh8_supported());
#endif
}

}  // namespace
}  // namespace sdf
