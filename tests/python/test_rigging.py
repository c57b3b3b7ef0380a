# SPDX-License-Identifier: GPL-3.0-or-later
"""shape_diameter.rigging: labels per polygon by largest area, principal axes against
analytic shapes, and the proto-skeleton of a dumbbell (its bones, joints and chain)."""

import numpy as np
import pytest
from shape_diameter import rigging, segment


def test_polygon_labels_take_the_largest_area():
    # Polygon 0: triangles of labels 2 (area 1), 1 (area 3), 2 (area 1.5): label 1 (3 > 2.5).
    # Polygon 1: a tie (1 and 0, area 2 each): the lower label. Polygon 2: no triangle: -1.
    # Polygon 3: zero area everywhere: the lowest label.
    labels = [2, 1, 2, 1, 0, 4, 3]
    polygons = [0, 0, 0, 1, 1, 3, 3]
    areas = [1.0, 3.0, 1.5, 2.0, 2.0, 0.0, 0.0]
    out = rigging.polygon_labels(labels, polygons, areas, 4)
    assert out.dtype == np.int32
    np.testing.assert_array_equal(out, [1, 0, -1, 3])


def test_polygon_labels_of_no_triangles():
    np.testing.assert_array_equal(rigging.polygon_labels([], [], [], 2), [-1, -1])


def box(size):
    """A closed box from the origin to `size`, 12 triangles, outward."""
    x, y, z = size
    v = np.array([[i * x, j * y, k * z] for i in (0, 1) for j in (0, 1) for k in (0, 1)], float)
    t = [
        [0, 1, 3],
        [0, 3, 2],
        [4, 6, 7],
        [4, 7, 5],
        [0, 4, 5],
        [0, 5, 1],
        [2, 3, 7],
        [2, 7, 6],
        [0, 2, 6],
        [0, 6, 4],
        [1, 5, 7],
        [1, 7, 3],
    ]
    return v, np.array(t)


@pytest.mark.parametrize("size, axis", [((4, 1, 1), 0), ((1, 5, 2), 1), ((1, 2, 7), 2)])
def test_principal_axis_of_a_box_is_its_long_side(size, axis):
    v, t = box(size)
    axes = rigging.principal_axes(v, t, np.zeros(len(t), int), 1)
    np.testing.assert_allclose(axes.centroid[0], np.array(size) / 2, atol=1e-12)
    assert abs(axes.direction[0][axis]) == pytest.approx(1.0, abs=1e-9)
    # Vertices run half the long side either way of the centre.
    np.testing.assert_allclose(sorted(np.abs(axes.extent[0])), [size[axis] / 2] * 2, atol=1e-9)


def test_principal_axis_does_not_depend_on_the_tessellation():
    # The same box with its top cut into a fan of four: the axis and centroid stay put.
    v, t = box((1, 1, 3))
    fan_centre = len(v)
    v = np.vstack([v, [[0.5, 0.5, 3.0]]])  # centre of the top (z = 3) face
    top = [i for i, tri in enumerate(t) if all(v[tri][:, 2] == 3.0)]
    ring = [1, 5, 7, 3]  # the top's corners, counterclockwise seen from above
    fan = [[fan_centre, ring[i], ring[(i + 1) % 4]] for i in range(4)]
    t = np.vstack([np.delete(t, top, axis=0), fan])
    axes = rigging.principal_axes(v, t, np.zeros(len(t), int), 1)
    np.testing.assert_allclose(axes.centroid[0], [0.5, 0.5, 1.5], atol=1e-12)
    assert abs(axes.direction[0][2]) == pytest.approx(1.0, abs=1e-9)


def dumbbell(sides=32, rings=80):
    """Two balls of radius 1 at x = +-1.6 joined by a neck of radius 0.25, triangles."""
    x = np.linspace(-2.58, 2.58, rings)
    r = np.maximum(np.sqrt(np.clip(1.0 - (np.abs(x) - 1.6) ** 2, 0, None)), 0.25)
    theta = np.linspace(0, 2 * np.pi, sides, endpoint=False)
    ring = np.stack(
        [
            np.repeat(x, sides),
            np.outer(r, np.cos(theta)).ravel(),
            np.outer(r, np.sin(theta)).ravel(),
        ],
        1,
    )
    v = np.vstack([[-2.6, 0, 0], ring, [2.6, 0, 0]])
    last, faces = len(v) - 1, []
    for j in range(sides):
        jn = (j + 1) % sides
        faces.append([0, 1 + jn, 1 + j])
        for i in range(rings - 1):
            a, b = 1 + i * sides + j, 1 + i * sides + jn
            faces += [[a, b, b + sides], [a, b + sides, a + sides]]
        base = 1 + (rings - 1) * sides
        faces.append([last, base + j, base + jn])
    return v, np.array(faces)


def test_proto_skeleton_of_a_dumbbell_is_a_chain_through_the_necks():
    v, t = dumbbell()
    x = v[t].mean(axis=1)[:, 0]
    values = 2 * np.hypot(*v[t].mean(axis=1)[:, 1:].T)  # twice the radius: the exact SDF
    seg = segment(v, t, values, clusters=2)
    assert seg.segment_count == 3
    sk = rigging.proto_skeleton(
        v, t, seg.labels, seg.segment_count, seg.boundaries, seg.segment_area
    )
    neck = int(seg.labels[np.argmin(np.abs(x))])
    roots = np.flatnonzero(sk.parent < 0)
    assert len(roots) == 1 and roots[0] != neck  # a ball, the largest part
    assert sk.parent[neck] == roots[0]
    other = ({0, 1, 2} - {neck, int(roots[0])}).pop()
    assert sk.parent[other] == neck and sk.connected[other]
    # The neck's bone runs from one neck loop's centroid to the other's, on the axis.
    neck_x = 1.6 - np.sqrt(1 - 0.25**2)
    for end in (sk.head[neck], sk.tail[neck]):
        assert abs(abs(end[0]) - neck_x) < 0.1 and np.hypot(end[1], end[2]) < 1e-6
    # The far ball's bone goes from its neck through the ball to its far side.
    assert np.hypot(*sk.tail[other][1:]) < 0.05 and abs(sk.tail[other][0]) > 2.0
    assert np.sign(sk.tail[other][0]) == np.sign(sk.head[other][0])


def test_proto_skeleton_bones_are_never_degenerate():
    # A single flat triangle: no extent along any axis worth a bone.
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1e-12, 0]], float)
    t = np.array([[0, 1, 2]])
    boundaries = {
        "segments": np.zeros((0, 2), int),
        "centroid": np.zeros((0, 3)),
        "length": np.zeros(0),
    }
    sk = rigging.proto_skeleton(v, t, np.zeros(1, int), 1, boundaries, np.ones(1), min_length=0.25)
    assert np.linalg.norm(sk.tail[0] - sk.head[0]) >= 0.25 - 1e-12
    assert sk.parent[0] == -1 and not sk.connected[0]
