# SPDX-License-Identifier: GPL-3.0-or-later
"""Segmentation to a number of segments (segment(segments=N), --segments N): the count asked
for where some clusters and smoothness give it, else the nearest; bad counts refused."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import shape_diameter
from test_segmentation import dumbbell as dumbbell_mesh

DATA = Path(__file__).resolve().parents[1] / "data"
SEARCH = [(k, f) for f in (1.0, 0.4, 2.0) for k in range(2, 10)]


def dumbbell():
    """Two balls joined by a thin neck, and its SDF."""
    vertices, triangles = dumbbell_mesh()
    return vertices, triangles, shape_diameter.compute(vertices, triangles).values


def counts_of_the_search(vertices, triangles, values):
    """The segment count of every (clusters, smoothness) pair the search may try."""
    return {
        (k, f): shape_diameter.segment(
            vertices, triangles, values, clusters=k, smoothness=0.26 * f
        ).segment_count
        for k, f in SEARCH
    }


def test_the_count_asked_for_or_the_nearest():
    vertices, triangles, values = dumbbell()
    counts = counts_of_the_search(vertices, triangles, values)
    for asked in sorted(set(counts.values())):
        assert (
            shape_diameter.segment(vertices, triangles, values, segments=asked).segment_count
            == asked
        )
    # Counts no pair gives: the nearest one some pair gives.
    for asked in (1, max(counts.values()) + 5):
        got = shape_diameter.segment(vertices, triangles, values, segments=asked)
        nearest = min(abs(c - asked) for c in counts.values())
        assert abs(got.segment_count - asked) == nearest
        assert "count_search" in got.timings


def test_the_first_pair_that_gives_the_count_is_kept():
    # The search tries clusters nearest the given ones first, at the given smoothness first:
    # asking for what clusters=5 gives returns clusters=5's segmentation itself.
    vertices, triangles, values = dumbbell()
    plain = shape_diameter.segment(vertices, triangles, values)
    asked = shape_diameter.segment(vertices, triangles, values, segments=plain.segment_count)
    np.testing.assert_array_equal(asked.labels, plain.labels)


def test_the_choice_is_reported():
    # The clusters (len(mixture)) and smoothness the search chose give the same segmentation
    # when asked for directly.
    vertices, triangles, values = dumbbell()
    for asked in (1, 3, 40):
        got = shape_diameter.segment(vertices, triangles, values, segments=asked)
        assert any(got.smoothness == pytest.approx(0.26 * f) for f in (1.0, 0.4, 2.0))
        direct = shape_diameter.segment(
            vertices, triangles, values, clusters=len(got.mixture), smoothness=got.smoothness
        )
        np.testing.assert_array_equal(got.labels, direct.labels)
    assert shape_diameter.segment(vertices, triangles, values, smoothness=0.3).smoothness == 0.3


@pytest.mark.parametrize("bad", [0, -1, 4097, 2.5, "3", True])
def test_a_bad_count_is_refused(bad):
    vertices, triangles, values = dumbbell()
    with pytest.raises(ValueError, match="segments"):
        shape_diameter.segment(vertices, triangles, values, segments=bad)


def test_command_line_segments(tmp_path, capsys):
    cli = pytest.importorskip("shape_diameter.cli")
    source = DATA / "psb" / "81.off"
    argv = [str(source), "--rays", "8", "--json", "--threads", "2", "--segment", "--segments",
            "4", "-o", str(tmp_path / "ant.ply")]  # fmt: skip
    assert cli.main(argv) == 0
    report = json.loads(capsys.readouterr().out)["segments"]
    vertices, triangles = shape_diameter.load_mesh(source)
    result = shape_diameter.compute(vertices, triangles, rays=8, threads=2)
    expected = shape_diameter.segment(
        vertices, triangles, result.values, postprocess=True, segments=4
    )
    np.testing.assert_array_equal(np.load(tmp_path / "ant.segments.npy"), expected.labels)
    assert report["count"] == expected.segment_count
    assert report["segments_asked"] == 4
    assert report["clusters"] == len(expected.mixture)
    assert report["smoothness"] == expected.smoothness
    assert cli.main([str(source), "--segments", "4"]) == 2
    assert "--segments applies to --segment" in capsys.readouterr().err
