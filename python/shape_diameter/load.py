# SPDX-License-Identifier: GPL-3.0-or-later
"""shape_diameter.load_mesh: mesh files read as the command line reads them, for scripts.

trimesh (the ``cli`` extra) is imported on the first call, never by ``import shape_diameter``.
"""

from __future__ import annotations

import os


def load_mesh(path, *, source_faces: bool = False, uvs: bool = False):
    """Read a mesh file as the command line does: returns (vertices float64 (n, 3),
    triangles int64 (m, 3), 0-based), ready for compute(); with source_faces=True also
    int64 (m,): the 0-based index of the file's face each triangle comes from; with uvs=True
    also (last) the texture coordinates of every triangle corner, float32 (m, 3, 2) (corner k
    of triangle i at [i, k], v = 0 at the bottom of the image), ready for compute()'s and
    smooth()'s `uvs` (texture smoothing), or None when the file has none for every face. UVs
    are read from OBJ ``vt``, glTF/GLB ``TEXCOORD_0`` (of primitives with a material) and PLY
    texture coordinates (texture_u/texture_v, u/v, s/t, or a per-face texcoord list); OFF and
    STL have none.

    Reads .obj, .ply, .off, .stl, .gltf and .glb (the suffix names the format). Vertices
    come in the file's order (STL: corners at the same position merged, numbered by first
    use; glTF/GLB: every mesh node of the scene with its transform applied, in the file's
    order: depth first, roots in the scene's order, a node before its children, a mesh's
    primitives in order).
    Triangles come in the file's face order, each polygon of k corners fanned in place into
    k - 2 consecutive triangles (corners 0, j, j + 1), so compute()'s per-face values for
    face i of the file are the rows where source_faces == i. (OBJ faces are counted over its
    ``f`` records; STL and glTF faces are triangles already.) The command line's --values rows
    follow these triangles (or the vertices).

    Raises ValueError naming the file when it is missing, not of its suffix's format,
    truncated, or holds no triangles; ImportError when trimesh is not installed
    (pip install "shape_diameter[cli]").
    """
    try:
        from . import mesh_io
    except ImportError as exc:
        raise ImportError(
            f"shape_diameter.load_mesh reads files with trimesh: pip install "
            f"'shape_diameter[cli]' ({exc})"
        ) from exc
    path = os.fsdecode(path)  # bytes too (os.walk(b'...') on names that are not UTF-8)
    if uvs:
        return mesh_io.load_mesh_with_uvs(path, source_faces=source_faces)
    return mesh_io.load_mesh(path, source_faces=source_faces)
