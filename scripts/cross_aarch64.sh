#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# The core and its C++ tests on a CPU without SSE: cross-compiled for aarch64 with Debian's
# g++-aarch64-linux-gnu (cmake/aarch64-linux-gnu.cmake; GoogleTest built from
# /usr/src/googletest for the target, the OpenCL engine built too: its headers are
# arch-independent), then run under qemu-user (qemu-aarch64-static -L /usr/aarch64-linux-gnu).
# Every x86 path is compiled out there, so the tests check the portable ones: the binary
# BVH's traversal in the CPU engine, the plain BVH-builder loops, the scalar smoothing.
# All C++ tests run (the AVX-512 one skips). Cold cost on a 2-core machine shared with other
# builds (load about 12): the packages 49 s, the build 18 min (3.5 CPU minutes), the tests
# under emulation 10 to 16 min (4 CPU minutes; 5 to 50 times the native time); on idle cores
# the CPU times are about the wall times.
#   scripts/cross_aarch64.sh                  build, then run every C++ test under qemu
#   CROSS_TESTS=none scripts/cross_aarch64.sh build only
set -euo pipefail
cd "$(dirname "$0")/.."

for tool in aarch64-linux-gnu-g++ qemu-aarch64-static; do
  if ! command -v "$tool" >/dev/null; then
    echo "cross_aarch64: $tool missing (scripts/setup.sh installs g++-aarch64-linux-gnu and" \
         "qemu-user-static)" >&2
    exit 1
  fi
done

BUILD=build/aarch64
echo "cross_aarch64: building the core and the C++ tests for aarch64"
cmake -S . -B "$BUILD" -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_TOOLCHAIN_FILE=cmake/aarch64-linux-gnu.cmake \
  -DSDF_BUILD_TESTS=ON -DSDF_BUILD_BENCH=OFF -DSDF_GTEST_SOURCE_DIR=/usr/src/googletest >/dev/null
cmake --build "$BUILD"
readelf -h "$BUILD/tests/cpp/cpu_cast_paths_test" | grep -q "Machine: *AArch64" || {
  echo "cross_aarch64: the tests were not built for aarch64" >&2
  exit 1
}

if [ "${CROSS_TESTS:-all}" != none ]; then
  echo "cross_aarch64: the C++ tests under qemu-aarch64"
  ctest --test-dir "$BUILD" --output-on-failure
fi
