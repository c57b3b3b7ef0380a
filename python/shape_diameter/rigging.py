# SPDX-License-Identifier: GPL-3.0-or-later
"""From segments to what a rig is made of: labels per polygon of a polygon mesh, each
segment's principal axis, and a proto-skeleton (one bone per segment, chained at the boundary
loops between adjacent segments). Plain numpy over the arrays segment() returns; nothing here
knows about Blender.

A proto-skeleton is a starting point for rigging, not a finished rig: bones follow the parts'
main directions, and joints sit where parts meet.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


def triangle_areas(vertices, triangles) -> np.ndarray:
    """float64 per triangle: its area."""
    v = np.asarray(vertices, dtype=np.float64)
    t = np.asarray(triangles)
    return 0.5 * np.linalg.norm(np.cross(v[t[:, 1]] - v[t[:, 0]], v[t[:, 2]] - v[t[:, 0]]), axis=1)


def polygon_labels(triangle_labels, triangle_polygons, areas, polygon_count) -> np.ndarray:
    """int32 per polygon: the label covering the largest area of its triangles (a polygon
    split into triangles of several segments takes the one with the most of it; among equal
    areas, and for polygons of zero area, the lowest label). A polygon with no triangle gets
    -1."""
    labels = np.asarray(triangle_labels, dtype=np.int64)
    polys = np.asarray(triangle_polygons, dtype=np.int64)
    out = np.full(polygon_count, -1, dtype=np.int32)
    if len(labels) == 0:
        return out
    # Area per (polygon, label) pair: the pairs sorted, summed, then per polygon the largest.
    width = int(labels.max()) + 1
    keys = polys * width + labels
    pairs, inverse = np.unique(keys, return_inverse=True)
    summed = np.bincount(inverse, weights=np.asarray(areas, dtype=np.float64))
    pair_polys, pair_labels = pairs // width, pairs % width
    # Sort by polygon, then by area descending, then label ascending: the first of each wins.
    order = np.lexsort((pair_labels, -summed, pair_polys))
    first = np.ones(len(order), dtype=bool)
    first[1:] = pair_polys[order][1:] != pair_polys[order][:-1]
    winners = order[first]
    out[pair_polys[winners]] = pair_labels[winners]
    return out


@dataclass
class Axes:
    """Per segment: centroid (S, 3), unit principal direction (S, 3) and the extent of the
    segment's vertices along it, (S, 2) signed distances from the centroid (low, high)."""

    centroid: np.ndarray
    direction: np.ndarray
    extent: np.ndarray


def principal_axes(vertices, triangles, labels, segment_count) -> Axes:
    """Each segment's principal axis: the main eigenvector of the area-weighted covariance of
    its triangles (each triangle's second moment taken exactly, so that the axis does not
    depend on how finely the surface is cut), through its area centroid. A segment of no area
    takes the mean of its vertices and the x axis."""
    v = np.asarray(vertices, dtype=np.float64)
    t = np.asarray(triangles, dtype=np.int64)
    labels = np.asarray(labels, dtype=np.int64)
    s = int(segment_count)
    a, b, c = v[t[:, 0]], v[t[:, 1]], v[t[:, 2]]
    area = triangle_areas(v, t)
    mid = (a + b + c) / 3.0
    weight = np.bincount(labels, weights=area, minlength=s)
    count = np.bincount(labels, minlength=s).astype(np.float64)
    plain = np.stack([np.bincount(labels, weights=mid[:, i], minlength=s) for i in range(3)], 1)
    summed = np.stack(
        [np.bincount(labels, weights=area * mid[:, i], minlength=s) for i in range(3)], 1
    )
    has_area = weight > 0.0
    centroid = np.where(
        has_area[:, None],
        summed / np.where(has_area, weight, 1.0)[:, None],
        plain / np.maximum(count, 1.0)[:, None],
    )
    # Second moment of a triangle about the origin: area/12 (sum p p^T + 9 m m^T).
    corner = a[:, :, None] * a[:, None, :] + b[:, :, None] * b[:, None, :]
    corner += c[:, :, None] * c[:, None, :]
    moment = (area / 12.0)[:, None, None] * (corner + 9.0 * mid[:, :, None] * mid[:, None, :])
    second = np.zeros((s, 3, 3))
    np.add.at(second, labels, moment)
    safe = np.where(has_area, weight, 1.0)[:, None, None]
    covariance = second / safe - centroid[:, :, None] * centroid[:, None, :]
    direction = np.tile([1.0, 0.0, 0.0], (s, 1))
    if has_area.any():
        _, vectors = np.linalg.eigh(covariance[has_area])
        direction[has_area] = vectors[:, :, 2]
    # Extent of the segment's vertices along its axis.
    corner_labels = np.repeat(labels, 3)
    points = t.reshape(-1)
    projection = np.einsum(
        "ij,ij->i", v[points] - centroid[corner_labels], direction[corner_labels]
    )
    low = np.full(s, np.inf)
    high = np.full(s, -np.inf)
    np.minimum.at(low, corner_labels, projection)
    np.maximum.at(high, corner_labels, projection)
    empty = ~np.isfinite(low)
    low[empty] = high[empty] = 0.0
    return Axes(centroid, direction, np.stack([low, high], 1))


@dataclass
class Skeleton:
    """One bone per segment: head and tail (S, 3), parent (S,) int32 (-1 for a root) and
    connected (S,) bool (the head is the parent's tail)."""

    head: np.ndarray
    tail: np.ndarray
    parent: np.ndarray
    connected: np.ndarray


def _joints(boundaries, segment_count):
    """{(a, b): centroid} of the longest boundary loop between each adjacent pair a < b, and
    the pairs ordered by loop length, longest first."""
    pairs = np.asarray(boundaries["segments"], dtype=np.int64).reshape(-1, 2)
    lengths = np.asarray(boundaries["length"], dtype=np.float64)
    centroids = np.asarray(boundaries["centroid"], dtype=np.float64).reshape(-1, 3)
    joint, length = {}, {}
    for (a, b), size, centroid in zip(pairs.tolist(), lengths, centroids):
        key = (min(a, b), max(a, b))
        if size > length.get(key, -1.0):
            joint[key], length[key] = centroid, size
    return joint, sorted(joint, key=lambda k: -length[k])


def _tree(segment_count, joint, ordered, area):
    """Parent per segment: a maximum spanning forest of the adjacency graph by boundary
    length (parts are joined where they meet most), rooted at each component's largest
    segment (the torso of a character)."""
    root_of = list(range(segment_count))

    def find(x):
        while root_of[x] != x:
            root_of[x] = root_of[root_of[x]]
            x = root_of[x]
        return x

    neighbours = [[] for _ in range(segment_count)]
    for a, b in ordered:
        ra, rb = find(a), find(b)
        if ra != rb:
            root_of[ra] = rb
            neighbours[a].append(b)
            neighbours[b].append(a)
    parent = np.full(segment_count, -1, dtype=np.int32)
    seen = np.zeros(segment_count, dtype=bool)
    for start in np.argsort(-np.asarray(area), kind="stable"):
        if seen[start]:
            continue
        seen[start] = True
        queue = [int(start)]
        while queue:
            node = queue.pop()
            for other in neighbours[node]:
                if not seen[other]:
                    seen[other] = True
                    parent[other] = node
                    queue.append(other)
    return parent


def proto_skeleton(
    vertices, triangles, labels, segment_count, boundaries, area, min_length=None
) -> Skeleton:
    """Bones of a proto-skeleton, in the mesh's coordinates. Each root bone runs along its
    segment's principal axis over the segment's extent. Every other bone starts at the
    centroid of the boundary loop to its parent (the longest loop where there are several)
    and ends at its only child's joint (a chain: upper arm, forearm), else along its principal
    axis, pointed away from the joint, to the segment's far end. No bone is shorter than
    `min_length` (default: 1% of the mesh's bounding box diagonal), so none is degenerate."""
    s = int(segment_count)
    v = np.asarray(vertices, dtype=np.float64)
    axes = principal_axes(v, triangles, labels, s)
    if min_length is None:
        diagonal = float(np.linalg.norm(v.max(0) - v.min(0))) if len(v) else 1.0
        min_length = 0.01 * diagonal if diagonal > 0.0 else 1.0
    joint, ordered = _joints(boundaries, s)
    parent = _tree(s, joint, ordered, area)
    children = [[] for _ in range(s)]
    for child, p in enumerate(parent):
        if p >= 0:
            children[p].append(child)
    head = np.empty((s, 3))
    tail = np.empty((s, 3))
    connected = np.zeros(s, dtype=bool)
    for i in range(s):
        centroid, direction = axes.centroid[i], axes.direction[i]
        if parent[i] < 0:
            low, high = axes.extent[i]
            head[i], tail[i] = centroid + low * direction, centroid + high * direction
        else:
            head[i] = joint[(min(i, parent[i]), max(i, parent[i]))]
            if len(children[i]) == 1:
                c = children[i][0]
                tail[i] = joint[(min(i, c), max(i, c))]
            else:
                tail[i] = head[i] + _reach(
                    v, triangles, labels, i, head[i], centroid, direction, axes.extent[i]
                )
        along = tail[i] - head[i]
        length = float(np.linalg.norm(along))
        if length < min_length:
            unit = along / length if length > 0.0 else direction
            tail[i] = head[i] + min_length * unit
    for i in range(s):
        p = parent[i]
        connected[i] = p >= 0 and np.allclose(tail[p], head[i], rtol=0.0, atol=1e-9 * min_length)
    return Skeleton(head, tail, parent, connected)


# A part whose principal axis runs across the line from its joint to its centroid (a ball, a
# hand wider than long) gets its bone along that line instead: |cos| below this.
ACROSS = 0.5


def _reach(vertices, triangles, labels, segment, head, centroid, direction, extent):
    """The vector from the joint `head` to the part's far end: along the principal axis turned
    away from the joint, or along joint -> centroid where the axis runs across it, as far as
    the part's vertices go."""
    toward = centroid - head
    distance = float(np.linalg.norm(toward))
    if distance > 0.0 and abs(float(np.dot(toward, direction))) < ACROSS * distance:
        unit = toward / distance
        points = vertices[np.unique(np.asarray(triangles)[np.asarray(labels) == segment])]
        return max(float(np.max((points - head) @ unit)), 0.0) * unit
    # The vertices' extent along the axis, measured from the joint instead of the centroid:
    # the far end is high (or -low, the axis turned) plus the centroid's offset.
    low, high = extent
    offset = float(np.dot(toward, direction))
    if offset < 0.0:
        return max(-(low + offset), 0.0) * -direction
    return max(high + offset, 0.0) * direction
