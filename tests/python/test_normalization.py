# SPDX-License-Identifier: GPL-3.0-or-later
"""shape_diameter.normalize (native, parallel) against the numpy expression it replaced."""
import numpy as np
import pytest
import shape_diameter as sd


def numpy_normalize(values, method):
    v = np.asarray(values, dtype=np.float64)
    lo, hi = (float(v.min()), float(v.max())) if v.size else (0.0, 0.0)
    out = (v - lo) / (hi - lo) if hi > lo else np.zeros_like(v)
    if method == "log":
        out = np.log1p(4.0 * out) / np.log1p(4.0)
    return np.clip(out, 0.0, 1.0).astype(np.float32)


@pytest.mark.parametrize("dtype", [np.float32, np.float64, np.int32])
@pytest.mark.parametrize("method", ["linear", "log"])
@pytest.mark.parametrize("n", [0, 1, 7, 300_001])
def test_same_bits_as_numpy(dtype, method, n):
    # 300,001 values: several parallel chunks, one of them short.
    values = (np.random.default_rng(n).random(n) * 50 + 1).astype(dtype)
    got = sd.normalize(values, method)
    assert got.dtype == np.float32 and got.shape == values.shape
    np.testing.assert_array_equal(got, numpy_normalize(values, method))


def test_range_shape_and_thread_count():
    values = np.random.default_rng(3).normal(size=(1000, 3))
    one, many = sd.normalize(values, "log", threads=1), sd.normalize(values, "log", threads=4)
    np.testing.assert_array_equal(one, many)
    assert one.shape == (1000, 3) and one.min() == 0.0 and one.max() == 1.0


def test_constant_and_nan_map_to_zero():
    np.testing.assert_array_equal(sd.normalize(np.full(5, 2.5), "linear"), np.zeros(5))
    np.testing.assert_array_equal(sd.normalize(np.array([1.0, np.nan, 3.0]), "log"), np.zeros(3))


def test_unknown_method():
    with pytest.raises(ValueError, match="normalize must be one of"):
        sd.normalize(np.ones(3), "cubic")


def test_infinite_values_as_numpy_had_them():
    # An infinite value makes the range infinite: numpy gave 0 for the finite values and NaN
    # for the infinite one (inf / inf), and so does the native version.
    for values in ([0.0, 1.0, np.inf], [-np.inf, 0.0], [np.inf, np.inf]):
        v = np.array(values)
        with np.errstate(invalid="ignore"):
            expected = numpy_normalize(v, "linear")
        np.testing.assert_array_equal(sd.normalize(v, "linear"), expected)
