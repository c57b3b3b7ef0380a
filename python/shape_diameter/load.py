# SPDX-License-Identifier: GPL-3.0-or-later
"""shape_diameter.load_mesh: mesh files read as the command line reads them, for scripts.

trimesh (the ``cli`` extra) is imported on the first call, never by ``import shape_diameter``.
"""

from __future__ import annotations


def load_mesh(path, *, source_faces: bool = False):
    """Read a mesh file as the command line does: returns (vertices float64 (n, 3),
    triangles int64 (m, 3), 0-based), ready for compute(); with source_faces=True also
    int64 (m,): the 0-based index of the file's face each triangle comes from.

    Reads .obj, .ply, .off, .stl, .gltf and .glb (the suffix names the format). Vertices
    come in the file's order (STL: corners at the same position merged, numbered by first
    use; glTF/GLB: every mesh of the scene with its transform applied, in scene order).
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
    return mesh_io.load_mesh(path, source_faces=source_faces)
