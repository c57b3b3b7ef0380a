# SPDX-License-Identifier: GPL-3.0-or-later
"""Whether a mesh file holds what its header declares, before trimesh reads it: trimesh
reads a truncated ASCII OFF or PLY as a smaller mesh without a word, and fails on bytes that
are no STL with an error about text encodings."""

import os

# The first bytes of the formats read, to say what a misnamed file seems to be.
_MAGIC = {b"ply": "PLY", b"glTF": "GLB", b"OFF": "OFF", b"COFF": "OFF", b"solid": "STL"}
_ARTICLE = {"OFF": "an", "STL": "an"}


def format_name(suffix: str) -> str:
    return {".gltf": "glTF", ".glb": "GLB"}.get(suffix, suffix[1:].upper() or "mesh")


def _not_valid(suffix: str, why: str, data: bytes) -> ValueError:
    """The error for a file that is not what its suffix says, naming what it looks like."""
    for magic, name in _MAGIC.items():
        if data.startswith(magic) and name != format_name(suffix):
            why = f"it looks like {_ARTICLE.get(name, 'a')} {name} file"
    return ValueError(f"not a valid {format_name(suffix)} file ({why})")


def check_complete(path: str, suffix: str) -> None:
    """The counts a header declares against what the file holds (ValueError if short).

    trimesh reads a truncated ASCII OFF or PLY as a smaller mesh without a word, and fails on
    bytes that are no STL with an error about text encodings. A cut inside the last number
    stays unseen: the file then holds a different, complete-looking number.
    """
    if suffix not in (".off", ".ply", ".stl"):
        return
    with open(path, "rb") as stream:
        head = stream.read(84)
        if suffix == ".stl" and len(head) == 84:
            count = int.from_bytes(head[80:84], "little")
            if os.fstat(stream.fileno()).st_size == 84 + 50 * count:
                return  # a whole binary STL: not worth reading twice
        data = head + stream.read()
    if suffix == ".off":
        _check_off(data)
    elif suffix == ".ply":
        _check_ply(data)
    else:
        _check_stl(data)


def _check_off(data: bytes) -> None:
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:
        raise _not_valid(".off", "it is not text", data) from None
    # Lines without comments and blank ones, as trimesh reads them (split only where needed:
    # this pass is a third of the load time otherwise).
    lines = text.splitlines()
    if "#" in text:
        lines = [line.split("#", 1)[0] for line in lines]
    lines = [line for line in lines if line and not line.isspace()]
    header = lines[0].split() if lines else []
    if not header or not header[0].endswith("OFF"):
        raise _not_valid(".off", "no OFF header", data)
    counts = header[1:] or (lines[1].split() if len(lines) > 1 else [])
    body = lines[1:] if header[1:] else lines[2:]
    try:
        vertex_count, face_count = int(counts[0]), int(counts[1])
    except (ValueError, IndexError):
        vertex_count = face_count = -1
    if vertex_count < 0 or face_count < 0:
        raise ValueError("malformed OFF header: no vertex and face counts")
    if len(body) < vertex_count:
        raise ValueError(
            f"truncated OFF file: the header declares {vertex_count} vertices, the file "
            f"holds only {len(body)}"
        )
    if len(body) < vertex_count + face_count:
        raise ValueError(
            f"truncated OFF file: the header declares {face_count} faces, the file holds "
            f"only {len(body) - vertex_count}"
        )
    if face_count > 0:
        last = body[vertex_count + face_count - 1].split()
        if last[0].isdecimal() and len(last) < 1 + int(last[0]):
            raise ValueError("truncated OFF file: its last face has fewer corners than declared")


def _check_ply(data: bytes) -> None:
    """ASCII PLY only: binary PLY is checked against its expected length by trimesh."""
    end = data.find(b"end_header")
    if not data.startswith(b"ply") or end < 0:
        return  # trimesh says it is no PLY
    # Each element: name, count, and its properties (True for a list).
    elements, is_ascii = [], False
    for line in data[:end].decode("ascii", errors="replace").splitlines():
        fields = line.split()
        if len(fields) >= 2 and fields[0] == "format":
            is_ascii = fields[1] == "ascii"
        elif len(fields) >= 3 and fields[0] == "element" and fields[2].isdecimal():
            elements.append((fields[1], int(fields[2]), []))
        elif len(fields) >= 2 and fields[0] == "property" and elements:
            elements[-1][2].append(fields[1] == "list")
    if not is_ascii:
        return
    rows = [row for row in data[end:].splitlines()[1:] if row.strip()]
    seen = 0
    for name, count, _ in elements:
        if len(rows) < seen + count:
            plural = {"vertex": "vertices", "face": "faces"}.get(name, f"'{name}' elements")
            raise ValueError(
                f"truncated PLY file: the header declares {count} {plural}, the file holds "
                f"only {max(len(rows) - seen, 0)}"
            )
        seen += count
    last = [(name, properties) for name, count, properties in elements if count > 0]
    if last and not _ply_row_complete(rows[seen - 1].split(), last[-1][1]):
        raise ValueError(
            f"truncated PLY file: its last {last[-1][0]} has fewer values than declared"
        )


def _ply_row_complete(fields, properties) -> bool:
    """Whether an ASCII PLY row holds every property: one value each, a list its length."""
    at = 0
    for is_list in properties:
        if at >= len(fields):
            return False
        if is_list:
            try:
                at += int(float(fields[at]))
            except (ValueError, OverflowError):
                return True  # not a count: trimesh's error to give
        at += 1
    return at <= len(fields)


def _check_stl(data: bytes) -> None:
    # trimesh reads a file as binary STL when its size is the one its header declares,
    # else as ASCII STL text.
    if len(data) >= 84:
        count = int.from_bytes(data[80:84], "little")
        if len(data) == 84 + 50 * count:
            return
    try:
        data.decode("utf-8")
        return  # ASCII STL: trimesh finds no triangles in broken text
    except UnicodeDecodeError:
        pass
    if len(data) < 84:
        raise _not_valid(".stl", "too short for a binary STL, and not ASCII STL text", data)
    raise _not_valid(
        ".stl",
        f"not ASCII STL text, nor a whole binary STL: its header declares {count} "
        f"triangles, {84 + 50 * count} bytes, the file has {len(data)}",
        data,
    )
