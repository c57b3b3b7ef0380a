# SPDX-License-Identifier: GPL-3.0-or-later
"""The test-only module shape_diameter._testing: its overrides hold inside their block only,
refuse unknown names and bad values, and reach the computations; its functions answer."""

import numpy as np
import pytest
from shape_diameter import _testing
from shapes import box

DEFAULTS = {
    "cpu_without_avx2": False,
    "no_sliver_cutting": False,
    "opencl_kernel": "engine",
    "opencl_tree": "engine",
    "opencl_extra_options": "",
    "opencl_staging_chunk": 0,
    "opencl_lose_device_after": -1,
}


def test_overrides_hold_inside_their_block_and_nest():
    assert _testing.current_overrides() == DEFAULTS
    with _testing.overrides(opencl_kernel="bvh_per_ray", opencl_staging_chunk=4096):
        with _testing.overrides(opencl_tree="host"):
            now = _testing.current_overrides()
            assert now["opencl_kernel"] == "bvh_per_ray" and now["opencl_tree"] == "host"
            assert now["opencl_staging_chunk"] == 4096
        assert _testing.current_overrides()["opencl_tree"] == "engine"
    assert _testing.current_overrides() == DEFAULTS


def test_overrides_are_put_back_when_the_block_raises():
    with pytest.raises(KeyError), _testing.overrides(cpu_without_avx2=True):
        assert _testing.current_overrides()["cpu_without_avx2"]
        raise KeyError("out")
    assert _testing.current_overrides() == DEFAULTS


def test_unknown_names_and_bad_values_are_refused_before_anything_is_set():
    with pytest.raises(TypeError, match="no test override named 'opencl_wide'"):
        _testing.overrides(opencl_wide=True)
    with pytest.raises(ValueError, match="opencl_tree='gpu': use engine, host, device"):
        _testing.set_overrides(cpu_without_avx2=True, opencl_tree="gpu")
    with pytest.raises(TypeError, match="opencl_staging_chunk='64k': a value of the wrong type"):
        _testing.set_overrides(opencl_kernel="bvh_per_ray", opencl_staging_chunk="64k")
    assert _testing.current_overrides() == DEFAULTS


def slivers():
    """A box crossed by 50 long needles: each one's bounding box is far larger than its area,
    so the BVH builder cuts it into pieces."""
    v, f = box(1.0, 1.0, 1.0, 1)
    rng = np.random.default_rng(4)
    a = rng.uniform(-0.5, 0.5, (50, 3))
    k = len(v) + np.arange(50)
    v = np.vstack([v, a, -a, -a + 1e-4])
    f = np.vstack([f, np.stack([k, k + 50, k + 100], 1)])
    return v, f


def test_no_sliver_cutting_builds_one_reference_a_face():
    v, f = slivers()
    cut = _testing.bvh_stats(v, f)["triangles"]
    with _testing.overrides(no_sliver_cutting=True):
        uncut = _testing.bvh_stats(v, f)["triangles"]
    assert uncut == len(f) < cut


def test_weld_vertices_merges_a_cubes_corners_given_once_a_face():
    v, f = box(1.0, 1.0, 1.0, 1)
    corners = v[f].reshape(-1, 3)  # three vertices of its own a face
    soup = np.arange(len(corners)).reshape(-1, 3)
    merged, count = _testing.weld_vertices(corners, soup, 1e-6)
    assert count == 8
    # Corners at one position weld to one vertex, corners elsewhere never do.
    same = np.all(corners[:, None] == corners[None], axis=2)
    np.testing.assert_array_equal(merged[:, None] == merged[None], same)
