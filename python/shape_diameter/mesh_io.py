# SPDX-License-Identifier: GPL-3.0-or-later
"""Mesh files in and out for the command line, through trimesh.

This module imports trimesh, an optional dependency (the ``cli`` extra), so the
package's ``__init__`` must never import it.

Reading keeps the file's own numbering wherever the format has one, because the
values written with ``--values`` are indexed by it: polygons are fanned in place (a face
of k corners gives k - 2 consecutive triangles (0, j, j + 1), in the file's face order), and
load_mesh(source_faces=True) says which face each triangle comes from.

* OBJ: vertices in file order (none split or merged), faces in file order. trimesh on its own
  splits vertices at UV and normal seams and moves the second half of every quad to the end,
  so the file is first reduced to its ``v`` and ``f`` records (see ``_plain_obj``).
* PLY: vertices as stored, faces fanned here from the elements trimesh read (its own
  triangles come grouped by polygon size). trimesh reads binary PLY lists of one length only
  (a binary file mixing triangles and quads is refused).
* OFF: read here (trimesh groups the pieces by polygon size, and fails on polygons of more
  than four corners).
* STL: a triangle soup by design, so corners at the same position are merged
  (in order of first use) to give the mesh back its connectivity; triangle order
  is kept.
* glTF/GLB: every mesh node of the scene, with its transform applied, in the file's
  order (depth first: roots in the scene's order, a node before its children, a mesh's
  primitives in order; see ``gltf_order``); vertices as stored in each primitive.
"""

from __future__ import annotations

import io
import os

import numpy as np
import trimesh

from .gltf_checks import check_gltf
from .gltf_order import json_header, mesh_nodes_in_file_order
from .mesh_file_checks import check_complete, check_suffix, format_name, off_sections
from .output_files import written_whole
from .warning_log import warn

# Formats ``save_colored`` writes. PLY, OBJ and OFF go through our own writers: trimesh's
# PLY holds float32 coordinates, its OBJ 8 fixed decimals, and its OFF drops colours. STL has
# no colour at all.
WRITE_SUFFIXES = (".ply", ".obj", ".off", ".glb", ".stl")


def load_mesh(path, *, source_faces: bool = False):
    """Read a mesh file as (vertices float64 (n,3), triangles int64 (m,3)).

    Triangles come in the file's face order, each polygon of k corners fanned in place into
    k - 2 consecutive triangles (corners 0, j, j + 1); with source_faces=True a third array
    comes back: int64 (m,), the 0-based index of the file's face each triangle comes from
    (OBJ: its ``f`` records, counted in order; PLY and OFF: its face elements; STL, glTF and
    GLB: the triangle's own index, their faces being triangles).

    Raises ValueError naming the file for a missing, unreadable or empty file,
    and for one that holds no triangles (a point cloud, a set of lines).
    """
    vertices, triangles, source, _ = _read(path)
    return (vertices, triangles, source) if source_faces else (vertices, triangles)


def load_mesh_with_uvs(path, *, source_faces: bool = False):
    """load_mesh, plus the texture coordinates of every face corner.

    Returns (vertices, triangles, uvs), or with source_faces=True (vertices, triangles,
    source, uvs) (source as load_mesh gives it): uvs float32 (m, 3, 2), corner k of triangle i at
    uvs[i, k], with v = 0 at the bottom of the image (OBJ and Blender's convention; glTF's
    top-down v is flipped by trimesh), or None when the file has no UVs for every face. Read
    from OBJ ``vt`` (through the ``f v/vt`` references, polygons fanned as load_mesh fans
    them), glTF/GLB ``TEXCOORD_0`` (of primitives that have a material: trimesh reads UVs only
    with one) and PLY texture coordinates (texture_u/texture_v, u/v, s/t or a per-face
    texcoord list). OFF and STL have none.
    """
    vertices, triangles, source, ply_uvs = _read(path, want_uvs=True)
    path = os.fspath(path)
    suffix = os.path.splitext(path)[1].lower()
    uvs = None
    if suffix == ".obj":
        uvs = _obj_corner_uvs(path)
    elif suffix == ".ply":
        uvs = ply_uvs
    elif suffix in (".gltf", ".glb"):
        try:
            # Materials are loaded this time: trimesh keeps glTF UVs only with them.
            scene = trimesh.load(path, process=False, force="scene")
        except Exception:  # e.g. a texture image that cannot be decoded: read without
            scene = trimesh.load(path, process=False, force="scene", skip_materials=True)
        uvs = _scene_corner_uvs(scene, mesh_nodes_in_file_order(json_header(path), scene))
    if uvs is not None and (uvs.shape != (len(triangles), 3, 2) or not np.isfinite(uvs).all()):
        uvs = None
    return (vertices, triangles, source, uvs) if source_faces else (vertices, triangles, uvs)


def _read(path, want_uvs: bool = False):
    """(vertices, triangles, source faces, PLY corner UVs or None) of a mesh file."""
    path = os.fspath(path)
    if not os.path.exists(path):
        if os.path.islink(path):
            raise ValueError(f"{path}: a link to nothing (it points to {os.readlink(path)})")
        raise ValueError(f"{path}: no such file")
    if not os.path.isfile(path):
        raise ValueError(f"{path}: not a file")
    try:
        suffix = check_suffix(path)
        check_complete(path, suffix)
    except ValueError as exc:
        raise ValueError(f"{path}: {exc}") from None
    except OSError as exc:  # e.g. no permission to read it
        raise ValueError(f"{path}: cannot read mesh ({exc.strerror or exc})") from exc
    uvs, other_kinds, header = None, set(), None
    try:
        if suffix == ".off":
            # Read here: trimesh groups an OFF's triangles by polygon size, and fails on
            # polygons of more than four corners.
            vertices, triangles, source = _read_off(path)
        elif suffix == ".obj":
            text, source, obj_has_lines = _plain_obj(path)
            scene = trimesh.load(
                io.BytesIO(text),
                file_type="obj",
                process=False,
                force="scene",
                maintain_order=True,
                skip_materials=True,
            )
        else:
            if suffix in (".gltf", ".glb"):
                header = json_header(path)
                check_gltf(header, uvs=want_uvs)
            # skip_materials: textures are irrelevant here, and decoding them
            # needs Pillow, which the ``cli`` extra does not pull in.
            scene = trimesh.load(path, process=False, force="scene", skip_materials=True)
    except ImportError as exc:
        # trimesh guesses the encoding of text that is not UTF-8 with charset_normalizer,
        # which it does not require: such bytes in a text format mean a broken file.
        raise ValueError(
            f"{path}: not a valid {format_name(suffix)} file (it is not text, or not UTF-8)"
        ) from exc
    except Exception as exc:  # a parser fed a broken file fails in many ways
        reason = str(exc) or type(exc).__name__
        if reason == "PLY is unexpected length!":  # trimesh's words; they do not say why
            reason = (
                "its size is not what its header declares: it is truncated, or mixes "
                "faces of different corner counts, which trimesh cannot read in binary "
                "PLY"
            )
        raise ValueError(f"{path}: cannot read mesh ({reason})") from exc

    if suffix != ".off":
        try:
            in_place = _ply_in_place(scene, want_uvs) if suffix == ".ply" else None
            if in_place is not None:
                vertices, triangles, source, uvs = in_place
            else:
                nodes = (
                    mesh_nodes_in_file_order(header, scene)
                    if header is not None
                    else scene.graph.nodes_geometry
                )
                vertices, triangles, other_kinds = _flatten(scene, nodes)
                if suffix != ".obj":  # (a PLY only where trimesh kept no elements: never seen)
                    source = np.arange(len(triangles), dtype=np.int64)
                elif len(source) != len(triangles):
                    raise ValueError(
                        f"{len(source) - len(triangles)} of its faces were lost in reading"
                    )
        except ValueError as exc:
            raise ValueError(f"{path}: cannot read mesh ({exc})") from exc
    if len(triangles) == 0:
        if suffix == ".obj" and obj_has_lines:  # its vertices alone reached trimesh
            other_kinds = {"lines"}
        found = f" (it holds {', '.join(sorted(other_kinds))})" if other_kinds else ""
        raise ValueError(f"{path}: no triangles found{found}")
    if suffix == ".stl":
        vertices, triangles = _merge_identical(vertices, triangles)
    _check_indices(path, vertices, triangles, source)
    return vertices, triangles, source, uvs


def _check_indices(path: str, vertices, triangles, source) -> None:
    """ValueError naming the first vertex that is not finite, or the first face that refers
    to a vertex the file does not have. (Looked for only when a whole-array test fails: the
    search costs ten times the test on a mesh of a million faces.)"""
    if np.isfinite(vertices).all() and (
        len(triangles) == 0 or (triangles.min() >= 0 and triangles.max() < len(vertices))
    ):
        return
    not_finite = np.flatnonzero(~np.isfinite(vertices).all(axis=1))
    if len(not_finite):  # numbered from 0, as the file's vertices are read
        count = "1 vertex has" if len(not_finite) == 1 else f"{len(not_finite)} vertices have"
        raise ValueError(
            f"{path}: {count} a coordinate that is not finite (NaN or infinite; "
            f"the first: vertex {not_finite[0]}, counting from 0)"
        )
    beyond = (triangles < 0) | (triangles >= len(vertices))
    outside = np.flatnonzero(beyond.any(axis=1))
    if len(outside):
        first = outside[0]
        face, index = int(source[first]), int(triangles[first][beyond[first]][0])
        raise ValueError(
            f"{path}: face {face} (counting from 0) refers to vertex {index}, but "
            f"the file has {len(vertices)} vertices (0 to {len(vertices) - 1})"
        )


def _fan(polygons):
    """Polygons (a 2D array, one row each, or a sequence of index arrays) fanned in place:
    (triangles int64 (t, 3), source int64 (t,)), polygon i of k corners giving triangles
    (0, j, j + 1) for j = 1 .. k - 2 at consecutive rows; fewer than 3 corners give none.
    Also returns the corner positions, (t, 3) indices into the polygons' corners laid end to
    end, for anything stored per corner (PLY's per-face UVs)."""
    if isinstance(polygons, np.ndarray) and polygons.ndim == 2 and polygons.shape[1] == 3:
        # Triangles already (as the command line writes PLY): each is its own, in place.
        count = len(polygons)
        corners = np.arange(3 * count, dtype=np.int64).reshape(count, 3)
        triangles = np.array(polygons, dtype=np.int64, order="C")
        return triangles, np.arange(count, dtype=np.int64), corners
    if isinstance(polygons, np.ndarray) and polygons.ndim == 2:
        sizes = np.full(len(polygons), polygons.shape[1], dtype=np.int64)
        flat = polygons.reshape(-1)
    else:
        sizes = np.fromiter((len(p) for p in polygons), dtype=np.int64, count=len(polygons))
        flat = (np.concatenate([np.asarray(p).reshape(-1) for p in polygons])
                if len(polygons) else np.zeros(0))  # fmt: skip
    starts = np.cumsum(sizes) - sizes
    counts = np.maximum(sizes - 2, 0)
    source = np.repeat(np.arange(len(sizes), dtype=np.int64), counts)
    step = np.arange(len(source), dtype=np.int64) - np.repeat(np.cumsum(counts) - counts, counts)
    first = starts[source]
    corners = np.stack([first, first + step + 1, first + step + 2], axis=1)
    return flat.astype(np.int64)[corners], source, corners


def _read_off(path: str):
    """An OFF file (check_complete has seen its header and counts): vertices as stored, each
    face fanned in place. Values after a vertex's first three (colours, normals, texture
    coordinates: COFF, NOFF, STOFF) and after a face's corners (colours) are skipped."""
    with open(path, "rb") as stream:
        _, counts, body = off_sections(stream.read().decode("utf-8"))
    vertex_count, face_count = int(counts[0]), int(counts[1])
    try:
        vertices = np.array([line.split()[:3] for line in body[:vertex_count]],
                            dtype=np.float64).reshape(vertex_count, 3)  # fmt: skip
    except ValueError:
        raise ValueError("malformed OFF vertex: not three numbers") from None
    polygons = []
    for line in body[vertex_count : vertex_count + face_count]:
        fields = line.split()
        try:
            size = int(fields[0])
            polygons.append(np.array(fields[1 : 1 + size], dtype=np.int64))
        except ValueError:
            raise ValueError(f"malformed OFF face {line.strip()[:60]!r}") from None
        if len(polygons[-1]) != size:
            raise ValueError(f"malformed OFF face {line.strip()[:60]!r}")
    triangles, source, _ = _fan(polygons)
    return vertices, triangles, source


# Names PLY writers give per-vertex texture coordinates, as trimesh reads them.
_PLY_UV_NAMES = (("texture_u", "texture_v"), ("u", "v"), ("s", "t"))


def _ply_in_place(scene, want_uvs: bool):
    """A PLY's vertices as stored and its faces fanned in place, from the elements trimesh
    read (its own triangles put the pieces of polygons in groups by size), with corner UVs
    when asked: (vertices, triangles, source, uvs or None), or None where its elements are
    not there to read (trimesh's mesh is used then)."""
    geometries = [g for g in scene.geometry.values() if isinstance(g, trimesh.Trimesh)]
    if len(geometries) != 1 or "_ply_raw" not in geometries[0].metadata:
        return None
    raw = geometries[0].metadata["_ply_raw"]
    try:
        vertex_data = raw["vertex"]["data"]
        vertices = np.column_stack([np.asarray(vertex_data[axis], dtype=np.float64)
                                    for axis in "xyz"])  # fmt: skip
        face_data = raw["face"]["data"]
    except (KeyError, TypeError, ValueError, IndexError):
        return None
    polygons, texcoords = None, None
    if isinstance(face_data, dict):
        for name in ("vertex_indices", "vertex_index"):
            if name in face_data:
                polygons = face_data[name]
                break
        texcoords = face_data.get("texcoord")
    elif isinstance(face_data, np.ndarray) and face_data.dtype.names:
        names = face_data.dtype.names
        name = (
            names[0]
            if len(names) == 1
            else next((n for n in ("vertex_indices", "vertex_index") if n in names), None)
        )
        if name is not None:
            polygons = face_data[name]["f1"]
        if "texcoord" in names:
            texcoords = face_data["texcoord"]["f1"]
    elif isinstance(face_data, np.ndarray) and face_data.ndim == 2:
        polygons = face_data
    if polygons is None:
        return None
    if isinstance(polygons, np.ndarray) and polygons.dtype != object:
        polygons = polygons.reshape(len(polygons), -1)
    triangles, source, corners = _fan(polygons)
    uvs = None
    if want_uvs:
        uvs = _ply_corner_uvs(vertex_data, triangles, texcoords, corners)
    return vertices, triangles, source, uvs


def _ply_corner_uvs(vertex_data, triangles, texcoords, corners):
    """Corner UVs of a PLY's fanned triangles: from a per-face texcoord list (u, v per corner)
    or from per-vertex coordinates; None if it has neither."""
    if texcoords is not None:
        try:
            if isinstance(texcoords, np.ndarray) and texcoords.dtype != object:
                flat = np.asarray(texcoords, dtype=np.float64).reshape(-1, 2)
            else:
                flat = np.concatenate([np.asarray(t, dtype=np.float64).reshape(-1, 2)
                                       for t in texcoords])  # fmt: skip
            return flat[corners].astype(np.float32)
        except (ValueError, IndexError):
            return None
    for u, v in _PLY_UV_NAMES:
        try:
            per_vertex = np.column_stack(
                [
                    np.asarray(vertex_data[u], dtype=np.float64),
                    np.asarray(vertex_data[v], dtype=np.float64),
                ]
            )
        except (KeyError, ValueError, IndexError):
            continue
        return per_vertex[triangles].astype(np.float32)
    return None


def _obj_corner_uvs(path: str):
    """Corner UVs of an OBJ in the order _plain_obj writes its triangles, or None when a face
    has no ``vt`` reference."""
    with open(path, "rb") as stream:
        text = stream.read().decode("utf-8", errors="replace")
    text = text.replace("\\\r\n", " ").replace("\\\n", " ")
    texcoords, corners = [], []
    for line in text.splitlines():
        fields = line.split()
        if not fields:
            continue
        if fields[0] == "vt":
            try:
                texcoords.append((float(fields[1]), float(fields[2]) if len(fields) > 2 else 0.0))
            except (ValueError, IndexError):
                return None
        elif fields[0] == "f":
            refs = []
            for token in fields[1:]:
                parts = token.split("/")
                if len(parts) < 2 or not parts[1]:
                    return None
                index = int(parts[1])
                refs.append(index - 1 if index > 0 else len(texcoords) + index)
            if any(not 0 <= r < len(texcoords) for r in refs):
                return None
            for k in range(1, len(refs) - 1):
                corners.append((refs[0], refs[k], refs[k + 1]))
    if not corners:
        return None
    return np.asarray(texcoords, dtype=np.float32)[np.asarray(corners, dtype=np.int64)]


def _scene_corner_uvs(scene: trimesh.Scene, nodes: list):
    """Corner UVs of the triangles _flatten gathers from ``nodes`` (same meshes, order and
    winding), or None when one of those meshes has no per-vertex UVs."""
    parts = []
    for node in nodes:
        transform, name = scene.graph[node]
        geometry = scene.geometry[name]
        if not isinstance(geometry, trimesh.Trimesh) or len(geometry.faces) == 0:
            continue
        uv = getattr(geometry.visual, "uv", None)
        if uv is None or np.shape(uv) != (len(geometry.vertices), 2):
            return None
        corners = np.asarray(uv, dtype=np.float32)[np.asarray(geometry.faces, dtype=np.int64)]
        transform = np.asarray(transform, dtype=np.float64)
        if np.linalg.det(transform[:3, :3]) < 0:  # _flatten reverses these triangles
            corners = corners[:, ::-1]
        parts.append(corners)
    if not parts:
        return None
    return np.ascontiguousarray(np.concatenate(parts))


def _plain_obj(path: str):
    """The OBJ file reduced to ``v`` lines and triangular ``f`` lines, in order, for each
    triangle the index of the ``f`` record it comes from (int64), and whether it has ``l``
    (line) records, which are dropped. Faces using a vertex the file does not have are
    refused here: trimesh's own words for them are numpy's, or it wraps a negative index.

    Dropping the texture and normal references keeps trimesh from splitting
    vertices at seams; fanning polygons here keeps each polygon's triangles at
    its place in the file; relative (negative) indices are made absolute because
    they count back from the current line, which trimesh cannot know once the
    file is reduced. Materials, groups and objects are irrelevant to the SDF.
    """
    with open(path, "rb") as stream:
        # Numbers are ASCII; a stray byte can only sit in a name or comment.
        text = stream.read().decode("utf-8", errors="replace")
    text = text.replace("\\\r\n", " ").replace("\\\n", " ")  # continuation lines
    out, source = [], []
    vertex_count = face_count = 0
    highest = (0, "")  # the highest vertex a face uses, and that face's line
    has_lines = False
    for line in text.splitlines():
        fields = line.split()
        if not fields:
            continue
        if fields[0] == "v":
            # Three numbers, checked here: trimesh makes a one-number line a one-column
            # array. Colours after them are dropped.
            try:
                if len(fields) < 4:
                    raise ValueError
                for token in fields[1:4]:
                    float(token)
            except ValueError:
                raise ValueError(f"malformed vertex {line.strip()[:60]!r}") from None
            out.append(" ".join(fields[:4]))
            vertex_count += 1
        elif fields[0] == "f":
            try:
                refs = [int(token.split("/", 1)[0]) for token in fields[1:]]
            except ValueError:
                raise ValueError(f"malformed face {line.strip()[:60]!r}") from None
            if 0 in refs:
                raise ValueError(f"face {line.strip()[:60]!r} uses index 0 (OBJ counts from 1)")
            if len(refs) < 3:  # trimesh drops it: a file cut inside its last face read "ok"
                raise ValueError(
                    f"face {line.strip()[:60]!r} has {len(refs)} corner"
                    f"{'s' if len(refs) != 1 else ''}, fewer than a face's 3 (is "
                    "the file cut short?)"
                )
            refs = [index if index > 0 else vertex_count + 1 + index for index in refs]
            if refs and min(refs) < 1:  # trimesh would count on from the end of the list
                raise ValueError(
                    f"face {line.strip()[:60]!r} counts back past the first "
                    "vertex (a negative index counts back from its line)"
                )
            if refs and max(refs) > highest[0]:
                highest = (max(refs), line.strip()[:60])
            for k in range(1, len(refs) - 1):
                out.append(f"f {refs[0]} {refs[k]} {refs[k + 1]}")
                source.append(face_count)
            face_count += 1
        elif fields[0] == "l":
            has_lines = True
    if highest[0] > vertex_count:
        raise ValueError(
            f"face {highest[1]!r} uses vertex {highest[0]}, but the file has "
            f"{vertex_count} vertices"
        )
    text = ("\n".join(out) + "\n").encode("ascii")
    return text, np.array(source, dtype=np.int64), has_lines


# How non-mesh geometry is named in the "no triangles" message.
_KIND_NAMES = {"PointCloud": "a point cloud", "Path2D": "2D paths", "Path3D": "lines"}


def _flatten(scene: trimesh.Scene, nodes: list) -> tuple[np.ndarray, np.ndarray, set]:
    """Concatenate the triangle meshes of the scene's ``nodes``, in that order, each placed
    by its node transform.

    Done here rather than with ``force="mesh"`` because trimesh's own
    concatenation copies each mesh's colours and textures, which needs SciPy or
    Pillow for some files; only positions and faces matter for the SDF.
    Returns the names of the other kinds of geometry found, for error messages.
    """
    vertex_parts, triangle_parts, other_kinds = [], [], set()
    offset = 0
    for node in nodes:
        transform, name = scene.graph[node]
        geometry = scene.geometry[name]
        if not isinstance(geometry, trimesh.Trimesh):
            other_kinds.add(_KIND_NAMES.get(type(geometry).__name__, type(geometry).__name__))
            continue
        if len(geometry.faces) == 0:
            continue
        vertices = np.asarray(geometry.vertices, dtype=np.float64)
        triangles = np.asarray(geometry.faces, dtype=np.int64)
        # trimesh keeps what a broken file declares (e.g. glTF positions of one component).
        if vertices.ndim != 2 or vertices.shape[1] != 3:
            raise ValueError(f"vertices of shape {vertices.shape}, not (n, 3)")
        if triangles.ndim != 2 or triangles.shape[1] != 3:
            raise ValueError(f"faces of shape {triangles.shape}, not (m, 3)")
        transform = np.asarray(transform, dtype=np.float64)
        if not np.array_equal(transform, np.eye(4)):
            vertices = vertices @ transform[:3, :3].T + transform[:3, 3]
            # A mirroring transform turns the surface inside out; reversing the
            # winding keeps the normals pointing outward (the SDF shoots inward).
            if np.linalg.det(transform[:3, :3]) < 0:
                triangles = triangles[:, ::-1]
        vertex_parts.append(vertices)
        triangle_parts.append(triangles + offset)
        offset += len(vertices)
    if not triangle_parts:
        return np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64), other_kinds
    return (
        np.ascontiguousarray(np.concatenate(vertex_parts)),
        np.ascontiguousarray(np.concatenate(triangle_parts)),
        other_kinds,
    )


def _merge_identical(vertices: np.ndarray, triangles: np.ndarray):
    """Merge vertices with exactly equal coordinates, numbered by first use."""
    if not np.isfinite(vertices).all():  # (refused after this, naming a vertex so numbered)
        return _merge_equal_rows(vertices, triangles)
    # Finite coordinates are equal exactly when their bits are, once -0.0 is made 0.0: rows
    # of three integers sort as one (lexsort, a third of np.unique(axis=0)'s time on 2.5M).
    keys = np.ascontiguousarray(vertices + 0.0).view(np.uint64)
    order = np.lexsort(keys.T[::-1])  # stable: each group's rows by first use
    ordered = keys[order]
    starts = np.ones(len(order), dtype=bool)
    np.any(ordered[1:] != ordered[:-1], axis=1, out=starts[1:])
    inverse = np.empty(len(order), dtype=np.int64)
    inverse[order] = np.cumsum(starts) - 1
    first = order[starts]  # each group's first use, groups in sorted order
    by_use = np.argsort(first, kind="stable")
    rank = np.empty_like(by_use)
    rank[by_use] = np.arange(len(by_use))
    return vertices[first[by_use]], rank[inverse][triangles]


def _merge_equal_rows(vertices: np.ndarray, triangles: np.ndarray):
    """_merge_identical by np.unique, for rows that may hold NaN (never equal)."""
    unique, first, inverse = np.unique(vertices, axis=0, return_index=True, return_inverse=True)
    order = np.argsort(first, kind="stable")
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    return unique[order], rank[inverse.reshape(-1)][triangles]


def save_colored(path, vertices, triangles, colors, per: str = "faces") -> None:
    """Write the mesh coloured per face or per vertex; the format follows the suffix.

    colors: (m,4) uint8 RGBA for per="faces", (n,4) for per="vertices".
    PLY is written binary with 64-bit float coordinates and keeps either kind of colour; OFF
    keeps either (written here, coordinates as %.17g); OBJ and GLB store only vertex colours,
    so per-face colours give every triangle its own three vertices (exact flat colours, 3m
    vertices); STL keeps no colour. PLY, OFF and OBJ give the float64 coordinates back
    exactly; GLB and STL hold 32-bit floats only, and a RuntimeWarning says so when that moves
    a vertex by more than PRECISION_WARNING of the mesh's size (a mesh far from the origin:
    UTM coordinates, say). Raises ValueError for an unknown suffix or mismatched arrays.
    The file is written whole or not at all: a failed write raises an OSError naming it and
    leaves an existing file as it was.
    """
    path = os.fspath(path)
    suffix = os.path.splitext(path)[1].lower()
    if suffix not in WRITE_SUFFIXES:
        raise ValueError(
            f"{path}: cannot write '{suffix}' files (use one of {', '.join(WRITE_SUFFIXES)})"
        )
    vertices = np.asarray(vertices, dtype=np.float64).reshape(-1, 3)
    triangles = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    colors = np.asarray(colors)
    if per not in ("faces", "vertices"):
        raise ValueError(f"per must be 'faces' or 'vertices', not {per!r}")
    expected = len(triangles) if per == "faces" else len(vertices)
    if colors.dtype != np.uint8 or colors.shape != (expected, 4):
        raise ValueError(
            f"colors must be uint8 of shape ({expected}, 4) for per={per!r}, "
            f"got {colors.dtype} {colors.shape}"
        )

    if suffix in (".glb", ".stl"):
        _warn_if_float32_moves(path, vertices)
    if per == "faces" and suffix in (".obj", ".glb"):
        vertices = vertices[triangles].reshape(-1, 3)
        triangles = np.arange(len(vertices), dtype=np.int64).reshape(-1, 3)
        colors = np.repeat(colors, 3, axis=0)
        per = "vertices"
    # Written whole or not at all: a failed write leaves an existing file as it was.
    with written_whole(path) as temporary:
        if suffix == ".ply":
            _write_ply(temporary, vertices, triangles, colors, per)
        elif suffix == ".off":
            _write_off(temporary, vertices, triangles, colors, per)
        elif suffix == ".obj":
            _write_obj(temporary, vertices, triangles, colors)
        else:
            key = "face_colors" if per == "faces" else "vertex_colors"
            mesh = trimesh.Trimesh(vertices, triangles, process=False, **{key: colors})
            mesh.export(temporary, file_type=suffix[1:])


# Past this share of the mesh's size, rounding the coordinates to 32-bit floats (GLB, STL)
# is worth a warning: float32 keeps about 6e-8 of a coordinate's magnitude, so a mesh near
# the origin never reaches it, and a 10 m building at UTM northings (5.4e6) moves by 0.25 m.
PRECISION_WARNING = 1e-6


def _warn_if_float32_moves(path: str, vertices: np.ndarray) -> None:
    if len(vertices) == 0:
        return
    with np.errstate(over="ignore", invalid="ignore"):
        moved = float(np.max(np.abs(vertices.astype(np.float32) - vertices)))
    size = float(np.max(np.ptp(vertices, axis=0)))
    if not moved <= PRECISION_WARNING * size:  # also inf: beyond float32's range
        if size > 0 and moved < 0.1 * size:
            share = f"{moved / size:.2g} of the mesh's size"
        elif size > 0 and moved < size:  # (13% is not 'as much as the mesh is wide')
            share = f"{moved / size:.0%} of the mesh's size: its shape is lost"
        else:  # e.g. a unit cube at 1e8: every corner lands on one float32
            share = "as much as the mesh is wide: its shape is lost"
        warn(
            f"{path}: {format_name(os.path.splitext(path)[1].lower())} holds 32-bit float "
            f"coordinates: vertices move by up to {moved:.3g} units ({share}); write .ply, "
            ".off or .obj to keep them exactly"
        )


def _write_ply(path, vertices, triangles, colors, per) -> None:
    """Binary little-endian PLY, coordinates as double: float32 (trimesh's choice) moves a
    vertex of a mesh far from the origin by a visible amount, and collapses a small one."""
    channels = ("red", "green", "blue", "alpha")
    rgba = [(name, "u1") for name in channels]
    vertex_fields = [("x", "<f8"), ("y", "<f8"), ("z", "<f8")] + (rgba if per == "vertices" else [])
    face_fields = [("count", "u1"), ("indices", "<i4", (3,))] + (rgba if per == "faces" else [])
    if len(vertices) > np.iinfo(np.int32).max:
        raise ValueError(f"{path}: too many vertices for PLY's 32-bit indices")
    if per == "vertices":
        vertex_rows = np.empty(len(vertices), dtype=vertex_fields)
        for axis, name in enumerate("xyz"):
            vertex_rows[name] = vertices[:, axis]
    else:  # the rows are the coordinates as they are
        vertex_rows = np.ascontiguousarray(vertices, dtype="<f8")
    face_rows = np.empty(len(triangles), dtype=face_fields)
    face_rows["count"] = 3
    face_rows["indices"] = triangles
    coloured_rows = vertex_rows if per == "vertices" else face_rows
    for channel, name in enumerate(channels):
        coloured_rows[name] = colors[:, channel]

    colour_lines = "".join(f"property uchar {name}\n" for name in channels)
    header = (
        "ply\nformat binary_little_endian 1.0\ncomment shape-diameter\n"
        f"element vertex {len(vertices)}\n"
        "property double x\nproperty double y\nproperty double z\n"
        f"{colour_lines if per == 'vertices' else ''}"
        f"element face {len(triangles)}\nproperty list uchar int vertex_indices\n"
        f"{colour_lines if per == 'faces' else ''}end_header\n"
    )
    with open(path, "wb") as out:
        out.write(header.encode("ascii"))
        # The arrays' own memory, written as it is (tobytes() would copy it first).
        out.write(vertex_rows.reshape(-1).view(np.uint8).data)
        out.write(face_rows.view(np.uint8).data)


def _write_obj(path, vertices, triangles, colors) -> None:
    """OBJ with vertex colours ("v x y z r g b", colours in [0, 1] as trimesh writes and reads
    them; OBJ has no alpha). Coordinates in Python's shortest form that reads back as the
    same double: a fixed number of decimals loses small meshes (8 decimals: 2.5e-4 relative
    at 1e-5 units)."""
    rgb = (colors[:, :3] / 255.0).tolist()
    with open(path, "w", encoding="ascii", newline="\n") as out:
        out.writelines(
            f"v {x!r} {y!r} {z!r} {r:.8f} {g:.8f} {b:.8f}\n"
            for (x, y, z), (r, g, b) in zip(vertices.tolist(), rgb)
        )
        np.savetxt(out, triangles + 1, fmt="f %d %d %d")


def _write_off(path, vertices, triangles, colors, per) -> None:
    """OFF with colours: COFF puts RGBA after each vertex, OFF after each face."""
    corners = np.column_stack([np.full(len(triangles), 3), triangles])
    with open(path, "w", encoding="ascii") as out:
        out.write(f"{'COFF' if per == 'vertices' else 'OFF'}\n")
        out.write(f"{len(vertices)} {len(triangles)} 0\n")
        # %.17g gives back every float64 exactly.
        if per == "vertices":
            np.savetxt(out, np.column_stack([vertices, colors]), fmt=["%.17g"] * 3 + ["%d"] * 4)
            np.savetxt(out, corners, fmt="%d")
        else:
            np.savetxt(out, vertices, fmt="%.17g")
            np.savetxt(out, np.column_stack([corners, colors]), fmt="%d")
