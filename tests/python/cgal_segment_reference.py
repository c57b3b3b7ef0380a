# SPDX-License-Identifier: GPL-3.0-or-later
"""Runs the ``cgal_segment`` reference (tests/reference/cgal_segment.cpp) and reads its output.

The binary's path comes from the environment variable SDF_CGAL_SEGMENT. Without it the tests
that need it skip, unless CI is set, in which case they fail: CI must not pass silently
without the reference.
"""

from __future__ import annotations

import json
import os
import subprocess
from dataclasses import dataclass
from pathlib import Path

import numpy as np

_NOT_CI = {"", "0", "false", "no", "off"}


@dataclass
class CgalSegmentation:
    """One run of cgal_segment: per-face arrays in the OFF file's face order."""

    sdf: np.ndarray  # float64, the post-processed SDF the segmentation used, in [0, 1]
    clusters: np.ndarray  # int64, cluster per face (output_cluster_ids=true), 0 = thinnest
    labels: np.ndarray  # int64, segment per face, numbered by increasing mean SDF
    header: dict  # faces, clusters, lambda, segments, source, *_seconds


def reference_binary() -> str:
    """Path of cgal_segment, or skip (fail under CI) with the reason."""
    return cgal_binary("SDF_CGAL_SEGMENT", "cgal_segment")


def cgal_binary(variable: str, target: str) -> str:
    """Path of the CGAL reference program the environment variable names (tests/reference's
    `target`), or skip (fail under CI, where the comparison must run) with the reason."""
    path = os.environ.get(variable, "")
    if not path:
        problem = (
            f"{variable} is not set; build tests/reference (target {target}, needs "
            f"libcgal-dev) and point {variable} at the binary"
        )
    elif not (os.path.isfile(path) and os.access(path, os.X_OK)):
        problem = f"{variable}={path!r} is not an executable file"
    else:
        return path
    import pytest  # only here: the benchmark imports this module too, with the path set

    if os.environ.get("CI", "").strip().lower() not in _NOT_CI:
        pytest.fail(
            f"{problem} (CI is set, so the CGAL comparison may not be skipped)", pytrace=False
        )
    pytest.skip(problem)


def write_values(path: Path, values: np.ndarray) -> None:
    """One value per line at full double precision, as cgal_segment --values reads them."""
    np.savetxt(path, np.asarray(values, dtype=np.float64), fmt="%.17g")


def read_output(path: Path) -> CgalSegmentation:
    """The "# {json}" header and the "SDF CLUSTER SEGMENT" rows of a cgal_segment output."""
    with open(path) as f:
        first = f.readline()
    assert first.startswith("# "), f"{path}: no header line"
    header = json.loads(first[2:])
    table = np.loadtxt(path, dtype=np.float64, ndmin=2)
    assert table.shape == (header["faces"], 3), f"{path}: table {table.shape}, header {header}"
    return CgalSegmentation(
        sdf=table[:, 0],
        clusters=table[:, 1].astype(np.int64),
        labels=table[:, 2].astype(np.int64),
        header=header,
    )


def run(
    off: Path,
    out: Path,
    *,
    clusters: int = 5,
    smoothness: float = 0.26,
    values: np.ndarray | None = None,
    postprocess: bool = False,
    extra: tuple[str, ...] = (),
) -> CgalSegmentation:
    """CGAL's segmentation of the OFF mesh: from its own sdf_values, or from `values`."""
    cmd = [
        reference_binary(),
        str(off),
        str(out),
        "--clusters",
        str(clusters),
        "--lambda",
        repr(float(smoothness)),
        *extra,
    ]
    if values is not None:
        values_path = out.with_suffix(".values.txt")
        write_values(values_path, values)
        cmd += ["--values", str(values_path)]
        if postprocess:
            cmd.append("--postprocess")
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=3600)
    assert proc.returncode == 0, f"cgal_segment failed on {off}:\n{proc.stderr}"
    return read_output(out)
