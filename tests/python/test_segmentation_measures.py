# SPDX-License-Identifier: GPL-3.0-or-later
"""bench/segmentation_measures.py, the Princeton Segmentation Benchmark's measures, against
their definitions written out face by face and pair by pair on small labelings, and on a
mesh where the cut distance is known."""

from __future__ import annotations

import importlib.util
from itertools import combinations
from pathlib import Path

import numpy as np
import pytest


def _load_measures():
    """bench/segmentation_measures.py by its path: bench/ is not put on sys.path, where its
    distributed.py would hide dask's package from every later import (spawned Dask workers
    take the test process's path and then failed to start)."""
    path = Path(__file__).resolve().parents[2] / "bench" / "segmentation_measures.py"
    spec = importlib.util.spec_from_file_location("segmentation_measures", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


m = _load_measures()


def _random_labelings(seed: int, n: int = 40):
    rng = np.random.default_rng(seed)
    return rng.integers(0, 4, n), rng.integers(0, 6, n) * 7 + 3  # any label values


@pytest.mark.parametrize("seed", range(5))
def test_rand_error_counts_disagreeing_pairs(seed):
    a, b = _random_labelings(seed)
    pairs = list(combinations(range(len(a)), 2))
    disagree = sum((a[i] == a[j]) != (b[i] == b[j]) for i, j in pairs)
    assert m.rand_error(a, b) == pytest.approx(disagree / len(pairs), rel=1e-12)


@pytest.mark.parametrize("seed", range(5))
def test_hamming_and_consistency_from_their_definitions(seed):
    a, b = _random_labelings(seed)
    n = len(a)

    def directional(x, y):  # D(x => y): y's segments outside their best-overlapping x segment
        total = 0
        for s in np.unique(y):
            inside = y == s
            best = max(np.sum(inside & (x == r)) for r in np.unique(x))
            total += inside.sum() - best
        return total

    hd, missing, false_alarm = m.hamming(a, b)
    assert missing == pytest.approx(directional(a, b) / n)
    assert false_alarm == pytest.approx(directional(b, a) / n)
    assert hd == pytest.approx((missing + false_alarm) / 2)

    def refinement(x, y, f):  # |R(x, f) \ R(y, f)| / |R(x, f)|
        region_x, region_y = x == x[f], y == y[f]
        return np.sum(region_x & ~region_y) / region_x.sum()

    e_ab = np.array([refinement(a, b, f) for f in range(n)])
    e_ba = np.array([refinement(b, a, f) for f in range(n)])
    gce, lce = m.consistency(a, b)
    assert gce == pytest.approx(min(e_ab.sum(), e_ba.sum()) / n)
    assert lce == pytest.approx(np.minimum(e_ab, e_ba).sum() / n)


def test_identical_and_refined_labelings():
    a, _ = _random_labelings(7)
    assert m.rand_error(a, a + 10) == 0.0
    assert m.hamming(a, a)[0] == 0.0
    assert m.consistency(a, a) == (0.0, 0.0)
    refined = a * 2 + (np.arange(len(a)) % 2)  # every segment of a split in two
    assert m.consistency(a, refined)[0] == 0.0  # consistency forgives refinement
    assert m.rand_error(a, refined) > 0.0


def _strip(columns: int):
    """A flat strip of unit squares along x (two triangles each), 0 <= x <= columns."""
    xs = np.arange(columns + 1, dtype=np.float64)
    vertices = np.concatenate(
        [
            np.c_[xs, np.zeros_like(xs), np.zeros_like(xs)],
            np.c_[xs, np.ones_like(xs), np.zeros_like(xs)],
        ]
    )
    top = columns + 1
    triangles = []
    for i in range(columns):
        triangles += [[i, i + 1, top + i + 1], [i, top + i + 1, top + i]]
    return vertices, np.array(triangles, dtype=np.int64)


def test_cut_discrepancy_of_parallel_cuts():
    vertices, triangles = _strip(10)
    cuts = m.MeshCuts(vertices, triangles)
    column = np.repeat(np.arange(10), 2)
    at_3, at_6 = (column >= 3).astype(int), (column >= 6).astype(int)
    assert cuts.cut_discrepancy(at_3, at_3) == 0.0
    # Cuts across the strip at x = 3 and x = 6: every point of one is 3 from the other
    # (along the bottom and top edges of the strip) in both directions.
    expected = (3.0 + 3.0) / cuts.average_radius
    assert cuts.cut_discrepancy(at_3, at_6) == pytest.approx(expected)
    assert cuts.cut_discrepancy(at_6, at_3) == pytest.approx(expected)
    assert np.isnan(cuts.cut_discrepancy(np.zeros(20, int), at_3))  # one segment: no cut
