#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# The benchmark references on top of scripts/setup.sh: Debian's Embree 3 (a reference only,
# never a product dependency) and the programs built against it in build/cpp/bench
# (embree_sdf, cast_timing), with CGAL's in build/cpp/tests/reference. Idempotent.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
if ! dpkg-query -W -f='${Status}' libembree-dev 2>/dev/null | grep -q "install ok installed"; then
  echo "setup_bench: installing libembree-dev"
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends libembree-dev
fi
cmake -S . -B build/cpp -G Ninja -DCMAKE_BUILD_TYPE=Release -DSDF_BUILD_TESTS=ON >/dev/null
cmake --build build/cpp --target embree_sdf cast_timing cgal_sdf cgal_segment
echo "setup_bench: build/cpp/bench/embree_sdf, build/cpp/bench/cast_timing ready"
