# SPDX-License-Identifier: GPL-3.0-or-later
"""docs/python.md documents the whole Python API (every option, every Result field), with the
ranges the code enforces, and its note on scale matches what the rule gives: a reader who
looks up an option, a field or a range finds it, and finds it right."""

import dataclasses
import inspect
import re
from pathlib import Path

import numpy as np
import pytest
import shape_diameter
from shape_diameter.smoothing import OPTIONS
from shapes import box, icosphere

# The Python package's reference (the Blender add-on's API, in docs/blender.md, has fields of
# its own).
PYTHON = (Path(__file__).resolve().parents[2] / "docs" / "python.md").read_text()


def _table_row(name):
    rows = [line for line in PYTHON.splitlines() if line.startswith(f"| `{name}` |")]
    assert len(rows) == 1, f"no row for `{name}` in docs/python.md's compute() table"
    return rows[0]


@pytest.mark.parametrize("function", ["compute", "smooth"])
def test_every_keyword_is_documented(function):
    signature = inspect.signature(getattr(shape_diameter, function))
    for name, parameter in signature.parameters.items():
        if parameter.default is not parameter.empty:  # the options (not the mesh, values)
            assert f"{name}=" in PYTHON or f"`{name}`" in PYTHON, (function, name)


@pytest.mark.parametrize("method", ["kring", "projected", "texture", "bilateral"])
def test_every_smoothing_option_is_in_the_methods_row(method):
    row = next(line for line in PYTHON.splitlines() if line.startswith(f"| `{method}` |"))
    for option in OPTIONS[method]:
        assert f"`{option}`" in row, (method, option)


def test_every_result_field_is_documented():
    for field in dataclasses.fields(shape_diameter.Result):
        assert re.search(rf"\b[rR]esult\.{field.name}\b", PYTHON), field.name


@pytest.mark.parametrize(
    ("name", "low", "high"), [("octree_depth", 0, 16), ("octree_leaf_size", 1, 2**31 - 1)]
)
def test_octree_ranges_are_the_ones_checked(name, low, high):
    vertices, triangles = icosphere(1.0, 1)
    for value in (low, high):  # accepted
        shape_diameter.compute(vertices, triangles, rays=1, accel="octree", engine="cpu",
                               **{name: value})  # fmt: skip
    for value in (low - 1, high + 1):
        with pytest.raises(ValueError, match=re.escape(f"[{low}, {high}]")):
            shape_diameter.compute(vertices, triangles, accel="octree", **{name: value})
    high_text = "16" if high == 16 else "2^31 − 1"
    assert f"{low}..{high_text}" in _table_row(name)


def test_the_scale_note_is_what_the_rule_gives():
    note = PYTHON[PYTHON.index("**Scale.**") :]
    assert "a sphere of radius r gives 0.767 × 2r" in note
    assert "a wide slab of thickness h gives 1.25 h" in note
    for radius in (1.0, 3.0):
        vertices, triangles = icosphere(radius, 5)
        raw = shape_diameter.compute(vertices, triangles).raw
        np.testing.assert_allclose(raw / (2 * radius), 0.767, atol=0.0006)
    h = 0.1
    vertices, triangles = box(40.0, 40.0, h, divisions=40)
    raw = shape_diameter.compute(vertices, triangles).raw
    centroids = vertices[triangles].mean(axis=1)
    inner = (np.abs(centroids[:, :2]) < 5.0).all(axis=1)  # far from the rim
    assert inner.sum() > 100
    np.testing.assert_allclose(raw[inner] / h, 1.25, atol=0.006)
