# SPDX-License-Identifier: GPL-3.0-or-later
"""Stage 5c: map SDF values to [0, 1]."""

import numpy as np

NORMALIZATIONS = ("linear", "log")
# Shapira et al.'s log normalisation log(a x + 1) / log(a + 1), with their a = 4.
LOG_STRENGTH = 4.0


def normalize_values(values, method: str = "linear") -> np.ndarray:
    """Map values to [0, 1]: 'linear' is (x - min) / (max - min); 'log' applies Shapira et al.'s
    log(4 x + 1) / log(5) to the linear result, spreading the thin end. A constant field maps
    to 0."""
    if method not in NORMALIZATIONS:
        raise ValueError(f"normalize must be one of {NORMALIZATIONS}, got {method!r}")
    v = np.asarray(values, dtype=np.float64)
    lo, hi = (float(v.min()), float(v.max())) if v.size else (0.0, 0.0)
    # The same operations as (v - lo) / (hi - lo), log1p(4 x) / log1p(4) and clip, done in
    # place: no temporary arrays for a million points.
    if hi > lo:
        out = np.subtract(v, lo)
        out /= hi - lo
    else:
        out = np.zeros_like(v)
    if method == "log":
        out *= LOG_STRENGTH
        np.log1p(out, out=out)
        out /= np.log1p(LOG_STRENGTH)
    np.clip(out, 0.0, 1.0, out=out)
    return out.astype(np.float32)
