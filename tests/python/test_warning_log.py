# SPDX-License-Identifier: GPL-3.0-or-later
"""Result.warnings and collect_warnings(): the package's warnings where a caller can read
them, on any thread (warnings.catch_warnings swaps process-wide filters)."""

import threading
import warnings
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest
import shape_diameter
import shapes

# One triangle: no ray of any point finds another side (a warning every time).
TRIANGLE = (np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]), np.array([[0, 1, 2]]))
NO_RAY = "no ray of any point found the other side"


def uvs_outside_the_square(faces):
    """Each face's UVs a small triangle at (-2, -2): in no UDIM tile, with area."""
    return np.tile(np.array([[-2.0, -2.0], [-1.9, -2.0], [-2.0, -1.9]]), (faces, 1, 1))


def test_compute_keeps_its_warnings_and_still_issues_them_naming_the_callers_line():
    with pytest.warns(RuntimeWarning, match=NO_RAY) as seen:
        result = shape_diameter.compute(*TRIANGLE)
    assert len(result.warnings) == 1 and result.warnings[0].startswith(NO_RAY)
    assert str(seen[0].message) == result.warnings[0]
    assert seen[0].filename == __file__  # the caller's line, not the package's


def test_a_warning_names_the_callers_line_from_inside_another_call():
    # A review's: compute() inside another's progress callback, and smooth() there, named a
    # line of the package (a count of frames, one per active compute()).
    V, F = shapes.icosphere(1.0, 2)
    seen = []

    def progress(fraction):
        if not seen:
            with warnings.catch_warnings(record=True) as inner:
                warnings.simplefilter("always")
                shape_diameter.compute(*TRIANGLE)
                shape_diameter.smooth(
                    V,
                    F,
                    np.ones(len(F), dtype=np.float32),
                    "texture",
                    uvs=uvs_outside_the_square(len(F)),
                    texture_size=16,
                )
            seen.extend(inner)

    shape_diameter.compute(V, F, progress=progress)
    assert len(seen) == 2
    assert all(w.filename == __file__ for w in seen), [(w.filename, w.lineno) for w in seen]


def test_a_mesh_with_nothing_to_say_has_no_warnings():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert shape_diameter.compute(*shapes.icosphere(1.0, 2)).warnings == []


def test_collect_warnings_keeps_them_from_the_warnings_module():
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # one issued would raise here
        with shape_diameter.collect_warnings() as caught:
            first = shape_diameter.compute(*TRIANGLE)
            shape_diameter.compute(*TRIANGLE, points="vertices")
    assert len(caught) == 2 and all(m.startswith(NO_RAY) for m in caught)
    assert first.warnings == caught[:1]  # each result keeps its own
    # Outside the block, issued again.
    with pytest.warns(RuntimeWarning, match=NO_RAY):
        shape_diameter.compute(*TRIANGLE)


def test_collect_warnings_takes_smooths_warnings_too():
    # smooth() with every face's UVs outside every UDIM tile.
    V, F = shapes.icosphere(1.0, 2)
    uvs = uvs_outside_the_square(len(F))
    with shape_diameter.collect_warnings() as caught:
        shape_diameter.smooth(
            V, F, np.ones(len(F), dtype=np.float32), "texture", uvs=uvs, texture_size=16
        )
    assert len(caught) == 1 and "outside every UDIM tile" in caught[0]


def test_threads_collect_their_own_warnings_only():
    # Each worker collects its own, while the main thread issues as ever.
    def run(count):
        with shape_diameter.collect_warnings() as caught:
            for _ in range(count):
                shape_diameter.compute(*TRIANGLE)
        return len(caught)

    with ThreadPoolExecutor(3) as pool:
        counts = list(pool.map(run, [1, 2, 3, 4]))
    assert counts == [1, 2, 3, 4]
    with pytest.warns(RuntimeWarning, match=NO_RAY):
        shape_diameter.compute(*TRIANGLE)


def test_a_quiet_thread_does_not_silence_another():
    inside, release = threading.Event(), threading.Event()

    def quiet():
        with shape_diameter.collect_warnings():
            inside.set()
            release.wait(10)

    worker = threading.Thread(target=quiet)
    worker.start()
    try:
        assert inside.wait(10)
        with pytest.warns(RuntimeWarning, match=NO_RAY):  # this thread is not collecting
            shape_diameter.compute(*TRIANGLE)
    finally:
        release.set()
        worker.join()
