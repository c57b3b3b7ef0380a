# SPDX-License-Identifier: GPL-3.0-or-later
# Sourced by scripts/check_wheels.sh and scripts/build_extension.sh: the targets
# scripts/build_wheels.sh builds (named as Blender names its platforms) and their wheels.
ALL_TARGETS=(linux-x64 linux-arm64 windows-x64 windows-arm64 macos-arm64 macos-x64)
WHEELS=${WHEELS:-dist/wheels}

# wheel_for TARGET TAG: the path of that target's wheel for CPython TAG (cp311, cp313) in
# $WHEELS, or nothing when it was not built.
wheel_for() {
  local pattern
  case $1 in
    linux-x64) pattern=manylinux_*_x86_64 ;;
    linux-arm64) pattern=manylinux_*_aarch64 ;;
    windows-x64) pattern=win_amd64 ;;
    windows-arm64) pattern=win_arm64 ;;
    macos-arm64) pattern=macosx_*_arm64 ;;
    macos-x64) pattern=macosx_*_x86_64 ;;
  esac
  # shellcheck disable=SC2086
  ls $WHEELS/shape_diameter-*-"$2"-"$2"-$pattern.whl 2>/dev/null | head -n 1 || true
}
