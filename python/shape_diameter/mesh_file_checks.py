# SPDX-License-Identifier: GPL-3.0-or-later
"""Whether a mesh file holds what its header declares, before trimesh reads it: trimesh
reads a truncated ASCII OFF or PLY as a smaller mesh without a word, and fails on bytes that
are no STL with an error about text encodings."""

import os

import numpy as np

# The suffixes read, and the format each names.
READ_SUFFIXES = (".obj", ".ply", ".off", ".stl", ".gltf", ".glb")
_ARTICLE = {"OFF": "an", "STL": "an", "OBJ": "an"}
# The first words of an OBJ file's records (after comments), to tell OBJ text from others.
_OBJ_RECORDS = {b"v", b"vt", b"vn", b"vp", b"f", b"o", b"g", b"s", b"l", b"mtllib", b"usemtl"}


def format_name(suffix: str) -> str:
    return {".gltf": "glTF", ".glb": "GLB"}.get(suffix, suffix[1:].upper() or "mesh")


def looks_like(head: bytes, size: int):
    """The format a file's first bytes (and its size, for binary STL) suggest: 'OBJ', 'PLY',
    'OFF', 'STL', 'GLB', 'glTF', or None."""
    if head.startswith(b"ply") and head[3:4] in (b"\n", b"\r"):
        return "PLY"
    if head.startswith(b"glTF"):
        return "GLB"
    if len(head) >= 84 and size == 84 + 50 * int.from_bytes(head[80:84], "little"):
        return "STL"  # binary: its 80-byte header says anything, its size is what counts
    if b"\x00" in head:
        return None  # no text
    head = head.removeprefix(b"\xef\xbb\xbf")  # a UTF-8 byte order mark
    words = [line.split(maxsplit=1)[0] for line in head.splitlines()
             if line.strip() and not line.lstrip().startswith(b"#")]  # fmt: skip
    first = words[0] if words else b""
    if first.endswith(b"OFF") and first.isalpha() and first.isupper():
        return "OFF"  # OFF, COFF, NOFF, STOFF, ...
    if first == b"solid":
        return "STL"
    if first.startswith(b"{"):
        return "glTF"
    if first in _OBJ_RECORDS:
        return "OBJ"
    return None


def _not_valid(suffix: str, why: str, data: bytes, size=None) -> ValueError:
    """The error for a file that is not what its suffix says, naming what it looks like."""
    seems = looks_like(data[:4096], len(data) if size is None else size)
    if seems is not None and seems != format_name(suffix):
        why = f"it looks like {_ARTICLE.get(seems, 'a')} {seems} file"
    return ValueError(f"not a valid {format_name(suffix)} file ({why})")


def check_suffix(path: str) -> str:
    """The suffix of a file to read, lower case; ValueError for one that names no format read
    (saying which are, and what the file looks like)."""
    suffix = os.path.splitext(path)[1].lower()
    if suffix in READ_SUFFIXES:
        return suffix
    supported = ", ".join(READ_SUFFIXES)
    try:
        with open(path, "rb") as stream:
            seems = looks_like(stream.read(4096), os.fstat(stream.fileno()).st_size)
    except OSError:
        seems = None
    hint = f"it looks like {_ARTICLE.get(seems, 'a')} {seems} file; " if seems else ""
    if not suffix:
        raise ValueError(
            f"no file extension to tell the mesh format by ({hint}supported: {supported})"
        )
    raise ValueError(f"cannot read '{suffix}' files ({hint}supported: {supported})")


def check_complete(path: str, suffix: str) -> None:
    """That the file is of the format its suffix names (ValueError saying what it seems to
    be otherwise), and the counts a header declares against what the file holds (ValueError
    if short).

    trimesh reads a truncated ASCII OFF or PLY as a smaller mesh without a word, fails on
    bytes that are no STL with an error about text encodings, and finds "no triangles" in a
    binary PLY named .obj. A cut inside the last number stays unseen: the file then holds a
    different, complete-looking number.
    """
    with open(path, "rb") as stream:
        size = os.fstat(stream.fileno()).st_size
        head = stream.read(84)
        if suffix == ".stl" and len(head) == 84:
            count = int.from_bytes(head[80:84], "little")
            if size == 84 + 50 * count:
                return  # a whole binary STL: not worth reading twice
        if suffix not in (".off", ".ply", ".stl"):
            _check_kind(suffix, head + stream.read(4096 - len(head)), size)
            return
        stream.seek(0)
        data = stream.read()  # (head + the rest would copy it all once more)
    if suffix == ".off":
        _check_off(data)
    elif suffix == ".ply":
        _check_ply(data)
    else:
        _check_stl(data)


def _check_kind(suffix: str, head: bytes, size: int) -> None:
    """OBJ, glTF and GLB: only whether the file is of that kind (trimesh checks the rest)."""
    seems = looks_like(head, size)
    if suffix == ".obj":
        if seems not in (None, "OBJ"):
            raise _not_valid(suffix, "", head, size)
        if b"\x00" in head:
            raise _not_valid(suffix, "it is not text", head, size)
    elif suffix == ".glb" and seems != "GLB":
        raise _not_valid(suffix, "no 'glTF' header", head, size)
    elif suffix == ".glb" and len(head) >= 12 and size < int.from_bytes(head[8:12], "little"):
        raise ValueError(
            f"truncated: its header declares {int.from_bytes(head[8:12], 'little')} "
            f"bytes, the file has {size}"
        )
    elif suffix == ".gltf" and seems != "glTF":
        raise _not_valid(suffix, "not JSON text", head, size)


def off_sections(text: str):
    """An OFF file's lines without comments and blank ones, as trimesh reads them: (header
    line's fields, the count fields (on the header line or the next), the lines after them).
    Split only where needed: this pass was a third of the load time otherwise."""
    lines = text.splitlines()
    if "#" in text:
        lines = [line.split("#", 1)[0] for line in lines]
    lines = [line for line in lines if line and not line.isspace()]
    header = lines[0].split() if lines else []
    counts = header[1:] or (lines[1].split() if len(lines) > 1 else [])
    body = lines[1:] if header[1:] else lines[2:]
    return header, counts, body


def _check_off(data: bytes) -> None:
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:
        raise _not_valid(".off", "it is not text", data) from None
    header, counts, body = off_sections(text)
    if not header or not header[0].endswith("OFF"):
        raise _not_valid(".off", "no OFF header", data)
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
    """ASCII PLY: the counts against the rows. Binary PLY: that lists (a face's corners) all
    have one length, the only kind trimesh reads (its length is checked by trimesh)."""
    if looks_like(data[:4096], len(data)) != "PLY":
        raise _not_valid(".ply", "no 'ply' header", data)
    end = data.find(b"end_header")
    if end < 0:
        raise ValueError("not a valid PLY file (no end_header)")
    # Each element: name, count, and its properties (True for a list); and the properties'
    # types, for binary files: (count type, item type) of a list, (None, type) otherwise.
    elements, types, format_name = [], [], ""
    for line in data[:end].decode("ascii", errors="replace").splitlines():
        fields = line.split()
        if len(fields) >= 2 and fields[0] == "format":
            format_name = fields[1]
        elif len(fields) >= 3 and fields[0] == "element" and fields[2].isdecimal():
            elements.append((fields[1], int(fields[2]), []))
            types.append([])
        elif len(fields) >= 2 and fields[0] == "property" and elements:
            elements[-1][2].append(fields[1] == "list")
            # (a list short of its types gets "": an unknown type, trimesh's to judge)
            types[-1].append((fields[2] if len(fields) > 2 else "",
                              fields[3] if len(fields) > 3 else "")
                             if fields[1] == "list" else (None, fields[1]))  # fmt: skip
    if format_name in ("binary_little_endian", "binary_big_endian"):
        start = data.index(b"\n", end) + 1
        _check_ply_lists(data, start, elements, types, format_name == "binary_big_endian")
        return
    if format_name != "ascii":
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


# Bytes of PLY's scalar types, by both their names.
_PLY_SIZES = {"char": 1, "uchar": 1, "int8": 1, "uint8": 1, "short": 2, "ushort": 2,
              "int16": 2, "uint16": 2, "int": 4, "uint": 4, "int32": 4, "uint32": 4,
              "float": 4, "float32": 4, "double": 8, "float64": 8}  # fmt: skip


def _check_ply_lists(data: bytes, start: int, elements, types, big_endian: bool) -> None:
    """Refuse a binary PLY whose lists of one property differ in length (a mesh of triangles
    and quads, as Blender writes n-gons): trimesh reads every row as long as the first, which
    fails on the file's length, or, where the lengths happen to add up, reads wrong faces.
    Each element's rows are laid side by side as the first row's lengths would have them, and
    every list's length is compared with the first's; elements after one that is not
    uniform are not checked (trimesh's length check remains)."""
    offset = start
    for (name, count, _), properties in zip(elements, types):
        if any(t not in _PLY_SIZES for pair in properties for t in pair if t is not None):
            return  # an unknown type: trimesh's to judge
        stride, lists, at = 0, [], offset
        for count_type, item_type in properties:
            if count_type is None:
                stride += _PLY_SIZES[item_type]
                continue
            size = _PLY_SIZES[count_type]
            if count == 0 or at + stride + size > len(data):
                return
            length = int.from_bytes(data[at + stride : at + stride + size],
                                    "big" if big_endian else "little")  # fmt: skip
            lists.append((stride, size, length))
            stride += size + length * _PLY_SIZES[item_type]
        if lists and count > 0:
            if len(data) < offset + count * stride:
                return  # short, or mixed: trimesh's length check says so
            table = np.frombuffer(data, dtype=np.uint8, count=count * stride, offset=offset)
            table = table.reshape(count, stride)
            for column, size, _ in lists:
                lengths = table[:, column : column + size]
                first = np.frombuffer(data[offset + column : offset + column + size],
                                      dtype=np.uint8)  # fmt: skip
                if not (lengths == first).all():
                    raise _mixed_lists(name)
        offset += count * stride


def _mixed_lists(name: str) -> ValueError:
    plural = {"face": "faces"}.get(name, f"'{name}' elements")
    return ValueError(
        f"binary PLY whose {plural} have different numbers of corners: trimesh cannot read "
        "that; save it as ASCII PLY, OBJ or OFF"
    )


def _ply_row_complete(fields, properties) -> bool:
    """Whether an ASCII PLY row holds every property: one value each, a list its length."""
    at = 0
    for is_list in properties:
        if at >= len(fields):
            return False
        if is_list:
            try:
                count = int(float(fields[at]))
            except (ValueError, OverflowError):
                return True  # not a count: trimesh's error to give
            if count < 0:
                return True  # the same (a negative count sent the index backwards: fuzzer)
            at += count
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
    except UnicodeDecodeError:
        pass
    else:
        if looks_like(data[:4096], len(data)) == "STL":
            # trimesh finds no triangles in broken text: a cut file would be "empty".
            # (A DOS end-of-file byte or NULs after it are padding, which trimesh reads past.)
            last_line = data.rstrip(b" \t\r\n\x00\x1a").rsplit(b"\n", 1)[-1].strip()
            if not last_line.lower().startswith(b"endsolid"):
                raise ValueError(
                    "truncated: ASCII STL text ends with an 'endsolid' line, this file does not"
                )
            return
        raise _not_valid(".stl", "text that does not start with 'solid'", data)
    if len(data) < 84:
        raise _not_valid(".stl", "too short for a binary STL, and not ASCII STL text", data)
    raise _not_valid(
        ".stl",
        f"not ASCII STL text, nor a whole binary STL: its header declares {count} "
        f"triangles, {84 + 50 * count} bytes, the file has {len(data)}",
        data,
    )
