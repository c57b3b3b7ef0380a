# SPDX-License-Identifier: GPL-3.0-or-later
"""The input checks compute(), smooth() and the single stages share: one rule and one message
for each argument, whichever function takes it."""

from __future__ import annotations

import numpy as np

from . import _core


def _array(name, value, shape, rows):
    """np.asarray(value), or ValueError naming `name` where its rows differ in length (numpy's
    own words name no argument)."""
    try:
        return np.asarray(value)
    except ValueError as error:
        raise ValueError(
            f"{name} must have shape {shape}, but its rows differ in length{rows}"
        ) from error


def check_mesh(vertices, triangles, threads=0):
    """The mesh as contiguous float64 and int64 arrays; ValueError naming what is wrong. The
    value checks run on `threads` (an already checked count, 0 = every core)."""
    polygons = "polygons: triangulate them first (load_mesh does)"
    v = _array("vertices", vertices, "(n, 3)", "")
    t = _array("triangles", triangles, "(m, 3)", f" (of {polygons})")
    if v.ndim != 2 or v.shape[1] != 3:
        raise ValueError(f"vertices must have shape (n, 3), got {v.shape}")
    if v.dtype.kind not in "fiu":
        raise ValueError(f"vertices must be real numbers, got dtype {v.dtype}")
    if t.ndim != 2 or t.shape[1] != 3:
        hint = f": {t.shape[1]}-corner {polygons}" if t.ndim == 2 and t.shape[1] > 3 else ""
        raise ValueError(f"triangles must have shape (m, 3), got {t.shape}{hint}")
    if t.dtype.kind not in "iu":
        raise ValueError(f"triangles must be integers, got dtype {t.dtype}")
    if v.shape[0] == 0:
        raise ValueError("the mesh is empty: no vertices")
    if t.shape[0] == 0:
        raise ValueError("the mesh is empty: no triangles")
    v = np.ascontiguousarray(v, dtype=np.float64)
    # Unsigned 64-bit indices may not fit int64: checked as they are. Otherwise one parallel
    # native pass (numpy's took 6 ms on 1.2M faces on a 16-core host).
    wide_unsigned = t.dtype.kind == "u" and t.dtype.itemsize == 8
    if wide_unsigned:
        lo, hi = int(np.min(t)), int(np.max(t))
    t = np.ascontiguousarray(t, dtype=np.int64)
    not_finite, first_not_finite, min_index, max_index = _core.mesh_values(v, t, threads)
    if not wide_unsigned:
        lo, hi = min_index, max_index
    if not_finite:
        raise ValueError(
            f"vertices must be finite: {not_finite} have NaN or infinite coordinates "
            f"(first: vertex {first_not_finite})"
        )
    if lo < 0:
        raise ValueError(f"triangles contain a negative vertex index ({lo})")
    if hi >= v.shape[0]:
        raise ValueError(
            f"triangles contain vertex index {hi}, but there are only {v.shape[0]} vertices"
        )
    return v, t


def check_integer(name, value, lo, hi):
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not lo <= value <= hi:
        raise ValueError(f"{name} must be an integer in [{lo}, {hi}], got {value!r}")


def check_cone_angle(cone_angle):
    if (
        isinstance(cone_angle, bool)
        or not isinstance(cone_angle, (int, float, np.integer, np.floating))
        or not 0.0 < float(cone_angle) < 180.0
    ):
        raise ValueError(f"cone_angle must be a number in (0, 180) degrees, got {cone_angle!r}")


def check_choice(name, value, choices):
    if value not in choices:
        raise ValueError(f"{name} must be one of {choices}, got {value!r}")


def check_progress(progress):
    if progress is not None and not callable(progress):
        raise ValueError("progress must be a callable taking a fraction in [0, 1], or None")
