# SPDX-License-Identifier: GPL-3.0-or-later
"""Seed corpora for the fuzzers, from the real meshes in tests/data and a few made by hand.

    python tests/fuzz/make_corpus.py OUT_DIR

writes OUT_DIR/compute/*.bin (compute_fuzzer.cpp's input layout) and OUT_DIR/mesh_io/*.bin
(mesh_io_fuzzer.py's: a selector byte, then the file). Real meshes are cut to patches of
about a hundred faces, so that one run of the target stays in the milliseconds. Deterministic:
the same files every time.
"""

from __future__ import annotations

import struct
import sys
from pathlib import Path

import numpy as np
import trimesh

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(Path(__file__).resolve().parent))

from mesh_io_fuzzer import SUFFIXES
from shape_diameter.mesh_io import load_mesh

DATA = ROOT / "tests" / "data"


# --- meshes -----------------------------------------------------------------------------


def _patch(name: str, faces: int):
    """The `faces` triangles nearest the mesh's first vertex, re-indexed: a connected-looking
    piece of a real surface, open along its border."""
    vertices, triangles = load_mesh(DATA / name)
    centroids = vertices[triangles].mean(axis=1)
    nearest = np.argsort(np.linalg.norm(centroids - vertices[triangles[0, 0]], axis=1))[:faces]
    used, inverse = np.unique(triangles[np.sort(nearest)], return_inverse=True)
    return vertices[used], inverse.reshape(-1, 3)


def meshes():
    """(name, vertices, triangles): closed and open, tiny and real."""
    tetra_v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
    tetra_t = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    box = trimesh.creation.box()
    sphere = trimesh.creation.icosphere(subdivisions=1)
    out = [
        ("tetra", tetra_v, tetra_t),
        ("box", np.asarray(box.vertices), np.asarray(box.faces)),
        ("sphere", np.asarray(sphere.vertices), np.asarray(sphere.faces)),
        ("square", tetra_v[:3].copy(), np.array([[0, 1, 2]])),
    ]
    for name, faces in (
        ("suzanne.obj", 120),
        ("spot.obj", 100),
        ("fandisk.obj", 100),
        ("bunny00.off", 80),
        ("armadillo.off", 80),
    ):
        v, t = _patch(name, faces)
        out.append((name.split(".")[0], v, t))
    return out


# --- compute_fuzzer.cpp inputs ----------------------------------------------------------


def compute_input(
    vertices, triangles, *, rays=30, cone=None, flags=0, more=0, seed=0, grid=False
) -> bytes:
    """compute_fuzzer.cpp's layout. grid: coordinates on its 1/8 grid (one byte each, the
    mesh scaled into +-14), else exact doubles (nine bytes each)."""
    cone_byte = 174 if cone is None else cone  # about 120 degrees
    header = struct.pack(
        "<BBBBIbbH", (rays - 1) % 64, cone_byte, flags, more, seed, 0, 0, len(vertices)
    )
    body = bytearray()
    if grid:
        lo, hi = vertices.min(axis=0), vertices.max(axis=0)
        scaled = (vertices - 0.5 * (lo + hi)) * (28.0 / max(float((hi - lo).max()), 1e-30))
        for c in np.clip(np.round(scaled * 8) + 120, 0, 0xEF).astype(int).reshape(-1):
            body.append(int(c))
    else:
        for c in np.asarray(vertices, dtype=np.float64).reshape(-1):
            body += b"\xff" + struct.pack("<d", c)
    for i in np.asarray(triangles).reshape(-1):
        body += struct.pack("<H", int(i))
    return header + bytes(body)


def compute_corpus():
    for name, v, t in meshes():
        yield f"{name}-bvh", compute_input(v, t)
        yield f"{name}-grid-octree", compute_input(v, t, flags=8 | (4 << 5), more=3, grid=True)
        yield f"{name}-vertices-random", compute_input(v, t, rays=16, flags=4 | 1 | 16, seed=7)
        yield f"{name}-cgal", compute_input(v, t, rays=10, flags=2, grid=True)


# --- mesh_io_fuzzer.py inputs -----------------------------------------------------------


def _obj_text(vertices, triangles, *, uvs=True, quads=False, negative=False) -> str:
    lines = ["# a comment", "mtllib nothing.mtl", "o piece", "g group"]
    lines += [f"v {x:.6g} {y:.6g} {z:.6g}" for x, y, z in vertices]
    if uvs:
        lines += [f"vt {0.5 + 0.4 * x:.4g} {0.5 + 0.4 * y:.4g}" for x, y, _ in vertices]
    lines += ["vn 0 0 1", "usemtl m", "s 1"]
    n = len(vertices)
    for a, b, c in triangles:
        refs = [a + 1, b + 1, c + 1]
        if negative:
            refs = [r - n - 1 for r in refs]
        corners = [f"{r}/{r}/1" if uvs else f"{r}//1" for r in refs]
        lines.append("f " + " ".join(corners))
    if quads:
        lines.append("f 1 2 3 4")
        lines.append("f 1 2 \\\n 3")
        lines.append("l 1 2")
    return "\n".join(lines) + "\n"


def _export(mesh, file_type: str, **kwargs) -> bytes:
    data = mesh.export(file_type=file_type, **kwargs)
    if isinstance(data, dict):  # glTF: the one file, buffers embedded
        (data,) = data.values()
    return data.encode() if isinstance(data, str) else bytes(data)


def mesh_io_corpus():
    index = {suffix: i for i, suffix in enumerate(SUFFIXES)}
    with_uvs = 8  # the selector bit for load_mesh_with_uvs
    # Small files: the tiny meshes and a 40-face piece of a real one.
    for name, v, t in meshes()[:4] + [("suzanne", *_patch("suzanne.obj", 40))]:
        mesh = trimesh.Trimesh(v, t, process=False)
        textured = trimesh.Trimesh(
            v,
            t,
            process=False,
            visual=trimesh.visual.TextureVisuals(
                uv=0.5 + 0.4 * v[:, :2],
                # A material with no image: glTF keeps UVs only with one, images need Pillow.
                material=trimesh.visual.material.PBRMaterial(baseColorFactor=[200, 0, 0, 255]),
            ),
        )
        yield f"{name}.obj", index[".obj"], _obj_text(v, t).encode()
        yield (
            f"{name}-quads-negative.obj",
            index[".obj"] | with_uvs,
            _obj_text(v, t, quads=True, negative=True).encode(),
        )
        yield f"{name}-binary.ply", index[".ply"], _export(mesh, "ply")
        yield (
            f"{name}-ascii.ply",
            index[".ply"] | with_uvs,
            _export(textured, "ply", encoding="ascii"),
        )
        yield f"{name}.off", index[".off"], _export(mesh, "off")
        yield f"{name}-binary.stl", index[".stl"], _export(mesh, "stl")
        yield f"{name}-ascii.stl", index[".stl"], _export(mesh, "stl_ascii")
        yield f"{name}.glb", index[".glb"] | with_uvs, _export(textured, "glb")
        scene = trimesh.Scene()
        scene.add_geometry(mesh, transform=np.diag([-1.0, 2.0, 1.0, 1.0]))
        scene.add_geometry(trimesh.PointCloud(v))
        yield f"{name}-scene.glb", index[".glb"], _export(scene, "glb")
        yield (
            f"{name}.gltf",
            index[".gltf"] | with_uvs,
            _export(textured, "gltf", embed_buffers=True),
        )
    yield (
        "off-polygons.off",
        index[".off"],
        (b"OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n3 0 1 2 255 0 0\n"),
    )
    yield (
        "coff.off",
        index[".off"],
        (b"COFF\n3 1 0\n0 0 0 1 2 3 4\n1 0 0 1 2 3 4\n0 1 0 1 2 3 4\n3 0 1 2\n"),
    )
    yield (
        "points.ply",
        index[".ply"],
        (
            b"ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
            b"property float z\nend_header\n0 0 0\n1 1 1\n"
        ),
    )


def main(argv):
    if len(argv) != 2:
        print(__doc__)
        return 2
    out = Path(argv[1])
    (out / "compute").mkdir(parents=True, exist_ok=True)
    (out / "mesh_io").mkdir(parents=True, exist_ok=True)
    count = 0
    for name, data in compute_corpus():
        (out / "compute" / f"seed-{name}.bin").write_bytes(data)
        count += 1
    for name, selector, data in mesh_io_corpus():
        (out / "mesh_io" / f"seed-{name}.bin").write_bytes(bytes([selector]) + data)
        count += 1
    print(f"make_corpus: {count} seeds in {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
