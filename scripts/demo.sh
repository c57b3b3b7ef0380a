#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# The demo: set-up, then the SDF of a real mesh kept in the repository, written as a coloured
# mesh and the raw values into out/.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
mkdir -p out
MESH=${1:-tests/data/bunny00.off}
name=$(basename "${MESH%.*}")
.venv/bin/shape-diameter "$MESH" -o "out/$name.sdf.ply" --values "out/$name.sdf.npy" --json
echo "demo: wrote out/$name.sdf.ply (coloured by SDF) and out/$name.sdf.npy (raw values)"
