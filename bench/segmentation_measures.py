# SPDX-License-Identifier: GPL-3.0-or-later
"""The Princeton Segmentation Benchmark's measures between two segmentations of one mesh.

Every measure is an error (0 when the two agree, lower is better) and counts faces, as the
benchmark's own code does for the Rand index; the definitions are those of Chen, Golovinskiy
and Funkhouser, "A Benchmark for 3D Mesh Segmentation" (SIGGRAPH 2009), section 4:

- rand_error: 1 - Rand index, the share of face pairs on which the two disagree (same segment
  in one, different segments in the other).
- hamming: Huang and Dom's directional Hamming distances, D(A => B) = sum over the segments of
  B of the faces outside their best-overlapping segment of A; missing rate D(A => B) / n,
  false alarm D(B => A) / n, and their mean, the Hamming distance.
- consistency: Martin et al.'s refinement error E(A, B, f) = |R(A, f) minus R(B, f)| / |R(A, f)|
  (R(S, f): the segment of S holding face f); GCE = min(sum_f E(A, B, f), sum_f E(B, A, f)) / n
  and LCE = sum_f min(E(A, B, f), E(B, A, f)) / n.
- cut_discrepancy: the mean distance from the points of one segmentation's cuts to the nearest
  cut of the other, both directions summed, divided by the mesh's average radius (the
  area-weighted mean distance of the surface from its area centroid). The benchmark measures
  geodesic distance; here it is the shortest path along the mesh's edges (Dijkstra over the
  vertex graph, edge lengths as weights), taken at the cut edges' end points and averaged with
  half of each cut edge's length as weight. A segmentation without cuts (one segment) has no
  cut discrepancy (nan).

All but the cut discrepancy are computed from the contingency table of the two labelings.
"""

from __future__ import annotations

import numpy as np
from scipy.sparse import coo_matrix, csr_matrix
from scipy.sparse.csgraph import dijkstra


def _dense_labels(labels: np.ndarray) -> np.ndarray:
    return np.unique(np.asarray(labels).reshape(-1), return_inverse=True)[1].reshape(-1)


def contingency(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Counts (segments of a, segments of b) of faces in each pair of segments."""
    a, b = _dense_labels(a), _dense_labels(b)
    if len(a) != len(b):
        raise ValueError(f"labelings of {len(a)} and {len(b)} faces")
    table = np.zeros((a.max() + 1, b.max() + 1), dtype=np.int64)
    np.add.at(table, (a, b), 1)
    return table


def rand_error(a: np.ndarray, b: np.ndarray) -> float:
    """1 - Rand index: the share of face pairs the two labelings disagree on."""
    table = contingency(a, b).astype(np.float64)
    n = table.sum()

    def pairs(x):
        return float((x * (x - 1.0) / 2.0).sum())

    same_both = pairs(table)
    same_a, same_b = pairs(table.sum(axis=1)), pairs(table.sum(axis=0))
    return (same_a + same_b - 2.0 * same_both) / (n * (n - 1.0) / 2.0)


def hamming(a: np.ndarray, b: np.ndarray) -> tuple[float, float, float]:
    """(Hamming distance, missing rate, false alarm) of a (automatic) against b (human)."""
    table = contingency(a, b)
    n = float(table.sum())
    missing = (n - table.max(axis=0).sum()) / n  # D(a => b): b's segments outside a's best
    false_alarm = (n - table.max(axis=1).sum()) / n  # D(b => a)
    return (missing + false_alarm) / 2.0, missing, false_alarm


def consistency(a: np.ndarray, b: np.ndarray) -> tuple[float, float]:
    """(GCE, LCE): Martin et al.'s global and local consistency errors."""
    table = contingency(a, b).astype(np.float64)
    n = table.sum()
    size_a = table.sum(axis=1, keepdims=True)
    size_b = table.sum(axis=0, keepdims=True)
    # Every face of cell (i, j) has the same two refinement errors.
    error_ab = (size_a - table) / size_a
    error_ba = (size_b - table) / size_b
    gce = min((table * error_ab).sum(), (table * error_ba).sum()) / n
    lce = (table * np.minimum(error_ab, error_ba)).sum() / n
    return float(gce), float(lce)


class MeshCuts:
    """The mesh's edge graph, face adjacency and average radius, for cut discrepancy."""

    def __init__(self, vertices: np.ndarray, triangles: np.ndarray):
        vertices = np.asarray(vertices, dtype=np.float64)
        triangles = np.asarray(triangles, dtype=np.int64)
        self.vertex_count = len(vertices)
        edges = np.sort(triangles[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
        faces = np.repeat(np.arange(len(triangles)), 3)
        order = np.lexsort((edges[:, 1], edges[:, 0]))
        edges, faces = edges[order], faces[order]
        same = np.all(edges[1:] == edges[:-1], axis=1)
        # Interior edges of a manifold mesh: two consecutive rows with the same edge.
        self.edge_faces = np.stack([faces[:-1][same], faces[1:][same]], axis=1)
        self.edge_vertices = edges[:-1][same]
        self.edge_length = np.linalg.norm(
            vertices[self.edge_vertices[:, 0]] - vertices[self.edge_vertices[:, 1]], axis=1
        )
        unique = np.unique(edges, axis=0)
        length = np.linalg.norm(vertices[unique[:, 0]] - vertices[unique[:, 1]], axis=1)
        # Zero-length edges would vanish from a sparse matrix: keep them as tiny weights.
        length = np.maximum(length, 1e-12 * max(length.max(), 1e-300))
        n = self.vertex_count + 1  # one extra node: the source joined to every cut vertex
        self._graph = coo_matrix(
            (
                np.r_[length, length],
                (np.r_[unique[:, 0], unique[:, 1]], np.r_[unique[:, 1], unique[:, 0]]),
            ),
            shape=(n, n),
        ).tocsr()
        corners = vertices[triangles]
        area = 0.5 * np.linalg.norm(
            np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1
        )
        centres = corners.mean(axis=1)
        centroid = (area[:, None] * centres).sum(axis=0) / area.sum()
        self.average_radius = float(
            (area * np.linalg.norm(centres - centroid, axis=1)).sum() / area.sum()
        )

    def cut_edges(self, labels: np.ndarray) -> np.ndarray:
        """Indices of the interior edges whose two faces lie in different segments."""
        labels = np.asarray(labels)
        return np.nonzero(labels[self.edge_faces[:, 0]] != labels[self.edge_faces[:, 1]])[0]

    def distance_to_cuts(self, labels: np.ndarray) -> np.ndarray | None:
        """Per vertex, the edge-path distance to the nearest cut vertex; None without cuts."""
        cut_vertices = np.unique(self.edge_vertices[self.cut_edges(labels)])
        if len(cut_vertices) == 0:
            return None
        source = self.vertex_count
        tiny = np.full(len(cut_vertices), 1e-300)
        link = csr_matrix(
            (tiny, (np.full(len(cut_vertices), source), cut_vertices)), shape=self._graph.shape
        )
        distance = dijkstra(self._graph + link, directed=True, indices=source)
        return np.maximum(distance[:-1] - 1e-300, 0.0)  # the link's own length taken off

    def mean_cut_distance(self, labels: np.ndarray, other_distance: np.ndarray) -> float:
        """Mean over labels' cut edges (by length) of the distance to the other's cuts."""
        cut = self.cut_edges(labels)
        ends = other_distance[self.edge_vertices[cut]]  # (cuts, 2)
        weight = self.edge_length[cut]
        return float((weight * ends.mean(axis=1)).sum() / weight.sum())

    def cut_discrepancy(
        self,
        a: np.ndarray,
        b: np.ndarray,
        distance_a: np.ndarray | None = None,
        distance_b: np.ndarray | None = None,
    ) -> float:
        """Cut discrepancy of a against b (distances to their cuts may be given, cached)."""
        distance_a = self.distance_to_cuts(a) if distance_a is None else distance_a
        distance_b = self.distance_to_cuts(b) if distance_b is None else distance_b
        if distance_a is None or distance_b is None:
            return float("nan")
        both = self.mean_cut_distance(a, distance_b) + self.mean_cut_distance(b, distance_a)
        return both / self.average_radius
