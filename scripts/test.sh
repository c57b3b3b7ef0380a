#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# Every test: set-up, C++ tests (ctest) with the CGAL reference built beside them, the same
# cross-compiled for aarch64 and run under qemu, the extension inside two real Blenders (bpy
# from PyPI), then pytest.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh

echo "test: building C++ tests"
cmake -S . -B build/cpp -G Ninja -DCMAKE_BUILD_TYPE=Release -DSDF_BUILD_TESTS=ON >/dev/null
cmake --build build/cpp
echo "test: ctest"
ctest --test-dir build/cpp --output-on-failure
echo "test: aarch64"
bash scripts/cross_aarch64.sh
bash scripts/fuzz.sh

echo "test: Blender"
bash scripts/test_blender.sh

echo "test: pytest"
export SDF_CGAL_REFERENCE="$PWD/build/cpp/tests/reference/cgal_sdf"
.venv/bin/python -m pytest -q "$@"
