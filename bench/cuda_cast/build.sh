#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# Builds bench/cuda_cast/out/cuda_cast (needs nvcc, the OpenCL headers and GLM): the core
# library with CMake in $BUILD (default /tmp/cc-build), the kernels with nvcc for sm_90.
# --fmad=false: no fused multiply-adds, as the core and the OpenCL kernels (same bits).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
BUILD=${BUILD:-/tmp/cc-build}
cmake -S "$root" -B "$BUILD" $(command -v ninja >/dev/null && echo -G Ninja) -DCMAKE_BUILD_TYPE=Release -DSDF_BUILD_TESTS=OFF \
  -DSDF_BUILD_BENCH=OFF >/dev/null
cmake --build "$BUILD" --target sdf_core
mkdir -p "$here/out"
nvcc -std=c++17 -O3 -arch=sm_90 -lineinfo --fmad=false -DSDF_MAX_RAYS=30 ${NVCC_EXTRA:-} \
  -Xptxas -v -c "$here/cast_kernels.cu" -o "$BUILD/cast_kernels.o" 2> "$here/out/ptxas.txt"
g++ -std=c++17 -O2 -ffp-contract=off -I"$root/native" -I"$root/kernels" -c "$here/main.cpp" \
  -o "$BUILD/cuda_cast_main.o"
nvcc -arch=sm_90 -o "$here/out/cuda_cast" "$BUILD/cuda_cast_main.o" "$BUILD/cast_kernels.o" \
  "$BUILD/libsdf_core.a" -lpthread -ldl -Xcompiler -static-libstdc++,-static-libgcc
echo "built $here/out/cuda_cast"
