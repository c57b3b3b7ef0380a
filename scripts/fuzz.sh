#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# No input crashes the program: the C++ tests under AddressSanitizer and
# UndefinedBehaviorSanitizer (build/asan), then the fuzzers, each for FUZZ_SECONDS (default 60):
# the libFuzzer target of the compute entry point (build/fuzz) and the atheris target of the
# mesh reading path (against the package installed in .venv: run scripts/setup.sh first, as
# scripts/test.sh does). Corpora grow in build/fuzz/corpus and are kept between runs.
# Exits non-zero on any finding and names the reproducer; a finding that is fixed goes into
# tests/fuzz/regressions/ (ctest and pytest replay it). Needs clang and libclang-rt-14-dev.
#   FUZZ_SECONDS=0  sanitized C++ tests and a replay of the corpora only, no fuzzing
#   FUZZ_JOBS=2     build jobs
set -uo pipefail
cd "$(dirname "$0")/.."
FUZZ_SECONDS=${FUZZ_SECONDS:-60}
PYTHON=${PYTHON:-.venv/bin/python}
JOBS=${FUZZ_JOBS:-2}
FINDINGS=build/fuzz/findings
failed=()
timings=()
stage_start=0
begin() { echo "fuzz: $1"; stage_start=$SECONDS; }
end() { timings+=("$1 $((SECONDS - stage_start)) s"); }

# The reports abort the program (ctest then fails), with a stack trace for UB too.
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:check_initialization_order=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}

if ! command -v clang++ >/dev/null; then
  echo "fuzz: clang++ not found (Debian: clang libclang-rt-14-dev; scripts/setup.sh installs them)"
  exit 1
fi

SANITIZED=(-G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++
           -DSDF_SANITIZE=address,undefined -DSDF_BUILD_BENCH=OFF)

begin "C++ tests under ASan + UBSan (build/asan)"
# CGAL is left out: its reference only serves pytest, and it is slow to build.
if cmake -S . -B build/asan "${SANITIZED[@]}" -DSDF_BUILD_TESTS=ON \
     -DCMAKE_DISABLE_FIND_PACKAGE_CGAL=ON >/dev/null &&
   cmake --build build/asan -j "$JOBS"; then
  end "asan build"
  stage_start=$SECONDS
  if ctest --test-dir build/asan --output-on-failure -j2 >build/asan/ctest.log 2>&1; then
    grep -E "tests passed, [0-9]+ tests failed out of|did not run|Skipped" build/asan/ctest.log
  else
    tail -n 80 build/asan/ctest.log
    failed+=("ctest under ASan + UBSan: build/asan/ctest.log")
  fi
  end "asan ctest"
else
  failed+=("the ASan + UBSan build (build/asan)")
fi

begin "building compute_fuzzer (build/fuzz)"
# The fuzzer drives the CPU engine only: no OpenCL.
if cmake -S . -B build/fuzz "${SANITIZED[@]}" -DSDF_BUILD_FUZZERS=ON -DSDF_BUILD_TESTS=OFF \
     -DSDF_WITH_OPENCL=OFF >/dev/null &&
   cmake --build build/fuzz -j "$JOBS"; then
  built_fuzzer=1
else
  built_fuzzer=0
  failed+=("the fuzzer build (build/fuzz)")
fi
# Seeds from tests/data, made again when their maker changes.
stamp=build/fuzz/seeds/.stamp
if [ ! -f $stamp ] || [ tests/fuzz/make_corpus.py -nt $stamp ]; then
  rm -rf build/fuzz/seeds
  "$PYTHON" tests/fuzz/make_corpus.py build/fuzz/seeds && touch $stamp ||
    failed+=("making the seed corpora (tests/fuzz/make_corpus.py)")
fi
mkdir -p build/fuzz/corpus/compute build/fuzz/corpus/mesh_io build/fuzz/seeds/compute \
  build/fuzz/seeds/mesh_io
rm -rf "$FINDINGS"
mkdir -p "$FINDINGS"
end "fuzzer build"

if [ "$FUZZ_SECONDS" -gt 0 ]; then
  LIMIT=(-max_total_time="$FUZZ_SECONDS")
else
  LIMIT=(-runs=0)
fi
# libFuzzer's flags: a hang (-timeout) and a memory blow-up (-rss_limit_mb) are findings too.
FLAGS=(-timeout=25 -rss_limit_mb=2048 -print_final_stats=1)

# $1: name, $2: log, rest: the command. Prints the outcome; remembers a finding.
run_fuzzer() {
  local name=$1 log=$2
  shift 2
  begin "$name for ${FUZZ_SECONDS} s (log: $log)"
  "$@" >"$log" 2>&1
  local status=$?
  grep -E '^Done [0-9]+ runs' "$log" | tail -n 1
  if [ $status -ne 0 ]; then
    grep -vE '^INFO: Instrumenting|^#[0-9]+[[:space:]]+(NEW|REDUCE|pulse|INITED)' "$log" |
      tail -n 40
    local found
    found=$(ls "$FINDINGS"/"$name"-* 2>/dev/null | head -n 1)
    echo "fuzz: $name FAILED (exit $status); reproducer: ${found:-none saved, see $log}"
    failed+=("$name: ${found:-see $log}")
  fi
  end "$name"
}

if [ $built_fuzzer = 1 ]; then
  # A run first replays its whole corpus, within its time: past FUZZ_CORPUS_MAX files the
  # corpus is merged down to the inputs that add coverage (measured: 996 -> 727 in 24 s).
  corpus=build/fuzz/corpus/compute
  count=$(ls $corpus | wc -l)
  if [ "$count" -gt "${FUZZ_CORPUS_MAX:-1000}" ]; then
    rm -rf $corpus.merged && mkdir -p $corpus.merged &&
      build/fuzz/tests/fuzz/compute_fuzzer -merge=1 $corpus.merged $corpus \
        >build/fuzz/merge.log 2>&1 &&
      rm -rf $corpus && mv $corpus.merged $corpus &&
      echo "fuzz: compute corpus merged from $count to $(ls $corpus | wc -l) inputs"
  fi
  run_fuzzer compute build/fuzz/compute.log \
    build/fuzz/tests/fuzz/compute_fuzzer build/fuzz/corpus/compute build/fuzz/seeds/compute \
    tests/fuzz/regressions/compute "${LIMIT[@]}" "${FLAGS[@]}" -max_len=4096 \
    -artifact_prefix="$FINDINGS/compute-"
fi

if ! "$PYTHON" -c "import atheris" 2>/dev/null; then
  "$PYTHON" -m pip install -q atheris || echo "fuzz: cannot install atheris"
fi
PLAIN=()
"$PYTHON" -c "import atheris" 2>/dev/null || PLAIN=(--plain)
run_fuzzer mesh_io build/fuzz/mesh_io.log \
  "$PYTHON" tests/fuzz/mesh_io_fuzzer.py "${PLAIN[@]}" build/fuzz/corpus/mesh_io \
  build/fuzz/seeds/mesh_io tests/fuzz/regressions/mesh_io "${LIMIT[@]}" "${FLAGS[@]}" \
  -max_len=8192 -artifact_prefix="$FINDINGS/mesh_io-"

echo "fuzz: times: $(IFS=,; echo "${timings[*]}" | sed 's/,/, /g')"
if [ ${#failed[@]} -gt 0 ]; then
  echo "fuzz: FAILED:"
  printf '  %s\n' "${failed[@]}"
  echo "fuzz: replay a compute finding with build/fuzz/tests/fuzz/compute_fuzzer FILE" \
       "(SDF_FUZZ_DESCRIBE=1 prints the mesh and options), a mesh_io one with" \
       "$PYTHON tests/fuzz/mesh_io_fuzzer.py FILE"
  exit 1
fi
echo "fuzz: no finding"
