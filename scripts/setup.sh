#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# Everything a fresh Debian 12 machine needs, idempotent: Debian packages, a Python venv in
# .venv with the build and test tools, and shape_diameter built and installed into it.
# Re-running rebuilds only what changed (scikit-build-core keeps build/wheel-*).
set -euo pipefail
cd "$(dirname "$0")/.."

APT_PACKAGES=(
  build-essential cmake ninja-build git       # C++ toolchain
  libglm-dev                                  # vector math of the core
  opencl-c-headers                            # OpenCL engine (libOpenCL itself is loaded at run time)
  ocl-icd-libopencl1 pocl-opencl-icd clinfo   # an OpenCL driver on the CPU (PoCL) for the tests
  libgtest-dev                                # C++ tests
  libcgal-dev                                 # reference implementation, tests/benchmarks only
  clang libclang-rt-14-dev                    # sanitizers and libFuzzer (scripts/fuzz.sh)
  g++-aarch64-linux-gnu qemu-user-static      # the aarch64 build and its tests (scripts/cross_aarch64.sh)
  llvm osslsigncode                           # the wheels' checks: llvm-objdump, llvm-nm, signatures
  python3 python3-venv python3-dev            # the Python package
)
missing=()
for p in "${APT_PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing Debian packages: ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

PYTHON=${PYTHON:-python3}
if [ ! -x .venv/bin/python ]; then
  echo "setup: creating .venv with $($PYTHON --version)"
  "$PYTHON" -m venv .venv
fi
# Build tools installed up front so the package builds without isolation, against a build
# directory that survives between runs (incremental rebuilds).
.venv/bin/python -m pip install -q --upgrade pip
.venv/bin/python -m pip install -q "scikit-build-core>=0.10" "pybind11>=2.12" numpy \
  "trimesh>=4.4" "tqdm>=4.60" "pytest>=7" "scipy>=1.9" "atheris>=2.3" \
  "dask[distributed]>=2024.8"
echo "setup: building shape_diameter"
.venv/bin/python -m pip install -q --no-build-isolation --no-deps ".[cli,test]"
.venv/bin/python -c "import shape_diameter as s; print('setup: shape_diameter', s.__version__, 'engines:', [e['name'] for e in s.engines()])"
