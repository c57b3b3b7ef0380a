# SPDX-License-Identifier: GPL-3.0-or-later
"""Analytic test meshes as numpy arrays: vertices float64 (n, 3), triangles int64 (m, 3),
closed, with outward counter-clockwise winding (the engine's convention).

Every builder is vectorised: the largest meshes the tests use (an icosphere of about 80k faces)
must cost well under a second to make on a shared two-core machine. Results are cached, so
callers must not modify the returned arrays in place (copy first).
"""

from __future__ import annotations

from functools import cache

import numpy as np

_PHI = (1.0 + 5.0**0.5) / 2.0

# The regular icosahedron, vertices (0, +-1, +-phi) and cyclic permutations. The vertex set is
# closed under negation, and so are its subdivisions (a midpoint of two antipodal vertices'
# images is the negated midpoint, and normalising is sign-symmetric), which keeps the bounding
# box centred exactly on the origin.
_ICO_VERTICES = np.array(
    [
        [-1, _PHI, 0], [1, _PHI, 0], [-1, -_PHI, 0], [1, -_PHI, 0],
        [0, -1, _PHI], [0, 1, _PHI], [0, -1, -_PHI], [0, 1, -_PHI],
        [_PHI, 0, -1], [_PHI, 0, 1], [-_PHI, 0, -1], [-_PHI, 0, 1],
    ],
    dtype=np.float64,
)  # fmt: skip
_ICO_TRIANGLES = np.array(
    [
        [0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11],
        [1, 5, 9], [5, 11, 4], [11, 10, 2], [10, 7, 6], [7, 1, 8],
        [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8], [3, 8, 9],
        [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1],
    ],
    dtype=np.int64,
)  # fmt: skip


@cache
def _unit_icosphere(subdivisions: int) -> tuple[np.ndarray, np.ndarray]:
    v = _ICO_VERTICES / np.linalg.norm(_ICO_VERTICES, axis=1, keepdims=True)
    t = _ICO_TRIANGLES.copy()
    for _ in range(subdivisions):
        # One midpoint per undirected edge: the three edges of every triangle, deduplicated.
        edges = np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]])
        unique, inverse = np.unique(np.sort(edges, axis=1), axis=0, return_inverse=True)
        inverse = inverse.reshape(-1)
        mid = 0.5 * (v[unique[:, 0]] + v[unique[:, 1]])
        mid /= np.linalg.norm(mid, axis=1, keepdims=True)
        m = len(t)
        ab, bc, ca = (inverse[k * m : (k + 1) * m] + len(v) for k in range(3))
        a, b, c = t[:, 0], t[:, 1], t[:, 2]
        # The four children keep the parent's orientation.
        t = np.concatenate(
            [
                np.stack([a, ab, ca], axis=1),
                np.stack([ab, b, bc], axis=1),
                np.stack([ca, bc, c], axis=1),
                np.stack([ab, bc, ca], axis=1),
            ]
        )
        v = np.concatenate([v, mid])
    return v, t


def icosphere(radius: float = 1.0, subdivisions: int = 3) -> tuple[np.ndarray, np.ndarray]:
    """A sphere of the given radius centred on the origin: the icosahedron subdivided
    `subdivisions` times (20 * 4**subdivisions triangles), every vertex on the sphere."""
    v, t = _unit_icosphere(int(subdivisions))
    return v * float(radius), t.copy()


def box(sx: float, sy: float, sz: float, divisions=1) -> tuple[np.ndarray, np.ndarray]:
    """A closed axis-aligned box of size (sx, sy, sz) centred on the origin, each of its six
    faces a grid of quads split in two triangles.

    divisions: cells along every edge (an int), or (nx, ny, nz), cells along x, y and z. A wide
    thin slab with fine top and bottom is box(20, 20, 1, (40, 40, 1)).
    """
    if np.ndim(divisions) == 0:
        divisions = (int(divisions),) * 3
    n = np.array(divisions, dtype=np.int64)
    if n.shape != (3,) or (n < 1).any():
        raise ValueError("divisions must be a positive int or three positive ints")
    size = np.array([sx, sy, sz], dtype=np.float64)

    # Vertices are the lattice points (i, j, k) on the boundary of [0, nx] x [0, ny] x [0, nz],
    # so edges and corners shared by two or three faces are one vertex by construction.
    grid = np.stack(np.meshgrid(*(np.arange(k + 1) for k in n), indexing="ij"), axis=-1)
    on_boundary = ((grid == 0) | (grid == n)).any(axis=-1)
    index = np.full(on_boundary.shape, -1, dtype=np.int64)
    index[on_boundary] = np.arange(int(on_boundary.sum()))
    lattice = grid[on_boundary]
    vertices = -0.5 * size + lattice * (size / n)

    triangles = []
    for axis in range(3):
        # (axis, u, v) is a right-handed cyclic order, so a quad walked +u then +v turns
        # counter-clockwise seen from the +axis side.
        u, v = (axis + 1) % 3, (axis + 2) % 3
        iu, iv = np.meshgrid(np.arange(n[u]), np.arange(n[v]), indexing="ij")
        iu, iv = iu.reshape(-1), iv.reshape(-1)
        for side in (0, n[axis]):
            corners = []
            for du, dv in ((0, 0), (1, 0), (1, 1), (0, 1)):
                ijk = [None, None, None]
                ijk[axis], ijk[u], ijk[v] = np.full_like(iu, side), iu + du, iv + dv
                corners.append(index[ijk[0], ijk[1], ijk[2]])
            a, b, c, d = corners
            tri = np.concatenate([np.stack([a, b, c], axis=1), np.stack([a, c, d], axis=1)])
            if side == 0:
                tri = tri[:, ::-1]  # the face on the -axis side looks the other way
            triangles.append(tri)
    return vertices, np.ascontiguousarray(np.concatenate(triangles), dtype=np.int64)


def cylinder(
    radius: float = 1.0, length: float = 2.0, segments: int = 64, rings: int = 1
) -> tuple[np.ndarray, np.ndarray]:
    """A closed cylinder along z, centred on the origin: a prism with `segments` sides whose
    vertices lie on the circle of the given radius, cut into `rings` bands along its length,
    closed by two fans around a centre vertex.

    Side vertex (k, j) sits at angle 2 pi k / segments and z = -length/2 + j length/rings."""
    segments, rings = int(segments), int(rings)
    angle = 2.0 * np.pi * np.arange(segments) / segments
    z = -0.5 * length + length * np.arange(rings + 1) / rings
    ring_xy = np.stack([radius * np.cos(angle), radius * np.sin(angle)], axis=1)
    side = np.concatenate([np.column_stack([ring_xy, np.full(segments, zj)]) for zj in z])
    bottom_centre = len(side)
    top_centre = bottom_centre + 1
    vertices = np.concatenate([side, [[0.0, 0.0, -0.5 * length], [0.0, 0.0, 0.5 * length]]])

    k = np.arange(segments)
    k1 = (k + 1) % segments
    triangles = []
    for j in range(rings):
        a, b = j * segments + k, j * segments + k1
        c, d = (j + 1) * segments + k1, (j + 1) * segments + k
        # Walking +angle then +z turns counter-clockwise seen from outside (theta x z = r).
        triangles += [np.stack([a, b, c], axis=1), np.stack([a, c, d], axis=1)]
    top = rings * segments
    triangles.append(np.stack([np.full(segments, top_centre), top + k, top + k1], axis=1))
    triangles.append(np.stack([np.full(segments, bottom_centre), k1, k], axis=1))
    return vertices, np.ascontiguousarray(np.concatenate(triangles), dtype=np.int64)


def signed_volume(vertices: np.ndarray, triangles: np.ndarray) -> float:
    """Volume enclosed by a closed mesh; positive when its normals point outward."""
    a, b, c = (vertices[triangles[:, k]] for k in range(3))
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)


def edge_use_counts(triangles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(undirected edge use counts, directed edge use counts) over all triangle edges."""
    directed = np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]])
    _, undirected_counts = np.unique(np.sort(directed, axis=1), axis=0, return_counts=True)
    _, directed_counts = np.unique(directed, axis=0, return_counts=True)
    return undirected_counts, directed_counts


def face_normals(vertices: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Unit outward normals of the triangles (counter-clockwise winding)."""
    a, b, c = (vertices[triangles[:, k]] for k in range(3))
    n = np.cross(b - a, c - a)
    return n / np.linalg.norm(n, axis=1, keepdims=True)
