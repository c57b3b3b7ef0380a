#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# Runs on the GPU machine (the device tool), from the repository root: builds
# bench/tinybvh_compare and compares our OpenCL cast with tinybvh's GPU kernel on the same SDF
# rays, 208k to 1.21M faces, leaving the tables in $OUT/tinybvh.md and the log beside them.
# Needs .devdeps carried (made here by ../shared/tools/device-debs.sh) with tinybvh's folder
# copied into it, since only the repository and carried paths travel:
#   cp -r ../shared/reference/tinybvh .devdeps/tinybvh
# Usage: OUT=/some/dir bash bench/tinybvh_gpu.sh [tinybvh_compare args, e.g. --rays 64]
set -uo pipefail
OUT=${OUT:-/tmp/sdf-gpu-out}
TINYBVH=${TINYBVH:-$PWD/.devdeps/tinybvh}
mkdir -p "$OUT"
exec > >(tee "$OUT/tinybvh-log.txt") 2>&1
if [ ! -f "$TINYBVH/tiny_bvh.h" ]; then
  echo "no tinybvh in $TINYBVH: copy ../shared/reference/tinybvh there, or set TINYBVH"
  exit 2
fi
bash .devdeps/device-setup.sh && source .devdeps/env.sh
nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv
clinfo -l
echo "== build"
cmake -S . -B build/tinybvh -DCMAKE_BUILD_TYPE=Release -DSDF_TINYBVH_DIR="$TINYBVH" >/dev/null &&
  cmake --build build/tinybvh -j"$(nproc)" --target tinybvh_compare 2>&1 | tail -3 || exit 1
echo "== tinybvh_compare ($(date -u +%Y-%m-%dT%H:%MZ))"
# armadillo-x4 208k, bunny00-x4 302k, armadillo-x16 832k, bunny00-x16 1.21M faces (MESHES
# replaces them: OFF files, :K subdivided K times).
MESHES=${MESHES:-tests/data/armadillo.off:1 tests/data/bunny00.off:1 tests/data/armadillo.off:2 tests/data/bunny00.off:2}
# shellcheck disable=SC2086
build/tinybvh/bench/tinybvh_compare --tinybvh "$TINYBVH" --device opencl --rounds 7 $MESHES "$@" |
  tee "$OUT/tinybvh.md"
