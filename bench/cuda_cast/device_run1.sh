#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# First profiling call on the GPU machine (from the worktree root, ../.devdeps carried):
# bit checks and timings of OpenCL and the CUDA variants, whether ncu sees the OpenCL kernel,
# the OpenCL kernel's registers (ptxas on its cached PTX), and Nsight Compute reports of the
# CUDA kernel. Everything lands in $OUT.
set -uo pipefail
OUT=${OUT:-/tmp/out}
R=/tmp/r
mkdir -p "$OUT" $R
exec > >(tee "$OUT/log.txt") 2>&1
date -u
bash ../.devdeps/device-setup.sh && source ../.devdeps/env.sh
export LD_LIBRARY_PATH=/opt/devdeps/usr/lib/x86_64-linux-gnu${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
export SDF_CACHE_DIR=/tmp/sdfcache
nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.max.sm,clocks.mem --format=csv
which ncu nvcc ptxas; ncu --version | tail -1
BIN=bench/cuda_cast/out/cuda_cast
if ! $BIN 2>&1 | grep -q usage; then
  echo "== carried binary does not run here; building"
  bash bench/cuda_cast/build.sh 2>&1 | tail -3
fi
python3 bench/cuda_cast/mesh_bin.py bunny00-x16 /tmp/bunny.bin
M=/tmp/bunny.bin
echo "== all variants (bits vs CPU engine, times)"
$BIN $M all 2>&1 | tee "$R/all.txt" | tail -40
echo "== ncu on the OpenCL kernel?"
timeout 150 ncu --clock-control none --target-processes all --launch-count 1 \
  --section SpeedOfLight $BIN $M opencl > "$R/ncu_opencl.txt" 2>&1
tail -25 "$R/ncu_opencl.txt"
echo "== OpenCL kernel's PTX through ptxas"
python3 - <<'PY'
import glob
for f in glob.glob("/tmp/sdfcache/**/*", recursive=True):
    try:
        d = open(f, "rb").read()
    except IsADirectoryError:
        continue
    i = d.find(b".version")
    if i < 0:
        continue
    j = d.find(b"\0", i)
    open("/tmp/ocl.ptx", "wb").write(d[i:j if j > 0 else len(d)])
    print("PTX from", f, j - i if j > 0 else len(d) - i, "bytes")
PY
cp /tmp/ocl.ptx "$R/ocl.ptx" 2>/dev/null
ptxas -arch=sm_90 -v /tmp/ocl.ptx -o /tmp/ocl.cubin 2>&1 | grep -A2 "sdf_cast_bvh_per_ray" | tee "$R/ocl_ptxas.txt"
cuobjdump -sass -fun sdf_cast_bvh_per_ray /tmp/ocl.cubin > "$R/ocl_sass.txt" 2>&1; wc -l "$R/ocl_sass.txt"
echo "== OpenCL with register caps (bits vs CPU, 3 runs best)"
for cap in 32 40; do
  SDF_OPENCL_EXTRA_OPTIONS="-cl-nv-maxrregcount=$cap" $BIN $M all base 3 2>&1 | grep -E "^(opencl|cuda)"
done
echo "== ncu: CUDA base, full set"
ncu --clock-control none --set full --import-source no -k regex:cast_per_ray --launch-count 1 \
  -o /tmp/base $BIN $M cuda base 1 > /tmp/ncu_base_run.txt 2>&1; tail -3 /tmp/ncu_base_run.txt
ncu --import /tmp/base.ncu-rep --page details > "$R/ncu_base.txt" 2>&1
ncu --import /tmp/base.ncu-rep --page source --csv --print-source sass > /tmp/src.csv 2>&1 && gzip -c /tmp/src.csv > "$R/ncu_base_sass.csv.gz"
cp /tmp/base.ncu-rep "$OUT/" 2>/dev/null
echo "== ncu: CUDA variants, main sections"
for v in sh8 minb12 minb16; do
  ncu --clock-control none --section SpeedOfLight --section Occupancy --section WarpStateStats \
    --section MemoryWorkloadAnalysis --section LaunchStats -k regex:cast_per_ray --launch-count 1 \
    $BIN $M cuda $v 1 > "$R/ncu_$v.txt" 2>&1
done
grep -h -E "Duration|Achieved Occupancy|Registers Per|Memory Throughput|L1/TEX Hit|L2 Hit|Compute \(SM\) Th" "$R"/ncu_*.txt | head -60
date -u
tar czf "$OUT/results.tgz" -C $R .
