#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# Third call on the GPU machine (from the worktree root, ../.devdeps carried): the per-ray
# kernel with 16-byte loads from float4 kernel arguments and the rays ranked before the
# reduction, against the tree before (bench/cuda_cast/out/oldtree.tar.gz = git archive bca59f5),
# in OpenCL and CUDA, bits checked against the CPU engine; the OpenCL kernel's registers and
# SASS; Nsight Compute on the CUDA kernel; the Python package's OpenCL tests.
set -uo pipefail
OUT=${OUT:-/tmp/out}
R=/tmp/r
mkdir -p "$OUT" $R
exec > >(tee "$OUT/log.txt") 2>&1
date -u
bash ../.devdeps/device-setup.sh >/dev/null && source ../.devdeps/env.sh
export LD_LIBRARY_PATH=/opt/devdeps/usr/lib/x86_64-linux-gnu${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
(python3 -m pip install -q --no-index --find-links ../.devdeps/wheels pytest trimesh scikit-build-core &&
 CMAKE_BUILD_PARALLEL_LEVEL=6 python3 -m pip install -q --no-build-isolation --no-deps . ) > /tmp/pip.log 2>&1 &
PIP=$!
mkdir -p /tmp/oldtree && tar xzf bench/cuda_cast/out/oldtree.tar.gz -C /tmp/oldtree
(cd /tmp/oldtree && BUILD=/tmp/old-build bash bench/cuda_cast/build.sh > /tmp/old-build.log 2>&1) &
OLD=$!
BUILD=/tmp/cc-build bash bench/cuda_cast/build.sh 2>&1 | tail -1
grep -A1 "new_psort\b\|cast_per_rayILi0ELi0ELb0ELb0ELi1ELi4ELb1E" bench/cuda_cast/out/ptxas.txt | grep Used | head -2
wait $OLD; tail -1 /tmp/old-build.log
python3 bench/cuda_cast/mesh_bin.py bunny00-x16 /tmp/bunny.bin
python3 bench/cuda_cast/mesh_bin.py armadillo-x16 /tmp/arma.bin
BIN=bench/cuda_cast/out/cuda_cast
OLDBIN=/tmp/oldtree/bench/cuda_cast/out/cuda_cast
M=/tmp/bunny.bin
echo "== OpenCL new kernel alone (its own cache), for its PTX"
SDF_CACHE_DIR=/tmp/cache_new $BIN $M opencl
python3 - <<'PY'
import glob
for f in glob.glob("/tmp/cache_new/**/*.bin", recursive=True):
    d = open(f, "rb").read()
    i = d.find(b".version")
    if i >= 0:
        j = d.find(b"\0", i)
        open("/tmp/ocl.ptx", "wb").write(d[i:j if j > 0 else len(d)])
PY
ptxas -arch=sm_90 -v /tmp/ocl.ptx -o /tmp/ocl.cubin 2>&1 | grep -A2 "sdf_cast_bvh_per_ray" | tee "$R/ocl_ptxas.txt"
cuobjdump -sass -fun sdf_cast_bvh_per_ray /tmp/ocl.cubin > /tmp/ocl_sass.txt 2>&1
gzip -c /tmp/ocl_sass.txt > "$R/ocl_sass.txt.gz"
grep -oE "\b(LDG|LDL|STL|LDS|STS|STG|LD|ST)(\.[A-Z0-9]+)*" /tmp/ocl_sass.txt | sort | uniq -c | sort -rn
export SDF_CACHE_DIR=/tmp/sdfcache
echo "== CUDA variants, bits vs CPU"
$BIN $M all 2>&1 | tee "$R/all.txt" | tail -14
echo "== OpenCL per-ray kernel: before (old tree) and after (new), alternating, 3 casts each"
for round in 1 2; do
  for m in /tmp/bunny.bin /tmp/arma.bin; do
    echo "-- $m round $round"
    $OLDBIN $m all base 3 2>&1 | grep -E "^opencl " | sed 's/^/old tree: /'
    $BIN $m all new_psort 3 2>&1 | grep -E "^opencl " | sed 's/^/new tree: /'
  done
done | tee "$R/opencl_old_new.txt"
echo "== OpenCL new kernel with register caps"
for cap in 40 48; do
  SDF_OPENCL_EXTRA_OPTIONS="-cl-nv-maxrregcount=$cap" $BIN $M all new_psort 3 2>&1 | grep -E "^opencl " | sed "s/^/cap $cap: /"
done | tee "$R/opencl_caps.txt"
echo "== ncu: CUDA new_psort, full set"
ncu --clock-control none --set full --import-source no -k regex:cast_per_ray --launch-count 1 \
  -o /tmp/new $BIN $M cuda new_psort 1 > /tmp/ncu_new_run.txt 2>&1; tail -1 /tmp/ncu_new_run.txt
ncu --import /tmp/new.ncu-rep --page details > "$R/ncu_new_psort.txt" 2>&1
ncu --import /tmp/new.ncu-rep --page source --csv --print-source sass > /tmp/src.csv 2>&1 && gzip -c /tmp/src.csv > "$R/ncu_new_psort_sass.csv.gz"
cp /tmp/new.ncu-rep "$OUT/new_psort.ncu-rep" 2>/dev/null
grep -E "Duration|Achieved Occupancy|Registers Per|L1/TEX Cache Th|L2 Cache Th|DRAM Th|L1/TEX Hit|L2 Hit|Compute \(SM\) Th|Avg. Active Threads|Warp Cycles Per Issued|Executed Instructions  " "$R/ncu_new_psort.txt"
tar czf "$OUT/results.tgz" -C $R .
echo "== Python package and its OpenCL tests"
wait $PIP; tail -3 /tmp/pip.log
unset SDF_CACHE_DIR
python3 -c "import shape_diameter as s; print([(i, e.get('name'), e.get('type')) for i, e in enumerate(s.engines())])"
PYTHONUNBUFFERED=1 timeout 200 python3 -m pytest tests/python/test_opencl.py -q -p no:cacheprovider 2>&1 | tail -8 | tee "$R/pytest.txt"
date -u
tar czf "$OUT/results.tgz" -C $R .
