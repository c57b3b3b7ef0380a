#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# Every test: set-up, C++ tests (ctest) with the CGAL reference built beside them, the same
# cross-compiled for aarch64 and run under qemu (scripts/cross_aarch64.sh), the Windows x64
# wheel under wine (scripts/build_wheels.sh, scripts/check_wheels.sh), the C++
# tests under ASan + UBSan and the fuzzers (scripts/fuzz.sh), the extension inside two real
# Blenders (bpy from PyPI), then pytest. Every suite runs even when one before it failed; the
# last lines sum them up, one line a suite, and the exit status is non-zero if any failed.
# Arguments go to pytest.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
mkdir -p build
LOGS=build/test-logs
rm -rf "$LOGS" && mkdir -p "$LOGS"

summary=()
status=0
# suite NAME LOG COMMAND...: runs it, its output shown and kept in LOG; remembers the outcome.
suite() {
  local name=$1 log=$2 start=$SECONDS rc
  shift 2
  echo "test: $name"
  set +e
  "$@" 2>&1 | tee "$log"
  rc=${PIPESTATUS[0]}
  set -e
  [ "$rc" -eq 0 ] || status=1
  summary+=("$(printf '%-22s %-40s %5d s' "$name" "$(counts "$log" "$rc")" $((SECONDS - start)))")
}
# counts LOG RC: "N passed, N failed" from ctest's, pytest's or the Blender script's last words.
counts() {
  local log=$1 rc=$2 line
  line=$(grep -E 'tests passed, [0-9]+ tests failed out of' "$log" | tail -n 1)
  if [ -n "$line" ]; then
    local total failed
    total=$(echo "$line" | grep -oE 'out of [0-9]+' | grep -oE '[0-9]+')
    failed=$(echo "$line" | grep -oE '[0-9]+ tests failed' | grep -oE '^[0-9]+')
    echo "$((total - failed)) passed, $failed failed"
    return
  fi
  line=$(grep -E '^(=+ )?[0-9]+ (passed|failed)|^blender: [0-9]+ passed' "$log" | tail -n 1)
  if [ -n "$line" ]; then
    echo "$line" | sed -E 's/^=+ //; s/ in [0-9.]+s.*//; s/^blender: //'
  elif [ "$rc" -eq 0 ]; then
    echo "ok"
  else
    echo "FAILED (exit $rc)"
  fi
}

build_and_ctest() {
  cmake -S . -B build/cpp -G Ninja -DCMAKE_BUILD_TYPE=Release -DSDF_BUILD_TESTS=ON >/dev/null
  cmake --build build/cpp
  ctest --test-dir build/cpp --output-on-failure
}
suite "C++ (ctest)" "$LOGS/ctest.log" build_and_ctest
suite "C++ on aarch64 (qemu)" "$LOGS/aarch64.log" bash scripts/cross_aarch64.sh
# The Windows x64 wheel for Python 3.11, cross-built with zig and run under wine, against the
# values of the package in .venv, in python.org's CPython whose PSF signature is verified. The
# other platforms: scripts/build_wheels.sh all, then scripts/check_wheels.sh (README.md,
# Platforms): each other wheel costs 4 to 10 minutes to build here, so CI builds none of them.
windows_under_wine() {
  SDF_WHEEL_PYTHONS=cp311 bash scripts/build_wheels.sh windows-x64 &&
    SDF_WHEEL_PYTHONS=cp311 bash scripts/check_wheels.sh windows-x64
}
suite "Windows x64 (wine)" "$LOGS/windows.log" windows_under_wine
# fuzz.sh prints the sanitized ctest's counts, then each fuzzer's runs.
suite "ASan+UBSan, fuzzers" "$LOGS/fuzz.log" bash scripts/fuzz.sh
suite "Blender" "$LOGS/blender.log" bash scripts/test_blender.sh
export SDF_CGAL_REFERENCE="$PWD/build/cpp/tests/reference/cgal_sdf"
export SDF_CGAL_SEGMENT="$PWD/build/cpp/tests/reference/cgal_segment"
suite "Python (pytest)" "$LOGS/pytest.log" .venv/bin/python -m pytest -q "$@"

echo "test: summary (logs in $LOGS)"
printf '  %s\n' "${summary[@]}"
total_passed=0
total_failed=0
for line in "${summary[@]}"; do
  p=$(echo "$line" | grep -oE '[0-9]+ passed' | grep -oE '[0-9]+' || echo 0)
  f=$(echo "$line" | { grep -oE '[0-9]+ (failed|errors?)' || true; } | awk '{s += $1} END {print s + 0}')
  total_passed=$((total_passed + ${p:-0}))
  total_failed=$((total_failed + ${f:-0}))
  case $line in *FAILED*) total_failed=$((total_failed + 1)) ;; esac
done
[ "$status" -eq 0 ] || [ "$total_failed" -gt 0 ] || total_failed=1
echo "total: $total_passed passed, $total_failed failed"
exit $status
