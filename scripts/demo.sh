#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# The demo: set-up, then the SDF of a real mesh kept in the repository, written as a coloured
# mesh and the raw values into out/, and a picture of it rendered by Blender (bpy from PyPI,
# with the extension installed into a user directory of the demo's own).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
mkdir -p out
MESH=${1:-tests/data/bunny00.off}
name=$(basename "${MESH%.*}")
.venv/bin/shape-diameter "$MESH" -o "out/$name.sdf.ply" --values "out/$name.sdf.npy" --json

SDF_WHEELS=cp311 bash scripts/build_extension.sh  # Blender 4.5 renders: Python 3.11 alone
source scripts/blender_venv.sh
bpy45_venv
ZIP=$(ls -t dist/shape_diameter-*-linux_x64.zip | head -1)
export BLENDER_USER_RESOURCES=$PWD/build/demo-blender-user
rm -rf "$BLENDER_USER_RESOURCES" && mkdir -p "$BLENDER_USER_RESOURCES"
.venv-bpy45/bin/python -c "import bpy, sys; bpy.ops.extensions.package_install_files(filepath=sys.argv[1], repo='user_default', enable_on_install=True)" "$ZIP" >/dev/null
.venv-bpy45/bin/python examples/blender/render_sdf.py -- "$MESH" "out/$name.sdf.png"
echo "demo: wrote out/$name.sdf.ply (coloured by SDF), out/$name.sdf.npy (raw values) and out/$name.sdf.png (Blender's render)"
