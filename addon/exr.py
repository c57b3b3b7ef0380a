# SPDX-License-Identifier: GPL-3.0-or-later
"""OpenEXR files of one channel, made with numpy and zlib alone (no bpy: the worker thread
encodes a bake while Blender's main thread only packs the bytes).

A scanline file with a single luminance channel "Y" (Blender reads it as a grey image: the
value in R, G and B) of 16-bit half floats (the default: 3 significant decimal digits, plenty
for a [0, 1] map) or 32-bit floats, ZIP-compressed in blocks of 16 lines, as the OpenEXR
file layout (openexr.com, "OpenEXR File Layout") describes it. Rows are given as Blender
holds pixels, row 0 at the bottom (v = 0); the file stores the top line first.
"""

import struct
import zlib

import numpy as np

HALF, FLOAT = 1, 2  # the file's pixel types
ZIP_COMPRESSION = 3  # zlib over blocks of 16 scanlines
LINES_PER_BLOCK = 16
MAGIC = 20000630
ZLIB_LEVEL = 4  # about as small as level 6 on a smooth map, at half the time


def _attribute(name, kind, value):
    return name.encode() + b"\0" + kind.encode() + b"\0" + struct.pack("<i", len(value)) + value


def _header(width, height, pixel_type):
    channel = b"Y\0" + struct.pack("<iB3xii", pixel_type, 0, 1, 1) + b"\0"
    window = struct.pack("<iiii", 0, 0, width - 1, height - 1)
    return b"".join(
        [
            struct.pack("<ii", MAGIC, 2),  # version 2, a single-part scanline file
            _attribute("channels", "chlist", channel),
            _attribute("compression", "compression", bytes([ZIP_COMPRESSION])),
            _attribute("dataWindow", "box2i", window),
            _attribute("displayWindow", "box2i", window),
            _attribute("lineOrder", "lineOrder", b"\0"),  # increasing y
            _attribute("pixelAspectRatio", "float", struct.pack("<f", 1.0)),
            _attribute("screenWindowCenter", "v2f", struct.pack("<ff", 0.0, 0.0)),
            _attribute("screenWindowWidth", "float", struct.pack("<f", 1.0)),
            b"\0",
        ]
    )


def _zip_block(raw):
    """One block as the ZIP compressor stores it: bytes split into even and odd halves,
    each byte replaced by its difference to the one before (plus 128), deflated; the raw
    bytes where that is no smaller."""
    data = np.frombuffer(raw, dtype=np.uint8)
    split = np.concatenate([data[0::2], data[1::2]])
    delta = split.copy()
    delta[1:] = (split[1:].astype(np.int16) - split[:-1] + 128).astype(np.uint8)
    packed = zlib.compress(delta.tobytes(), ZLIB_LEVEL)
    return packed if len(packed) < len(raw) else raw


def encode(values, half=True, check=None):
    """The bytes of an OpenEXR file holding `values` (height, width), row 0 at v = 0, as one
    channel of half floats (half=True) or 32-bit floats. `check()`, when given, is called
    between blocks (it may raise to stop)."""
    values = np.asarray(values, dtype=np.float32)
    height, width = values.shape
    top_first = values[::-1].astype(np.float16 if half else np.float32)
    header = _header(width, height, HALF if half else FLOAT)
    blocks = []
    for y in range(0, height, LINES_PER_BLOCK):
        if check is not None:
            check()
        data = _zip_block(np.ascontiguousarray(top_first[y : y + LINES_PER_BLOCK]).tobytes())
        blocks.append(struct.pack("<ii", y, len(data)) + data)
    at = len(header) + 8 * len(blocks)
    offsets = []
    for block in blocks:
        offsets.append(at)
        at += len(block)
    return header + struct.pack(f"<{len(offsets)}Q", *offsets) + b"".join(blocks)
