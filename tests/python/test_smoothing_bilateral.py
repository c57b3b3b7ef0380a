# SPDX-License-Identifier: GPL-3.0-or-later
"""smoothing='bilateral': CGAL's post-processing filter, against CGAL and against the filter
written out in numpy."""

from __future__ import annotations

from collections import deque
from pathlib import Path

import cgal_segment_reference as cgal
import numpy as np
import pytest
import shape_diameter
from shapes import icosphere
from test_segmentation import read_off

DATA = Path(__file__).resolve().parents[1] / "data"


def numpy_bilateral(triangles, values, window):
    """The filter face by face: rings of edge neighbours by breadth-first search."""
    edges = {}
    for f, tri in enumerate(triangles):
        for c in range(3):
            edges.setdefault(tuple(sorted((tri[c], tri[(c + 1) % 3]))), []).append(f)
    neighbours = [[] for _ in triangles]
    for faces in edges.values():
        for a in faces:
            neighbours[a] += [b for b in faces if b != a]
    out = np.empty(len(values))
    for f in range(len(values)):
        ring = {f: 0}
        queue = deque([f])
        while queue:
            g = queue.popleft()
            if ring[g] == window:
                continue
            for h in neighbours[g]:
                if h not in ring:
                    ring[h] = ring[g] + 1
                    queue.append(h)
        faces = np.array(list(ring))
        levels = np.array(list(ring.values()), dtype=np.float64)
        diff = values[faces] - values[f]
        deviation = np.sqrt(np.mean(diff**2))
        if deviation == 0:
            out[f] = values[f]
            continue
        w = np.exp(-0.5 * (levels / (window / 2)) ** 2) * np.exp(
            -0.5 * (diff / (1.5 * deviation)) ** 2
        )
        out[f] = np.sum(w * values[faces]) / np.sum(w)
    return out


def test_matches_the_filter_written_out():
    v, t = icosphere(1.0, 2)
    values = np.random.default_rng(2).random(len(t))
    for window in (1, 3):
        ours = shape_diameter.smooth(v, t, values, "bilateral", window=window)
        np.testing.assert_allclose(ours, numpy_bilateral(t, values, window), rtol=1e-6)


def test_cgal_post_processing_is_fill_filter_rescale(tmp_path):
    """segment(postprocess=True) prepares values as CGAL's sdf_values_postprocessing does."""
    name = "psb/341.off"  # 3322 faces: CGAL's window is 2 rings
    v, t = read_off(DATA / name)
    values = shape_diameter.compute(v, t, rays=16).raw.astype(np.float64)
    ref = cgal.run(DATA / name, tmp_path / "out.txt", values=values, postprocess=True)
    ours = shape_diameter.segment(v, t, values, postprocess=True, mode="cgal")
    np.testing.assert_allclose(ours.values, ref.sdf, rtol=0, atol=1e-12)
    filtered = shape_diameter.smooth(v, t, values, "bilateral")
    rescaled = (filtered - filtered.min()) / (filtered.max() - filtered.min())
    np.testing.assert_allclose(rescaled, ref.sdf, atol=1e-6)


def test_compute_runs_it_and_a_constant_field_stays_constant():
    v, t = icosphere(1.0, 3)
    result = shape_diameter.compute(v, t, rays=8, smoothing="bilateral")
    np.testing.assert_allclose(
        result.values, shape_diameter.smooth(v, t, result.raw, "bilateral"), rtol=1e-6
    )
    assert "smooth: bilateral" in result.timings
    constant = shape_diameter.smooth(v, t, np.full(len(t), 0.5), "bilateral", window=2)
    assert (constant == np.float32(0.5)).all()


@pytest.mark.parametrize(
    "call, message",
    [
        (
            lambda v, t: shape_diameter.smooth(
                v, t, np.zeros(len(v)), "bilateral", points="vertices"
            ),
            "per-face values",
        ),
        (
            lambda v, t: shape_diameter.smooth(v, t, np.zeros(len(t)), "bilateral", window=0),
            "window must be",
        ),
        (
            lambda v, t: shape_diameter.compute(v, t, smoothing="bilateral", points="vertices"),
            "per-face values",
        ),
    ],
)
def test_bad_use_is_refused(call, message):
    v, t = icosphere(1.0, 1)
    with pytest.raises(ValueError, match=message):
        call(v, t)


def test_command_line_smooths_with_it(tmp_path):
    from shape_diameter import cli

    source = DATA / "psb" / "341.off"
    values = tmp_path / "values.npy"
    argv = [
        str(source),
        "-o",
        str(tmp_path / "out.ply"),
        "--rays",
        "8",
        "--smooth",
        "bilateral",
        "--values",
        str(values),
    ]
    assert cli.main(argv) == 0
    v, t = read_off(source)
    expected = shape_diameter.compute(v, t, rays=8, smoothing="bilateral")
    np.testing.assert_array_equal(np.load(values), expected.values)
