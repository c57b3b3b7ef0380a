# SPDX-License-Identifier: GPL-3.0-or-later
"""Parts from thickness: segmentation of a mesh by its Shape Diameter Function.

``segment(vertices, triangles, values=None, ...)`` clusters the per-face SDF into `clusters`
levels of thickness (a Gaussian mixture over log-normalised values), smooths the clusters over
the mesh with a graph cut that prefers to cut along concave creases, and returns the connected
pieces of each cluster as segments, with what rigging reads from them (vertex labels, soft
vertex weights, the segments' adjacency and boundary loops). See docs/segmentation.md.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from . import _core
from .api import _check_choice, _check_integer, _check_mesh, compute
from .checks import check_progress
from .normalization import check_threads

MODES = ("auto", "cgal")
MAX_CLUSTERS = 256
# The most segments one may ask for: clusters 2..9 rarely make more than a few dozen, so a
# larger request is likely a face count given by mistake.
MAX_SEGMENTS = 4096
# With values=None, the share of the progress the SDF takes; the segmentation takes the rest.
SDF_SHARE = 0.8


class VertexWeights(NamedTuple):
    """Soft per-vertex weights, sparse by rows (CSR): vertex v's entries are
    ``segments[offsets[v]:offsets[v+1]]`` with ``weights[...]`` (float32, summing to 1). A
    vertex no face uses has none."""

    offsets: np.ndarray
    segments: np.ndarray
    weights: np.ndarray

    def dense(self, segment_count: int) -> np.ndarray:
        """The weights as a (vertices, segment_count) float32 array."""
        rows = len(self.offsets) - 1
        out = np.zeros((rows, segment_count), dtype=np.float32)
        row = np.repeat(np.arange(rows), np.diff(self.offsets))
        out[row, self.segments] = self.weights
        return out


@dataclass
class Segmentation:
    """What segment() returns. Per-face arrays have one entry per triangle."""

    labels: np.ndarray
    """int32 per face: its segment, in [0, segment_count). Segments are the connected pieces
    of the clusters (faces joined through shared edges), numbered by ascending mean of
    `values`: segment 0 is the thinnest."""
    clusters: np.ndarray
    """int32 per face: its cluster, in [0, k) for the k components of `mixture`; 0 the
    thinnest."""
    segment_count: int
    values: np.ndarray
    """float64 per face: the values clustered (filled, filtered when `postprocess`, rescaled
    to [0, 1])."""
    mixture: np.ndarray
    """(k, 3) float64: mean, deviation and weight of each Gaussian, over log-normalised values
    log(5 x + 1) / log(6), by ascending mean."""
    energy: float
    """The graph cut's energy of `clusters` (see docs/segmentation.md)."""
    smoothness: float
    """The smoothness (lambda) used: the one given, or the one the search for `segments`
    chose (the clusters it chose: len(mixture))."""
    vertex_labels: np.ndarray
    """int32 per vertex: the segment with the largest area among the faces around it (-1 for a
    vertex no face uses)."""
    vertex_weights: VertexWeights
    """Soft per-vertex weights per segment, falling off linearly over `weight_rings` rings of
    faces on each side of a boundary."""
    adjacency: np.ndarray
    """(A, 2) int32: pairs of segments (a < b) that share at least one edge."""
    boundaries: dict
    """The loops where two segments meet: 'segments' (B, 2) int32 (a < b), 'centroid' (B, 3)
    (mean of the edges' midpoints weighted by length), 'length' (B,), 'edges' (B,) int64."""
    segment_area: np.ndarray
    """float64 per segment: its area."""
    segment_mean: np.ndarray
    """float64 per segment: the mean of `values` over its faces."""
    timings: dict = field(default_factory=dict)
    """Seconds per stage: sdf (when values=None), face_graph, postprocess or rescale,
    soft_clustering, edge_weights, graph_cut, segments, parts (of the segmentation returned),
    count_search (with `segments`: every run of the search), total."""


def _check_number(name, value, lo):
    if (
        isinstance(value, bool)
        or not isinstance(value, (int, float, np.integer, np.floating))
        or not math.isfinite(float(value))
        or float(value) < lo
    ):
        raise ValueError(f"{name} must be a finite number >= {lo}, got {value!r}")


def _check_share(name, value):
    """A share of a whole: a real number in [0, 1)."""
    if (
        isinstance(value, bool)
        or not isinstance(value, (int, float, np.integer, np.floating))
        or not 0.0 <= float(value) < 1.0
    ):
        raise ValueError(f"{name} must be a share in [0, 1) (0.01: 1%), got {value!r}")


def _scaled(progress, start: float, end: float):
    """`progress` told [start, end] for a step's [0, 1]; None for None."""
    if progress is None:
        return None
    return lambda fraction: progress(start + (end - start) * fraction)


def _check_values(values, faces):
    """Per-face values as float64; NaN marks a missing value. ValueError naming the problem."""
    v = np.asarray(values)
    if v.dtype.kind not in "fiu":
        raise ValueError(f"values must be real numbers, got dtype {v.dtype}")
    if v.shape != (faces,):
        raise ValueError(f"values must have one entry per face, shape ({faces},), got {v.shape}")
    v = np.ascontiguousarray(v, dtype=np.float64)
    infinite = np.isinf(v)
    if infinite.any():
        raise ValueError(
            f"values must be finite or NaN (missing): {int(infinite.sum())} are infinite "
            f"(first: face {int(np.argmax(infinite))})"
        )
    return v


def segment(
    vertices,
    triangles,
    values=None,
    *,
    clusters: int = 5,
    smoothness: float = 0.26,
    mode: str = "auto",
    postprocess=None,
    weight_rings: int = 2,
    min_part_area: float = 0.0,
    segments: int | None = None,
    threads: int = 0,
    progress=None,
    **compute_options,
) -> Segmentation:
    """Segments a triangle mesh into parts by thickness.

    vertices (n, 3), triangles (m, 3): as for compute().
    values: per-face SDF (m,), any real dtype, NaN where missing (filled from edge
        neighbours); None computes it with compute(vertices, triangles, **compute_options)
        (faces only). Given values are used as they are, rescaled linearly to [0, 1].
    clusters: k, the number of thickness levels, 1..256 (CGAL's default 5). Fewer when the
        values hold fewer distinct levels.
    smoothness: lambda >= 0, the weight of cutting edges against the cluster fit (CGAL's
        default 0.26); 0 keeps the mixture's own labels.
    mode: 'auto' (alpha expansion run until no move lowers the energy) or 'cgal' (CGAL 5.5's
        segmentation_from_sdf_values exactly, whose graph cut keeps only its first move; see
        docs/segmentation.md).
    postprocess: CGAL's bilateral filter of the values before clustering (sdf_values'
        postprocess). None (default): on for values computed here, off for values given.
    weight_rings: rings of faces the soft vertex weights fall off over, 0..16.
    min_part_area: a minimum part size, as a share of the mesh's total area in [0, 1) (0.01:
        1%); 0 (default) is off. A segment below it joins the adjacent segment it shares the
        longest boundary with, smallest first, until none is below; a separate solid (no
        shared edge with the rest) below it stays a segment of its own. `clusters` keeps the
        graph cut's labels, so a joined segment may hold faces of several clusters.
    segments: the number of segments wanted, 1..4096, or None (default: `clusters` decides).
        Given, clusters 2..9 and the smoothness x 1, 0.4 and 2 are searched (clusters nearest
        `clusters` first, at `smoothness` first) until a segmentation has exactly that many
        segments, else the nearest count is kept: up to 24 segmentations, usually a few.
        `Segmentation.timings["count_search"]` gives the search's seconds. On the Princeton
        Segmentation Benchmark subset, asking for the people's median count of parts lowered
        the error (docs/segmentation.md).
    threads: CPU threads, 0 for every core. The result is the same for any count.
    progress: called with the fraction done in [0, 1] from the calling thread, as compute()'s
        (with values=None the SDF reports [0, 0.8] and the segmentation [0.8, 1]): between
        the steps and at most every 20 ms inside the long ones (the graph cut's moves and
        their max-flow). If it raises, the work stops and the exception propagates; nothing
        is returned.
    """
    _check_integer("clusters", clusters, 1, MAX_CLUSTERS)
    _check_number("smoothness", smoothness, 0.0)
    _check_choice("mode", mode, MODES)
    if postprocess is not None and not isinstance(postprocess, bool):
        raise ValueError(f"postprocess must be None, True or False, got {postprocess!r}")
    _check_integer("weight_rings", weight_rings, 0, 16)
    _check_share("min_part_area", min_part_area)
    if segments is not None:
        _check_integer("segments", segments, 1, MAX_SEGMENTS)
    check_threads(threads)
    check_progress(progress)
    if values is not None and compute_options:
        names = ", ".join(sorted(compute_options))
        raise ValueError(f"compute() options ({names}) apply only with values=None")
    if compute_options.get("points", "faces") != "faces":
        raise ValueError("segmentation needs per-face values: points must be 'faces'")
    v, t = _check_mesh(vertices, triangles, threads)
    start = time.perf_counter()
    timings = {}
    told = progress
    if values is None:
        told = _scaled(progress, SDF_SHARE, 1.0)
        sdf_progress = _scaled(progress, 0.0, SDF_SHARE)
        result = compute(v, t, threads=threads, progress=sdf_progress, **compute_options)
        values = result.values
        timings["sdf"] = time.perf_counter() - start
        if postprocess is None:
            postprocess = True
    values = _check_values(values, t.shape[0])
    cgal = mode == "cgal"
    out = _core.segment(
        v,
        t,
        values,
        clusters=int(clusters),
        smoothness=float(smoothness),
        filter=bool(postprocess),
        ties_move=cgal,
        first_move_only=cgal,
        weight_rings=int(weight_rings),
        threads=threads,
        min_segment_area=float(min_part_area),
        segments=0 if segments is None else int(segments),
        progress=told,
    )
    timings.update(out["timings"])
    timings["total"] = time.perf_counter() - start
    boundaries = out["boundaries"]
    pairs = boundaries["segments"]
    adjacency = np.unique(pairs, axis=0) if len(pairs) else np.zeros((0, 2), np.int32)
    return Segmentation(
        labels=out["labels"].astype(np.int32, copy=False),
        clusters=out["clusters"].astype(np.int32, copy=False),
        segment_count=int(out["segment_count"]),
        values=out["values"],
        mixture=out["mixture"],
        energy=float(out["energy"]),
        smoothness=float(out["smoothness"]),
        vertex_labels=out["vertex_labels"].astype(np.int32, copy=False),
        vertex_weights=VertexWeights(
            out["weight_offsets"].astype(np.int64),
            out["weight_segments"].astype(np.int32, copy=False),
            out["weight_values"],
        ),
        adjacency=adjacency.astype(np.int32, copy=False),
        boundaries=dict(boundaries),
        segment_area=out["segment_area"],
        segment_mean=out["segment_mean"],
        timings=timings,
    )


def segmentation_energy(
    vertices,
    triangles,
    values,
    clusters_per_face,
    *,
    clusters=5,
    smoothness=0.26,
    postprocess=False,
    threads=0,
) -> float:
    """The energy segment() minimises, of any labelling `clusters_per_face` (int, in [0, k)):
    to compare another optimiser's labels (CGAL's) with ours on the same terms."""
    _check_integer("clusters", clusters, 1, MAX_CLUSTERS)
    _check_number("smoothness", smoothness, 0.0)
    check_threads(threads)
    v, t = _check_mesh(vertices, triangles, threads)
    values = _check_values(values, t.shape[0])
    labels = np.ascontiguousarray(clusters_per_face, dtype=np.int32)
    return float(
        _core.segmentation_energy(
            v,
            t,
            values,
            labels,
            clusters=int(clusters),
            smoothness=float(smoothness),
            filter=bool(postprocess),
            threads=threads,
        )
    )
