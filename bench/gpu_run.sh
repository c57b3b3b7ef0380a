#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# Runs on the GPU machine (the device tool), from the repository root, with .devdeps carried
# (made here by ../shared/tools/device-debs.sh libgtest-dev plus Python wheels in
# .devdeps/wheels: pytest iniconfig pluggy packaging pygments trimesh scikit-build-core pathspec).
# Builds everything, runs the C++ tests, the OpenCL tests on the GPU and the benchmark, and
# leaves logs and tables in $OUT. Usage: OUT=/some/dir bash bench/gpu_run.sh [bench args]
set -uo pipefail
OUT=${OUT:-/tmp/sdf-gpu-out}
mkdir -p "$OUT"
exec > >(tee "$OUT/log.txt") 2>&1
bash .devdeps/device-setup.sh && source .devdeps/env.sh
nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv
clinfo -l
# The machine's python3 is a venv with numpy and pybind11; the machine is thrown away after.
PY=$(command -v python3)
"$PY" -m pip install -q --no-index --find-links .devdeps/wheels pytest trimesh scikit-build-core
echo "== build"
cmake -S . -B build/cpp -DCMAKE_BUILD_TYPE=Release -DSDF_BUILD_TESTS=ON >/dev/null &&
  cmake --build build/cpp -j"$(nproc)" 2>&1 | tail -3
echo "== ctest"
ctest --test-dir build/cpp 2>&1 | tail -4
echo "== python package"
"$PY" -m pip install -q --no-build-isolation --no-deps . 2>&1 | tail -3
"$PY" -c "import shape_diameter as s, json; print(json.dumps(s.engines(), indent=1))"
echo "== OpenCL tests (GPU first)"
PYTHONUNBUFFERED=1 "$PY" -m pytest tests/python/test_opencl.py tests/python/test_smoothing_opencl.py \
  -q -p no:cacheprovider 2>&1 | tail -15
echo "== benchmark"
gpu=$("$PY" -c "import shape_diameter as s; print(next(e['name'] for e in s.engines() if e['type'] == 'GPU'))")
PYTHONUNBUFFERED=1 "$PY" bench/bench.py --engines "$gpu,cpu" --out "$OUT/RESULTS-gpu.md" "$@"
if [ "$(nvidia-smi -L | wc -l)" -ge 2 ]; then
  echo "== several GPUs: opencl:all against one"
  PYTHONUNBUFFERED=1 "$PY" bench/bench.py --engines "$gpu,opencl:all" --only armadillo-x16,bunny00-x16 \
    --title "Several GPUs" --out "$OUT/RESULTS-gpu.md"
fi
echo "== stages of compute() on the GPU (end to end)"
PYTHONUNBUFFERED=1 "$PY" bench/stages.py "$gpu" | tee "$OUT/stages.txt"
PYTHONUNBUFFERED=1 "$PY" bench/bench.py --engines "$gpu" --rays 64 \
  --only bunny00-x16,armadillo-x16 --title "64 rays" --out "$OUT/RESULTS-gpu.md"
