# SPDX-License-Identifier: GPL-3.0-or-later
# Sourced by the scripts that need Blender as a Python module (bpy from PyPI): makes, once,
#   .venv-bpy45  bpy 4.5 LTS, Python 3.11, numpy < 2 (bpy 4.x does not pin it)
#   .venv-bpy51  bpy >= 5.1, Python 3.13, numpy 2.x
# and remakes one when its requirements change. PY311 and PY313 name the interpreters.
source "$(dirname "${BASH_SOURCE[0]}")/pythons.sh"

venv() {  # venv DIR PYTHON REQUIREMENT...
  local dir=$1 python=$2
  shift 2
  local want="$*"
  if [ ! -x "$dir/bin/python" ] || [ "$(cat "$dir/.requirements" 2>/dev/null)" != "$want" ]; then
    echo "blender_venv: creating $dir: $want"
    rm -rf "$dir"
    "$python" -m venv "$dir"
    "$dir/bin/python" -m pip install -q --upgrade pip
    "$dir/bin/python" -m pip install -q "$@"
    echo "$want" > "$dir/.requirements"
  fi
}

bpy45_venv() {  # as in build_extension.sh
  need_python PY311 3.11 "bpy 4.5"
  venv .venv-bpy45 "$PY311" "bpy>=4.5,<4.6" "numpy<2" "pytest>=7"
}
bpy51_venv() {
  need_python PY313 3.13 "bpy 5.1 and later"
  venv .venv-bpy51 "$PY313" "bpy>=5.1" "pytest>=7"
}
