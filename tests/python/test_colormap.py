# SPDX-License-Identifier: GPL-3.0-or-later
"""The embedded viridis: right colours, right shape, readable for missing values."""

import numpy as np
import pytest
from shape_diameter.colormap import NAN_RGBA, colormap


def test_shape_and_dtype():
    rgba = colormap(np.linspace(0.0, 1.0, 7, dtype=np.float32))
    assert rgba.shape == (7, 4)
    assert rgba.dtype == np.uint8
    assert np.all(rgba[:, 3] == 255)
    assert colormap([]).shape == (0, 4)
    # Any input shape is flattened: one colour per value.
    assert colormap(np.zeros((2, 3))).shape == (6, 4)


def test_endpoints_are_viridis():
    # matplotlib's viridis(0.0) and viridis(1.0) in 8 bits.
    low, high = colormap([0.0, 1.0])[:, :3].astype(int)
    assert np.abs(low - (68, 1, 84)).max() <= 1
    assert np.abs(high - (253, 231, 37)).max() <= 1


def _full_viridis():
    """Matplotlib's 256-entry viridis, from matplotlib or from the copy recent trimesh ships."""
    try:
        from matplotlib import colormaps

        return colormaps["viridis"](np.linspace(0.0, 1.0, 256))[:, :3]
    except ImportError:
        pass
    try:
        from trimesh.resources import get_json

        return np.asarray(get_json("color_map.json.gzip")["viridis"], dtype=float)
    except (ImportError, OSError, KeyError):
        pytest.skip("no full viridis table here (needs matplotlib, or a trimesh that ships one)")


def test_whole_map_matches_an_independent_copy_of_viridis():
    # The embedded subsample with linear interpolation must reproduce all 256
    # entries of the full table to 1/255.
    reference = _full_viridis()
    assert reference.shape == (256, 3)
    ours = colormap(np.linspace(0.0, 1.0, 256))[:, :3].astype(float)
    assert np.abs(ours - 255.0 * reference).max() <= 1.0


def _cie_lightness(rgb8):
    """CIE L* of sRGB colours (D65), the perceptual lightness."""
    c = rgb8 / 255.0
    linear = np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)
    y = linear @ np.array([0.2126, 0.7152, 0.0722])
    return np.where(y > (6 / 29) ** 3, 116 * np.cbrt(y) - 16, y * (29 / 3) ** 3)


def test_lightness_rises_monotonically():
    # What makes the map perceptual: a thicker part is always a lighter colour.
    lightness = _cie_lightness(colormap(np.linspace(0.0, 1.0, 64))[:, :3].astype(float))
    assert np.all(np.diff(lightness) > 0)
    assert lightness[0] < 20 and lightness[-1] > 85


def test_out_of_range_values_are_clipped():
    rgba = colormap([-3.0, 0.0, 1.0, 7.0, -np.inf, np.inf])
    np.testing.assert_array_equal(rgba[0], rgba[1])
    np.testing.assert_array_equal(rgba[3], rgba[2])
    np.testing.assert_array_equal(rgba[4], rgba[1])
    np.testing.assert_array_equal(rgba[5], rgba[2])


def test_nan_is_neutral_grey():
    rgba = colormap([0.5, np.nan, 0.2])
    np.testing.assert_array_equal(rgba[1], NAN_RGBA)
    r, g, b, a = (int(x) for x in rgba[1])
    assert r == g == b and a == 255
    # The grey is not a colour of the map itself.
    everything = colormap(np.linspace(0.0, 1.0, 1001))
    assert not np.any(np.all(everything == np.asarray(NAN_RGBA, dtype=np.uint8), axis=1))
    # NaN does not disturb the neighbours.
    np.testing.assert_array_equal(rgba[[0, 2]], colormap([0.5, 0.2]))


def test_same_colours_as_np_interp_bit_for_bit():
    # colormap() computes np.interp's arithmetic itself (one knot search for three channels):
    # every value, the knots and their neighbours included, gives the same doubles.
    from shape_diameter import colormap as module

    knots = module._POSITIONS
    position = np.clip(np.concatenate([np.random.default_rng(5).random(200_000), knots,
                                       np.nextafter(knots, 2.0), np.nextafter(knots, -1.0),
                                       [0.0, 1.0, 5e-324]]), 0.0, 1.0)  # fmt: skip
    reference = np.column_stack(
        [np.interp(position, knots, module._VIRIDIS[:, c]) for c in range(3)]
    )
    assert np.array_equal(module._interpolate(position).view(np.uint64), reference.view(np.uint64))
