# SPDX-License-Identifier: GPL-3.0-or-later
"""Stage 5c: map SDF values to [0, 1]."""

import numpy as np

from . import _core

NORMALIZATIONS = ("linear", "log")
MAX_THREADS = 4096  # compute()'s bound too


def normalize_values(values, method: str = "linear", threads: int = 0) -> np.ndarray:
    """Map values to [0, 1]: 'linear' is (x - min) / (max - min); 'log' applies Shapira et al.'s
    log(4 x + 1) / log(5) to the linear result, spreading the thin end. A constant field maps
    to 0. Computed in double precision by the native core on `threads` threads (0 = every
    core), rounded once to float32; the result has the shape of `values`. Raises ValueError
    for values that are not real numbers, or not finite in float32 (NaN or infinite make the
    range meaningless), and for a bad method or thread count."""
    if method not in NORMALIZATIONS:
        raise ValueError(f"normalize must be one of {NORMALIZATIONS}, got {method!r}")
    threads = check_threads(threads)
    v = np.asarray(values)
    if v.dtype.kind not in "fiu":
        raise ValueError(f"values must be real numbers, got dtype {v.dtype}")
    if v.dtype not in (np.float32, np.float64):
        v = v.astype(np.float64)
    check_finite_float32(v)
    # reshape: a 0-d input (one number) came back with shape (1,)
    return _core.normalize(np.ascontiguousarray(v), method, threads).reshape(v.shape)


def check_threads(threads) -> int:
    """A thread count as an int (0 = every core); ValueError for anything else, including
    counts the native core's unsigned argument cannot take."""
    if (
        isinstance(threads, bool)
        or not isinstance(threads, (int, np.integer))
        or not (0 <= threads <= MAX_THREADS)
    ):
        raise ValueError(f"threads must be an integer in [0, {MAX_THREADS}], got {threads!r}")
    return int(threads)


def check_finite_float32(values: np.ndarray) -> None:
    """ValueError unless every value is finite and stays finite as float32 (the SDF's type;
    smooth() and normalize() share this rule and its message)."""
    with np.errstate(over="ignore"):  # a float64 beyond float32 becomes inf: that is the test
        bad = ~np.isfinite(np.atleast_1d(values).astype(np.float32, copy=False))
    if bad.any():
        first = tuple(int(i) for i in np.unravel_index(int(np.argmax(bad)), bad.shape))
        raise ValueError(
            f"values must be finite: {int(bad.sum())} are NaN or infinite, or too large for "
            f"float32 (first: index {first[0] if len(first) == 1 else first})"
        )
