# SPDX-License-Identifier: GPL-3.0-or-later
"""Stage 5c: map SDF values to [0, 1]."""

import numpy as np

from . import _core

NORMALIZATIONS = ("linear", "log")


def normalize_values(values, method: str = "linear", threads: int = 0) -> np.ndarray:
    """Map values to [0, 1]: 'linear' is (x - min) / (max - min); 'log' applies Shapira et al.'s
    log(4 x + 1) / log(5) to the linear result, spreading the thin end. A constant field maps
    to 0. Computed in double precision by the native core on `threads` threads (0 = every
    core), rounded once to float32; the result has the shape of `values`."""
    if method not in NORMALIZATIONS:
        raise ValueError(f"normalize must be one of {NORMALIZATIONS}, got {method!r}")
    v = np.asarray(values)
    if v.dtype not in (np.float32, np.float64):
        v = v.astype(np.float64)
    return _core.normalize(np.ascontiguousarray(v), method, threads)
