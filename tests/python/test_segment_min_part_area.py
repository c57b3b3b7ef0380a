# SPDX-License-Identifier: GPL-3.0-or-later
"""A minimum part size (segment(min_part_area=...)): a small segment joins the adjacent
segment it shares the longest boundary with, separate solids never join, every face keeps a
label, 0 changes nothing, and a bad share is refused."""

from __future__ import annotations

import numpy as np
import pytest
import shape_diameter
from shapes import icosphere
from test_segmentation import dumbbell


def grid(columns: int, rows: int):
    """A flat grid of unit cells, two triangles each; cell (i, j) gives faces 2 (j columns + i)
    and the next one."""
    xs, ys = np.meshgrid(np.arange(columns + 1.0), np.arange(rows + 1.0))
    vertices = np.stack([xs.ravel(), ys.ravel(), np.zeros(xs.size)], axis=1)
    triangles = []
    for j in range(rows):
        for i in range(columns):
            a = j * (columns + 1) + i
            b, c = a + 1, a + columns + 1
            triangles += [[a, b, c + 1], [a, c + 1, c]]
    return vertices, np.array(triangles, dtype=np.int64)


def three_blocks(owner: int):
    """A 10 x 4 grid's values per face: a block on the left (1.0), one on the right (3.0) and
    a 1 x 2 piece (2.0) at rows 0-1 of column 4, whose rows 2-3 go to the block `owner`
    (0: left, 2: right): the piece shares 3 units of boundary with that block, 2 with the
    other."""
    cells = []
    for j in range(4):
        for i in range(10):
            piece = 0 if i < 4 else 2
            if i == 4:
                piece = 1 if j < 2 else owner
            cells.append(1.0 + piece)
    return np.repeat(cells, 2)


@pytest.mark.parametrize("owner", [0, 2])
def test_a_small_piece_joins_its_longest_boundary(owner):
    vertices, triangles = grid(10, 4)
    values = three_blocks(owner)
    # smoothness 0: the clusters are the three values as they are.
    plain = shape_diameter.segment(vertices, triangles, values, clusters=3, smoothness=0.0)
    assert plain.segment_count == 3
    np.testing.assert_array_equal(plain.labels, (values - 1).astype(np.int32))
    joined = shape_diameter.segment(
        vertices, triangles, values, clusters=3, smoothness=0.0, min_part_area=0.1
    )
    assert joined.segment_count == 2
    piece = values == 2.0
    into = values == 1.0 + owner
    assert (joined.labels[piece] == joined.labels[into][0]).all()
    assert len(np.unique(joined.labels[into | piece])) == 1
    assert len(np.unique(joined.labels[~(into | piece)])) == 1
    np.testing.assert_array_equal(joined.clusters, plain.clusters)  # clusters stay
    np.testing.assert_allclose(joined.segment_area.sum(), 40.0)
    assert len(joined.boundaries["length"]) == 1


def test_separate_solids_never_join():
    """A dumbbell and a small ball apart: the neck (7% of the area) joins a ball; the small
    ball (2%), below the share too, has no neighbour and stays a segment of its own."""
    v1, t1 = dumbbell()
    v2, t2 = icosphere(0.2, 3)
    vertices = np.vstack([v1, v2 + [0.0, 5.0, 0.0]])
    triangles = np.vstack([t1, t2 + len(v1)])
    values = shape_diameter.compute(vertices, triangles).values
    plain = shape_diameter.segment(vertices, triangles, values, clusters=2, postprocess=True)
    seg = shape_diameter.segment(
        vertices, triangles, values, clusters=2, postprocess=True, min_part_area=0.1
    )
    assert plain.segment_count == 4 and seg.segment_count == 3
    first, second = seg.labels[: len(t1)], seg.labels[len(t1) :]
    assert len(np.unique(second)) == 1 and second[0] not in first
    assert len(np.unique(first)) == 2
    areas = seg.segment_area / seg.segment_area.sum()
    assert areas[second[0]] < 0.1 and (np.delete(areas, second[0]) >= 0.1).all()
    assert (np.diff(seg.segment_mean) >= 0).all()  # still numbered by mean value
    assert seg.labels.min() == 0 and seg.labels.max() == seg.segment_count - 1
    assert (seg.vertex_labels >= 0).all()


def test_zero_changes_nothing_and_every_face_keeps_a_label():
    vertices, triangles = dumbbell()
    rng = np.random.default_rng(5)
    values = shape_diameter.compute(vertices, triangles).values
    values = values + rng.normal(0.0, 0.2, len(values))  # speckles: many small pieces
    for mode in ("auto", "cgal"):
        default = shape_diameter.segment(vertices, triangles, values, mode=mode, smoothness=0.0)
        zero = shape_diameter.segment(
            vertices, triangles, values, mode=mode, smoothness=0.0, min_part_area=0.0
        )
        np.testing.assert_array_equal(zero.labels, default.labels)
        assert zero.segment_count == default.segment_count > 3
        joined = shape_diameter.segment(
            vertices, triangles, values, mode=mode, smoothness=0.0, min_part_area=0.02
        )
        assert 1 <= joined.segment_count < default.segment_count
        assert joined.labels.shape == default.labels.shape
        assert set(np.unique(joined.labels)) == set(range(joined.segment_count))
        shares = joined.segment_area / joined.segment_area.sum()
        assert (shares >= 0.02).all()  # one solid: every part reaches the share


@pytest.mark.parametrize("share", [-0.1, 1.0, 1.5, float("nan"), float("inf"), "0.1", True])
def test_a_bad_share_is_refused(share):
    v, t = icosphere(1.0, 1)
    with pytest.raises(ValueError, match=r"min_part_area must be a share in \[0, 1\)"):
        shape_diameter.segment(v, t, np.zeros(len(t)), min_part_area=share)
