# SPDX-License-Identifier: GPL-3.0-or-later
"""Meshes of polygons (triangles, quads, pentagons) written by hand as OBJ, OFF and ASCII PLY
(trimesh writes triangles only), and how they fan into triangles in place."""

import numpy as np


def prism():
    """A closed pentagonal prism, outward: two pentagons, four quads and a quad split in two
    triangles, in a mixed order; (vertices, polygons)."""
    angles = 2 * np.pi * np.arange(5) / 5
    ring = np.column_stack([np.cos(angles), np.sin(angles)])
    vertices = np.vstack(
        [np.column_stack([ring, np.zeros(5)]), np.column_stack([ring, np.ones(5)])]
    )
    sides = [[k, (k + 1) % 5, (k + 1) % 5 + 5, k + 5] for k in range(5)]
    polygons = [
        sides[0],
        [4, 3, 2, 1, 0],
        sides[1],
        [sides[2][0], sides[2][1], sides[2][2]],
        [sides[2][0], sides[2][2], sides[2][3]],
        [5, 6, 7, 8, 9],
        sides[3],
        sides[4],
    ]
    return vertices, polygons


def fanned(polygons):
    """(triangles, source face of each) of the polygons fanned in place: (0, j, j + 1)."""
    triangles, source = [], []
    for index, polygon in enumerate(polygons):
        for j in range(1, len(polygon) - 1):
            triangles.append([polygon[0], polygon[j], polygon[j + 1]])
            source.append(index)
    return np.array(triangles), np.array(source)


def write_polygons(path, vertices, polygons, uvs=None):
    """OBJ, OFF and ASCII PLY by hand (trimesh writes triangles only); with uvs, each vertex's
    (x + 2, y + 3) as OBJ vt, as PLY per-vertex s and t (uvs="vertex") or as a PLY per-face
    texcoord list (uvs="corner")."""
    suffix = path.suffix
    uv = [f"{x + 2!r} {y + 3!r}" for x, y, _ in vertices.tolist()]
    rows = [" ".join(map(repr, v)) for v in vertices.tolist()]
    if suffix == ".obj":
        lines = [f"v {row}" for row in rows] + ([f"vt {t}" for t in uv] if uvs else [])
        lines += [
            "f " + " ".join(f"{i + 1}/{i + 1}" if uvs else str(i + 1) for i in polygon)
            for polygon in polygons
        ]
    elif suffix == ".off":
        lines = ["OFF", f"{len(vertices)} {len(polygons)} 0", *rows]
        lines += [" ".join(map(str, [len(p), *p])) for p in polygons]
    else:
        per_vertex = "property double s\nproperty double t\n" if uvs == "vertex" else ""
        per_corner = "property list uchar float texcoord\n" if uvs == "corner" else ""
        header = (
            f"ply\nformat ascii 1.0\nelement vertex {len(vertices)}\nproperty double x\n"
            f"property double y\nproperty double z\n{per_vertex}element face "
            f"{len(polygons)}\nproperty list uchar int vertex_indices\n{per_corner}"
            "end_header"
        )
        lines = [header]
        lines += [f"{row} {t}" if per_vertex else row for row, t in zip(rows, uv)]
        for p in polygons:
            corners = " ".join(map(str, [len(p), *p]))
            if per_corner:
                corners += f" {2 * len(p)} " + " ".join(uv[i] for i in p)
            lines.append(corners)
    path.write_text("\n".join(lines) + "\n")


def cube_of_quads():
    vertices = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1],
                         [1, 1, 1], [0, 1, 1]], dtype=np.float64)  # fmt: skip
    quads = [[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7]]
    return vertices, quads
