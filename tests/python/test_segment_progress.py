# SPDX-License-Identifier: GPL-3.0-or-later
"""segment(progress=...): fractions from 0 to 1 on the calling thread, shared with compute()'s
when the SDF is computed too, and a callback that raises stops the segmentation itself."""

from __future__ import annotations

import threading

import numpy as np
import pytest
import shape_diameter
from shapes import icosphere
from test_segmentation import dumbbell


class Stop(Exception):
    pass


@pytest.fixture(scope="module")
def noisy_sphere():
    """80k faces with noisy values: a graph cut of several moves and many pieces."""
    v, t = icosphere(1.0, 6)
    rng = np.random.default_rng(2)
    return v, t, rng.random(len(t))


def test_fractions_rise_to_one_on_the_calling_thread(noisy_sphere):
    v, t, values = noisy_sphere
    seen, threads = [], set()

    def progress(fraction):
        seen.append(fraction)
        threads.add(threading.get_ident())

    seg = shape_diameter.segment(v, t, values, progress=progress)
    assert threads == {threading.get_ident()}
    assert seen[0] == 0.0 and seen[-1] == 1.0
    assert (np.diff(seen) >= 0).all()
    # Each move of the graph cut (at least one sweep of the 5 clusters) reports.
    assert len(set(seen)) >= 10
    np.testing.assert_array_equal(seg.labels, shape_diameter.segment(v, t, values).labels)


def test_with_the_sdf_the_range_is_shared():
    v, t = dumbbell()
    seen = []
    seg = shape_diameter.segment(v, t, clusters=2, progress=seen.append)
    assert seg.segment_count == 3
    assert seen[0] == 0.0 and seen[-1] == 1.0
    assert (np.diff(seen) >= 0).all()
    sdf = [f for f in seen if f < 0.8]
    assert sdf and max(sdf) > 0.0  # the SDF's own progress, in [0, 0.8]
    assert sum(0.8 < f < 1.0 for f in seen) >= 5  # the segmentation's, in [0.8, 1]


@pytest.mark.parametrize("at", [0.0, 0.2, 0.5, 0.9])
def test_a_raising_callback_stops_the_segmentation(noisy_sphere, at):
    v, t, values = noisy_sphere
    seen = []

    def progress(fraction):
        seen.append(fraction)
        if fraction >= at:
            raise Stop(f"stop at {fraction}")

    with pytest.raises(Stop):
        shape_diameter.segment(v, t, values, progress=progress)
    assert seen[-1] >= at and all(f < at for f in seen[:-1])  # no call after the raise
    if 0.0 < at < 0.9:
        assert seen[-1] < 0.93  # inside the graph cut, not after it
    # Nothing is left behind: the next run gives what a run without a callback gives.
    again = shape_diameter.segment(v, t, values)
    np.testing.assert_array_equal(again.labels, shape_diameter.segment(v, t, values).labels)


def test_a_raise_during_the_sdf_stops_before_segmenting():
    v, t = dumbbell()
    seen = []

    def progress(fraction):
        seen.append(fraction)
        if fraction > 0.1:
            raise Stop()

    with pytest.raises(Stop):
        shape_diameter.segment(v, t, progress=progress)
    assert max(seen) < 0.8


def test_progress_must_be_callable():
    v, t = icosphere(1.0, 1)
    with pytest.raises(ValueError, match="progress must be a callable"):
        shape_diameter.segment(v, t, np.zeros(len(t)), progress=3)
