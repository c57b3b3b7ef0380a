# SPDX-License-Identifier: GPL-3.0-or-later
"""Runs an installed shape_diameter on a mesh and writes what came out, for comparing builds.

Run by scripts/check_wheels.sh inside each platform's interpreter (native, under wine, under
qemu), with only numpy and the package installed: no mesh library, so the OFF file is read
here. compute() on the CPU engine with Fibonacci sampling (deterministic), then smooth()'s
k-ring and projected methods on its raw values; every array goes to OUTPUT.npz, the engine
string to OUTPUT.txt. Builds for the same mesh must give the same bytes.

    python wheel_values.py MESH.off OUTPUT [--expect-width N]
"""

import sys

import numpy as np


def read_off(path):
    with open(path) as f:
        words = f.read().split()
    if words[0] != "OFF":
        raise SystemExit(f"{path}: not an OFF file")
    nv, nf = int(words[1]), int(words[2])
    at = 4
    vertices = np.array(words[at : at + 3 * nv], dtype=np.float64).reshape(nv, 3)
    at += 3 * nv
    faces = np.array(words[at : at + 4 * nf], dtype=np.int64).reshape(nf, 4)
    if not (faces[:, 0] == 3).all():
        raise SystemExit(f"{path}: only triangles are read here")
    return vertices, faces[:, 1:].astype(np.int32)


def main(argv):
    mesh, output = argv[1], argv[2]
    width = int(argv[4]) if len(argv) > 4 and argv[3] == "--expect-width" else None
    import shape_diameter as sd

    vertices, triangles = read_off(mesh)
    result = sd.compute(vertices, triangles, sampling="fibonacci", engine="cpu")
    arrays = {"raw": result.raw, "values": result.values, "normalized": result.normalized}
    for method in ("kring", "projected"):
        arrays[method] = sd.smooth(vertices, triangles, result.raw, method, engine="cpu")
    np.savez(output + ".npz", **arrays)
    with open(output + ".txt", "w") as f:
        f.write(result.engine + "\n")
    print(f"{sd._core.__file__}: {result.engine}, {len(result.raw)} faces")
    if width is not None and f"{width}-wide" not in result.engine:
        raise SystemExit(f"expected the {width}-wide tree, the engine says {result.engine!r}")


if __name__ == "__main__":
    main(sys.argv)
