# SPDX-License-Identifier: GPL-3.0-or-later
"""The benchmark's meshes: real ones from tests/data and larger ones made by subdividing a
real mesh 1-to-4 (like the paper's Table 1 sizes). numpy only, so the benchmark also runs on
machines without the command line's mesh library."""

from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "tests" / "data"
CACHE = ROOT / "build" / "bench-meshes"


def read_off(path):
    """(vertices float64 (n,3), triangles int64 (m,3)) from a triangle OFF file."""
    with open(path) as f:
        words = f.read().split()
    assert words[0] == "OFF", f"{path} is not an OFF file"
    nv, nf = int(words[1]), int(words[2])
    values = np.array(words[4 : 4 + 3 * nv], dtype=np.float64).reshape(nv, 3)
    faces = np.array(words[4 + 3 * nv : 4 + 3 * nv + 4 * nf], dtype=np.int64).reshape(nf, 4)
    assert (faces[:, 0] == 3).all(), f"{path} has faces that are not triangles"
    return values, faces[:, 1:]


def write_off(path, vertices, triangles):
    with open(path, "w") as f:
        f.write(f"OFF\n{len(vertices)} {len(triangles)} 0\n")
        np.savetxt(f, vertices, fmt="%.9g")
        np.savetxt(f, np.c_[np.full(len(triangles), 3), triangles], fmt="%d")


def subdivide(vertices, triangles):
    """1-to-4 midpoint subdivision: every edge gets one new vertex, shared by both faces."""
    edges = np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]])
    key = np.sort(edges, axis=1)
    unique, inverse = np.unique(key, axis=0, return_inverse=True)
    inverse = inverse.reshape(-1)
    mid = len(vertices) + inverse.reshape(3, -1).T  # per face: midpoints of edges 01, 12, 20
    new_vertices = np.concatenate([vertices, vertices[unique].mean(axis=1)])
    a, b, c = triangles.T
    ab, bc, ca = mid.T
    new_triangles = np.concatenate(
        [np.c_[a, ab, ca], np.c_[ab, b, bc], np.c_[ca, bc, c], np.c_[ab, bc, ca]]
    )
    return new_vertices, new_triangles


# The names benchmark_meshes() gives, smallest first.
NAMES = (
    "ChineseDragon-10kv",
    "armadillo",
    "bunny00",
    "armadillo-x4",
    "armadillo-x16",
    "bunny00-x16",
)


def benchmark_meshes(largest=True):
    """[(name, vertices, triangles)]: three real meshes and subdivisions up to 1.2M faces."""
    CACHE.mkdir(parents=True, exist_ok=True)
    meshes = []
    for name in ("ChineseDragon-10kv", "armadillo", "bunny00"):
        meshes.append((name, *read_off(DATA / f"{name}.off")))
    derived = [("armadillo-x4", "armadillo", 1), ("armadillo-x16", "armadillo", 2)]
    if largest:
        derived.append(("bunny00-x16", "bunny00", 2))
    for name, base, times in derived:
        cached = CACHE / f"{name}.npz"
        if cached.exists():
            z = np.load(cached)
            meshes.append((name, z["vertices"], z["triangles"]))
            continue
        v, t = read_off(DATA / f"{base}.off")
        for _ in range(times):
            v, t = subdivide(v, t)
        np.savez(cached, vertices=v, triangles=t)
        meshes.append((name, v, t))
    return meshes


def off_path(name, vertices, triangles):
    """An OFF file of the mesh for the reference programs (written once, then reused)."""
    path = CACHE / f"{name}.off"
    if not path.exists():
        CACHE.mkdir(parents=True, exist_ok=True)
        write_off(path, vertices, triangles)
    return path
