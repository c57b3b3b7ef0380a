# SPDX-License-Identifier: GPL-3.0-or-later
"""The cgal_segment reference itself: what the segmentation tests and benchmark rely on.

Checked on a small mesh of the Princeton Segmentation Benchmark (tests/data/psb/341.off, a
bearing, 3,322 faces): every face labelled, segment ids 0..S-1 with S the count CGAL returned
and S <= faces, each segment a connected set of faces of one cluster in the file's face order
(a face order that differed from the file's would break this connectivity), segments numbered by
increasing mean SDF, the SDF post-processed into [0, 1], and the same result when CGAL's own
values are given back through --values.
"""

from __future__ import annotations

import subprocess
from pathlib import Path

import cgal_segment_reference as ref
import numpy as np
import pytest
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

MESH = Path(__file__).resolve().parents[1] / "data" / "psb" / "341.off"


def _read_off_triangles(path: Path) -> np.ndarray:
    tokens = path.read_text().split()
    assert tokens[0] == "OFF"
    nv, nf = int(tokens[1]), int(tokens[2])
    rows = np.array(tokens[4 + 3 * nv : 4 + 3 * nv + 4 * nf], dtype=np.int64).reshape(nf, 4)
    assert np.all(rows[:, 0] == 3), "triangles only"
    return rows[:, 1:]


def _edge_neighbours(triangles: np.ndarray) -> np.ndarray:
    """Pairs of faces (k, 2) that share an edge used by exactly two faces."""
    edges = np.sort(triangles[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    faces = np.repeat(np.arange(len(triangles)), 3)
    order = np.lexsort((edges[:, 1], edges[:, 0]))
    edges, faces = edges[order], faces[order]
    same = np.all(edges[1:] == edges[:-1], axis=1)
    return np.stack([faces[:-1][same], faces[1:][same]], axis=1)


def _components_within_clusters(clusters: np.ndarray, pairs: np.ndarray) -> np.ndarray:
    keep = clusters[pairs[:, 0]] == clusters[pairs[:, 1]]
    a, b = pairs[keep, 0], pairs[keep, 1]
    n = len(clusters)
    graph = coo_matrix((np.ones(len(a)), (a, b)), shape=(n, n))
    return connected_components(graph, directed=False)[1]


@pytest.fixture(scope="module")
def cgal_run(tmp_path_factory) -> ref.CgalSegmentation:
    return ref.run(MESH, tmp_path_factory.mktemp("cgal_segment") / "341.txt")


def test_every_face_labelled_and_segments_counted(cgal_run):
    faces = len(_read_off_triangles(MESH))
    header = cgal_run.header
    assert header["faces"] == faces and header["source"] == "sdf_values"
    assert header["clusters"] == 5 and header["lambda"] == pytest.approx(0.26)
    segments = header["segments"]
    assert 1 <= segments <= faces
    assert np.array_equal(np.unique(cgal_run.labels), np.arange(segments))
    assert cgal_run.clusters.min() >= 0 and cgal_run.clusters.max() < 5
    assert np.all(np.isfinite(cgal_run.sdf))
    # Post-processing ends with a linear normalisation to [0, 1].
    assert cgal_run.sdf.min() == pytest.approx(0.0, abs=1e-12)
    assert cgal_run.sdf.max() == pytest.approx(1.0, abs=1e-12)
    for key in (
        "sdf_seconds",
        "cluster_seconds",
        "segmentation_seconds",
        "segmentation_cpu_seconds",
    ):
        assert header[key] > 0.0


def test_segments_are_connected_components_of_clusters_in_file_order(cgal_run):
    pairs = _edge_neighbours(_read_off_triangles(MESH))
    components = _components_within_clusters(cgal_run.clusters, pairs)
    # Segment and component partitions are the same: a bijection between their ids.
    joint = np.unique(np.stack([cgal_run.labels, components], axis=1), axis=0)
    assert len(joint) == cgal_run.header["segments"] == components.max() + 1
    # Segments are numbered by increasing mean SDF.
    means = np.bincount(cgal_run.labels, weights=cgal_run.sdf) / np.bincount(cgal_run.labels)
    assert np.all(np.diff(means) >= 0)


def test_given_values_reproduce_cgal_own(cgal_run, tmp_path):
    again = ref.run(MESH, tmp_path / "again.txt", values=cgal_run.sdf)
    assert again.header["source"] == "values" and again.header["sdf_seconds"] == 0.0
    assert np.array_equal(again.sdf, cgal_run.sdf)
    assert np.array_equal(again.clusters, cgal_run.clusters)
    assert np.array_equal(again.labels, cgal_run.labels)


def test_other_cluster_count_and_lambda(cgal_run, tmp_path):
    two = ref.run(MESH, tmp_path / "two.txt", clusters=2, smoothness=0.6, values=cgal_run.sdf)
    assert two.header["clusters"] == 2 and two.header["lambda"] == pytest.approx(0.6)
    assert set(np.unique(two.clusters)) <= {0, 1}
    assert np.array_equal(np.unique(two.labels), np.arange(two.header["segments"]))


def test_refuses_polygons_and_short_value_files(tmp_path):
    binary = ref.reference_binary()
    quad = tmp_path / "quad.off"
    quad.write_text("OFF\n4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n")
    proc = subprocess.run(
        [binary, str(quad), str(tmp_path / "q.txt")], capture_output=True, text=True, timeout=60
    )
    assert proc.returncode == 2 and "not triangles" in proc.stderr
    short = tmp_path / "short.txt"
    short.write_text("0.5\n")
    proc = subprocess.run(
        [binary, str(MESH), str(tmp_path / "s.txt"), "--values", str(short)],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert proc.returncode == 2 and "1 values for 3322 faces" in proc.stderr
