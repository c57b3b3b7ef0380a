#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# Fourth call on the GPU machine (from the worktree root, ../.devdeps carried): the Python
# package before (bench/cuda_cast/out/oldtree.tar.gz = git archive bca59f5) and after, through
# bench/opencl_vs_cpu.py and bench/stages.py; the device-lost test on the package before;
# OpenCL register caps on the per-ray kernel, bits checked against the CPU engine.
set -uo pipefail
OUT=${OUT:-/tmp/out}
R=/tmp/r
mkdir -p "$OUT" $R
exec > >(tee "$OUT/log.txt") 2>&1
date -u
bash ../.devdeps/device-setup.sh >/dev/null && source ../.devdeps/env.sh
export LD_LIBRARY_PATH=/opt/devdeps/usr/lib/x86_64-linux-gnu${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
python3 -m pip install -q --no-index --find-links ../.devdeps/wheels pytest trimesh scikit-build-core
mkdir -p /tmp/oldtree && tar xzf bench/cuda_cast/out/oldtree.tar.gz -C /tmp/oldtree
(CMAKE_BUILD_PARALLEL_LEVEL=6 python3 -m pip install -q --no-build-isolation --no-deps . ) > /tmp/pip.log 2>&1 &
PIP=$!
(cd /tmp/oldtree && CMAKE_BUILD_PARALLEL_LEVEL=6 python3 -m pip install -q --no-build-isolation --no-deps --target /tmp/oldpkg . ) > /tmp/pip_old.log 2>&1 &
PIPOLD=$!
BUILD=/tmp/cc-build bash bench/cuda_cast/build.sh 2>&1 | tail -1
python3 bench/cuda_cast/mesh_bin.py bunny00-x16 /tmp/bunny.bin
BIN=bench/cuda_cast/out/cuda_cast
M=/tmp/bunny.bin
export SDF_CACHE_DIR=/tmp/sdfcache
echo "== OpenCL per-ray kernel, register caps, alternating (3 casts each, bits vs CPU)"
for round in 1 2; do
  for cap in none 40 36; do
    opt=""; [ $cap != none ] && opt="-cl-nv-maxrregcount=$cap"
    SDF_OPENCL_EXTRA_OPTIONS="$opt" $BIN $M all new_psort 3 2>&1 | grep -E "^opencl " | sed "s/^/cap $cap: /"
  done
done | tee "$R/opencl_caps.txt"
wait $PIP; tail -2 /tmp/pip.log; wait $PIPOLD; tail -2 /tmp/pip_old.log
unset SDF_CACHE_DIR
echo "== device-lost test: package before (bca59f5) and after"
(cd /tmp/oldtree && PYTHONPATH=/tmp/oldpkg timeout 60 python3 -m pytest tests/python/test_opencl.py -q -p no:cacheprovider -k device_lost 2>&1 | tail -2 | sed 's/^/before: /')
timeout 60 python3 -m pytest tests/python/test_opencl.py -q -p no:cacheprovider -k device_lost 2>&1 | tail -1 | sed 's/^/after: /'
echo "== bench/opencl_vs_cpu.py (SAH tree, bits vs CPU): before, after, before, after"
for pkg in old new old new; do
  if [ $pkg = old ]; then P=/tmp/oldpkg; else P=; fi
  PYTHONPATH=$P PYTHONUNBUFFERED=1 python3 bench/opencl_vs_cpu.py opencl:0 armadillo-x16,bunny00-x16 bvh_per_ray,bvh_per_point 1 2>&1 | sed "s/^/$pkg: /"
done | tee "$R/opencl_vs_cpu.txt"
echo "== bench/stages.py opencl:0 bunny00-x16 (end to end): before, after"
for pkg in old new; do
  if [ $pkg = old ]; then P=/tmp/oldpkg; else P=; fi
  PYTHONPATH=$P PYTHONUNBUFFERED=1 python3 bench/stages.py opencl:0 bunny00-x16 2>&1 | sed "s/^/$pkg: /"
done | tee "$R/stages.txt"
date -u
tar czf "$OUT/results.tgz" -C $R .
