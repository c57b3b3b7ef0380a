# SPDX-License-Identifier: GPL-3.0-or-later
"""Writes a benchmark mesh (bench/meshes.py) as cuda_cast's MESH.bin: int64 vertex count, int64
face count, float64 vertices, int64 faces. The vertices go through float32 first, as
bench/opencl_vs_cpu.py hands them to compute(). Usage: mesh_bin.py NAME OUT.bin"""
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from meshes import DATA, read_off, subdivide  # noqa: E402

name, out = sys.argv[1], sys.argv[2]
base, _, times = name.partition("-x")
v, f = read_off(DATA / f"{base}.off")
for _ in range({"": 0, "4": 1, "16": 2}[times]):
    v, f = subdivide(v, f)
v = np.ascontiguousarray(v, np.float32).astype(np.float64)
with open(out, "wb") as fh:
    np.array([len(v), len(f)], np.int64).tofile(fh)
    v.tofile(fh)
    np.ascontiguousarray(f, np.int64).tofile(fh)
print(f"{name}: {len(v)} vertices, {len(f)} faces -> {out}")
