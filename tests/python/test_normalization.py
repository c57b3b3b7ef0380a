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


def test_constant_maps_to_zero():
    np.testing.assert_array_equal(sd.normalize(np.full(5, 2.5), "linear"), np.zeros(5))


def test_unknown_method():
    with pytest.raises(ValueError, match="normalize must be one of"):
        sd.normalize(np.ones(3), "cubic")


@pytest.mark.parametrize("method", ["linear", "log"])
@pytest.mark.parametrize(
    "values",
    [[1.0, np.nan, 3.0], [1.0, np.inf, 3.0], [-np.inf, 0.0], [0.0, 1e308, -1e308], [[0.0, 4e38]]],
    ids=["nan", "inf", "-inf", "beyond float32", "beyond float32 2-D"],
)
def test_values_not_finite_in_float32_are_refused_as_smooth_refuses_them(values, method):
    # A NaN or an infinite value has no range to map (they once gave 0 everywhere, or NaN),
    # and float64 values beyond float32 overflowed the range: smooth()'s rule and message.
    with pytest.raises(ValueError, match="values must be finite: .* too large for float32"):
        sd.normalize(np.array(values), method)


@pytest.mark.parametrize("threads", [-1, 2**40, 1.5, True, "2"])
def test_a_bad_thread_count_is_a_value_error(threads):
    with pytest.raises(ValueError, match=r"threads must be an integer in \[0, 4096\]"):
        sd.normalize(np.ones(3), "linear", threads=threads)


def test_values_that_are_not_numbers_are_a_value_error():
    with pytest.raises(ValueError, match="values must be real numbers"):
        sd.normalize(np.array(["1", "2"]), "linear")
