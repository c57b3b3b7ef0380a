#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# Tests the Blender extension inside real Blender, in two versions (bpy from PyPI):
#   .venv-bpy45  bpy 4.5 LTS, Python 3.11, numpy < 2 (bpy 4.x does not pin it)
#   .venv-bpy51  bpy >= 5.1, Python 3.13, numpy 2.x
# Builds dist/shape_diameter-<version>-linux_x64.zip (scripts/build_extension.sh), then, for
# each Blender, installs the zip through Blender's own extension install path into a fresh
# user directory (BLENDER_USER_RESOURCES) and runs pytest on tests/blender. Arguments go to
# pytest. The bpy wheels (~380 MB each) come from pip's cache after the first run.
#
# Environment: PY311, PY313 (interpreters), SDF_BLENDER_VERSIONS (default "45 51").
set -euo pipefail
cd "$(dirname "$0")/.."

log() { echo "test_blender: $*"; }
source scripts/blender_venv.sh

bash scripts/build_extension.sh
ZIP=$(ls -t dist/shape_diameter-*-linux_x64.zip | head -1)

passed=0
failed=0
status=0
for version in ${SDF_BLENDER_VERSIONS:-45 51}; do
  case $version in
    45) bpy45_venv ;;
    51) bpy51_venv ;;
    *) log "unknown Blender version $version (45 or 51)" >&2; exit 2 ;;
  esac
  py=.venv-bpy$version/bin/python
  log "Blender $("$py" -c 'import importlib.metadata as m; print(m.version("bpy"))') (Python $("$py" -c 'import sys; print(sys.version.split()[0])'))"
  user=$(mktemp -d -t sdf-blender-user-XXXXXX)
  out=$(mktemp -t sdf-blender-pytest-XXXXXX)
  set +e
  BLENDER_USER_RESOURCES=$user SDF_EXTENSION_ZIP=$PWD/$ZIP \
    "$py" -m pytest -p no:cacheprovider -q tests/blender "$@" 2>&1 | tee "$out"
  rc=${PIPESTATUS[0]}
  set -e
  summary=$(tail -n 1 "$out")
  count() { echo "$summary" | { grep -oE "[0-9]+ ($1)" || true; } | awk '{s += $1} END {print s + 0}'; }
  passed=$((passed + $(count passed)))
  failed=$((failed + $(count 'failed|errors?')))
  [ "$rc" -eq 0 ] || [ "$(count 'failed|errors?')" -gt 0 ] || failed=$((failed + 1))  # crashed
  [ "$rc" -eq 0 ] || status=1
  rm -rf "$user" "$out"
done
echo "blender: $passed passed, $failed failed"
exit $status
