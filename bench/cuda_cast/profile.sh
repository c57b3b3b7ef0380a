#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# On the GPU machine, from the repository root with .devdeps carried: builds the CUDA harness,
# checks every traversal variant's bits against the CPU engine, times the OpenCL per-ray kernel
# against the CUDA variants, and profiles one CUDA variant with Nsight Compute (ncu cannot see
# OpenCL kernels). Usage: OUT=dir bash bench/cuda_cast/profile.sh [MESH [VARIANT]]
# MESH: a bench mesh name (bench/meshes.py; default bunny00-x16); VARIANT: a CUDA variant
# name of main.cpp (default new_psort). Results and the ncu report land in $OUT.
set -uo pipefail
OUT=${OUT:-/tmp/cuda-cast-out}
MESH=${1:-bunny00-x16}
VARIANT=${2:-new_psort}
mkdir -p "$OUT"
exec > >(tee "$OUT/log.txt") 2>&1
bash .devdeps/device-setup.sh >/dev/null && source .devdeps/env.sh
export LD_LIBRARY_PATH=/opt/devdeps/usr/lib/x86_64-linux-gnu${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
bash bench/cuda_cast/build.sh | tail -1
grep -B1 Used bench/cuda_cast/out/ptxas.txt | grep -A1 "$VARIANT" | grep Used | head -1
python3 bench/cuda_cast/mesh_bin.py "$MESH" /tmp/mesh.bin
BIN=bench/cuda_cast/out/cuda_cast
echo "== every variant, CUDA and OpenCL, bits against the CPU engine"
$BIN /tmp/mesh.bin all 2>&1 | tee "$OUT/variants.txt"
echo "== ncu on the CUDA variant $VARIANT"
ncu --clock-control none --set full --import-source no -k regex:cast_per_ray --launch-count 1 \
  -o /tmp/profile "$BIN" /tmp/mesh.bin cuda "$VARIANT" 1 > /tmp/ncu_run.txt 2>&1
tail -1 /tmp/ncu_run.txt
ncu --import /tmp/profile.ncu-rep --page details > "$OUT/ncu_$VARIANT.txt" 2>&1
cp /tmp/profile.ncu-rep "$OUT/" 2>/dev/null
grep -E "Duration|Achieved Occupancy|Registers Per|L1/TEX Cache Th|L2 Cache Th|DRAM Th|L1/TEX Hit|L2 Hit|Avg. Active Threads|Warp Cycles Per Issued" "$OUT/ncu_$VARIANT.txt"
