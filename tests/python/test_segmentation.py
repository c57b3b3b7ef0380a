# SPDX-License-Identifier: GPL-3.0-or-later
"""shape_diameter.segment: against CGAL's segmentation_from_sdf_values, on constructed shapes,
on bad and awkward input, and across thread counts.

The CGAL comparisons run the cgal_segment reference (tests/reference; path in
SDF_CGAL_SEGMENT; see cgal_segment_reference.py for when they skip). CGAL computes its own
post-processed SDF once per mesh; both sides then segment those same values, so labels can be
compared face by face.
"""

from __future__ import annotations

from pathlib import Path

import cgal_segment_reference as cgal
import numpy as np
import pytest
import shape_diameter
from shape_diameter.segmentation import segmentation_energy
from shapes import icosphere

DATA = Path(__file__).resolve().parents[1] / "data"

# Five kinds of shape from the Princeton Segmentation Benchmark and one of the repository's.
MESHES = [
    "psb/1.off",
    "psb/81.off",
    "psb/101.off",
    "psb/241.off",
    "psb/341.off",
    "ChineseDragon-10kv.off",
]
CLUSTERS = [2, 5, 8]
SMOOTHNESS = [0.1, 0.26, 0.6]
MIN_EQUAL_LABELS = 0.999


def read_off(path: Path):
    with open(path) as f:
        words = [w for line in f for w in line.split("#", 1)[0].split()]
    assert words[0] == "OFF"
    nv, nf = int(words[1]), int(words[2])
    numbers = np.array(words[4 : 4 + 3 * nv], dtype=np.float64).reshape(nv, 3)
    faces = np.array(words[4 + 3 * nv : 4 + 3 * nv + 4 * nf], dtype=np.int64).reshape(nf, 4)
    assert (faces[:, 0] == 3).all()
    return numbers, faces[:, 1:]


@pytest.fixture(scope="module")
def cgal_values(tmp_path_factory):
    """Per mesh: the mesh and CGAL's own post-processed SDF (from its k=5 run)."""
    cache = {}

    def get(name):
        if name not in cache:
            out = tmp_path_factory.mktemp("cgal") / "sdf.txt"
            ref = cgal.run(DATA / name, out)
            cache[name] = (*read_off(DATA / name), ref.sdf)
        return cache[name]

    return get


# --------------------------------------------------------------------------- against CGAL


@pytest.mark.parametrize("name", MESHES)
def test_cgal_mode_gives_cgals_segments(name, cgal_values, tmp_path):
    vertices, triangles, sdf = cgal_values(name)
    for k in CLUSTERS:
        for smoothness in SMOOTHNESS:
            ref = cgal.run(
                DATA / name,
                tmp_path / f"{k}_{smoothness}.txt",
                clusters=k,
                smoothness=smoothness,
                values=sdf,
            )
            ours = shape_diameter.segment(
                vertices, triangles, sdf, clusters=k, smoothness=smoothness, mode="cgal"
            )
            where = f"{name} k={k} lambda={smoothness}"
            assert ours.segment_count == ref.header["segments"], where
            assert np.mean(ours.clusters == ref.clusters) >= MIN_EQUAL_LABELS, where
            assert np.mean(ours.labels == ref.labels) >= MIN_EQUAL_LABELS, where


@pytest.mark.parametrize("name", MESHES[:3])
def test_energy_never_above_cgals(name, cgal_values, tmp_path, record_property):
    """On CGAL's probabilities and weights, our labels' energy against CGAL's labels'."""
    vertices, triangles, sdf = cgal_values(name)
    for k in CLUSTERS:
        ref = cgal.run(DATA / name, tmp_path / f"{k}.txt", clusters=k, values=sdf)
        theirs = segmentation_energy(vertices, triangles, sdf, ref.clusters, clusters=k)
        same = shape_diameter.segment(vertices, triangles, sdf, clusters=k, mode="cgal")
        ours = shape_diameter.segment(vertices, triangles, sdf, clusters=k)
        record_property(
            f"energy k={k}", {"cgal": theirs, "cgal_mode": same.energy, "auto": ours.energy}
        )
        assert same.energy == pytest.approx(theirs, rel=1e-9)
        assert ours.energy <= theirs * (1 + 1e-12)
        # Recomputed from the labels alone, our energy is what segment() reports.
        again = segmentation_energy(vertices, triangles, sdf, ours.clusters, clusters=k)
        assert again == pytest.approx(ours.energy, rel=1e-12)


# --------------------------------------------------------------------------- constructed shapes


def revolved(profile, x, sides=48):
    """A closed surface of revolution around the x axis: radius profile(x) over the samples x
    (first and last: the poles, radius 0), outward-facing triangles."""
    rings = len(x) - 2
    theta = np.linspace(0.0, 2 * np.pi, sides, endpoint=False)
    r = profile(x[1:-1])
    ring = np.stack(
        [
            np.repeat(x[1:-1], sides),
            np.outer(r, np.cos(theta)).ravel(),
            np.outer(r, np.sin(theta)).ravel(),
        ],
        axis=1,
    )
    vertices = np.vstack([[x[0], 0, 0], ring, [x[-1], 0, 0]])
    faces = []
    first, last = 0, 1 + rings * sides
    for j in range(sides):
        jn = (j + 1) % sides
        faces.append([first, 1 + jn, 1 + j])
        for i in range(rings - 1):
            a, b = 1 + i * sides + j, 1 + i * sides + jn
            c, d = a + sides, b + sides
            faces += [[a, b, d], [a, d, c]]
        base = 1 + (rings - 1) * sides
        faces.append([last, base + j, base + jn])
    return vertices, np.array(faces, dtype=np.int64)


BALL, NECK, CENTRE = 1.0, 0.25, 1.6  # ball radius, neck radius, ball centres at +-CENTRE


def dumbbell():
    """Two balls of radius 1 at x = -1.6 and 1.6 joined by a neck of radius 0.25."""

    def profile(x):
        ball = np.sqrt(np.clip(BALL**2 - (np.abs(x) - CENTRE) ** 2, 0.0, None))
        return np.maximum(ball, NECK)

    x = np.concatenate(
        [
            [-CENTRE - BALL],
            np.linspace(-CENTRE - BALL + 0.02, CENTRE + BALL - 0.02, 120),
            [CENTRE + BALL],
        ]
    )
    return revolved(profile, x)


def face_centres(vertices, triangles):
    return vertices[triangles].mean(axis=1)


def test_dumbbell_gives_two_balls_and_a_neck():
    vertices, triangles = dumbbell()
    seg = shape_diameter.segment(vertices, triangles, clusters=2)
    assert seg.segment_count == 3
    x = face_centres(vertices, triangles)[:, 0]
    neck_x = CENTRE - np.sqrt(BALL**2 - NECK**2)  # where the neck meets each ball
    neck = seg.labels[np.abs(x) < neck_x - 0.1]
    left, right = seg.labels[x < -neck_x - 0.1], seg.labels[x > neck_x + 0.1]
    for part in (neck, left, right):
        assert len(np.unique(part)) == 1
    assert len({neck[0], left[0], right[0]}) == 3
    assert neck[0] == 0  # the thinnest segment
    # Two boundary loops, one at each neck, each about the neck's circumference.
    loops = seg.boundaries
    assert len(loops["length"]) == 2
    np.testing.assert_allclose(loops["length"], 2 * np.pi * NECK, rtol=0.05)
    np.testing.assert_allclose(np.sort(np.abs(loops["centroid"][:, 0])), neck_x, atol=0.1)
    assert sorted(map(tuple, seg.adjacency)) == sorted(
        {tuple(sorted((0, int(left[0])))), tuple(sorted((0, int(right[0]))))}
    )
    # Per-vertex output: labels follow the faces, weights sum to 1 and blend only near the cuts.
    weights = seg.vertex_weights.dense(seg.segment_count)
    np.testing.assert_allclose(weights.sum(axis=1), 1.0, rtol=1e-5)
    vx = vertices[:, 0]
    deep = np.abs(np.abs(vx) - neck_x) > 0.5
    assert (weights[deep].max(axis=1) == 1.0).all()
    assert (weights[~deep].max(axis=1) < 1.0).any()
    np.testing.assert_array_equal(np.argmax(weights[deep], axis=1), seg.vertex_labels[deep])
    np.testing.assert_allclose(seg.segment_area.sum(), _area(vertices, triangles), rtol=1e-12)


def _area(vertices, triangles):
    a, b, c = (vertices[triangles[:, i]] for i in range(3))
    return 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1).sum()


def _parts(triangles, vertex_count):
    """Connected part per face (faces joined through shared vertices)."""
    parent = np.arange(vertex_count)

    def root(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for a, b, c in triangles:
        ra, rb, rc = root(a), root(b), root(c)
        parent[rb] = ra
        parent[root(rc)] = ra
    return np.array([root(t[0]) for t in triangles])


@pytest.mark.parametrize("mode", ["auto", "cgal"])
def test_separate_solids_never_share_a_segment(mode):
    """Two balls of different sizes and a dumbbell, apart: no segment spans two of them, even
    where both balls fall in one cluster."""
    v1, t1 = icosphere(1.0, 3)
    v2, t2 = icosphere(1.0, 3)
    v3, t3 = dumbbell()
    vertices = np.vstack([v1, v2 + [5.0, 0, 0], v3 + [0, 5.0, 0]])
    triangles = np.vstack([t1, t2 + len(v1), t3 + len(v1) + len(v2)])
    seg = shape_diameter.segment(vertices, triangles, clusters=3, mode=mode)
    parts = _parts(triangles, len(vertices))
    assert len(np.unique(parts)) == 3
    for label in range(seg.segment_count):
        assert len(np.unique(parts[seg.labels == label])) == 1
    assert (seg.clusters[: len(t1)] == seg.clusters[len(t1) : len(t1) + len(t2)]).all()


def test_thread_count_on_a_mesh_of_several_chunks():
    # bunny00 (75,408 faces): the graph cut writes its capacities in chunks of 16,384 faces
    # in parallel, and resumes its flows from them; the labels must not depend on threads.
    vertices, triangles = read_off(DATA / "bunny00.off")
    sdf = shape_diameter.compute(vertices, triangles, rays=8, threads=2).values
    runs = [shape_diameter.segment(vertices, triangles, sdf, threads=n) for n in (1, 2, 3)]
    for other in runs[1:]:
        np.testing.assert_array_equal(other.labels, runs[0].labels)
        assert other.energy == runs[0].energy


def test_every_thread_count_gives_the_same_result(cgal_values):
    vertices, triangles, sdf = cgal_values("psb/1.off")
    for mode in ("auto", "cgal"):
        runs = [
            shape_diameter.segment(vertices, triangles, sdf, mode=mode, threads=n)
            for n in (1, 2, 3, 0)
        ]
        for other in runs[1:]:
            np.testing.assert_array_equal(other.labels, runs[0].labels)
            np.testing.assert_array_equal(other.clusters, runs[0].clusters)
            assert other.energy == runs[0].energy
            np.testing.assert_array_equal(
                other.vertex_weights.weights, runs[0].vertex_weights.weights
            )


def test_values_none_computes_the_sdf_first():
    vertices, triangles = dumbbell()
    result = shape_diameter.compute(vertices, triangles, threads=2)
    from_values = shape_diameter.segment(
        vertices, triangles, result.values, clusters=2, postprocess=True
    )
    computed = shape_diameter.segment(vertices, triangles, clusters=2, threads=2)
    np.testing.assert_array_equal(computed.labels, from_values.labels)
    assert "sdf" in computed.timings and "graph_cut" in computed.timings


# --------------------------------------------------------------------------- awkward input


def _check_complete(seg, faces, vertex_count):
    assert seg.labels.shape == (faces,) and seg.labels.dtype == np.int32
    assert seg.labels.min() >= 0 and seg.labels.max() < seg.segment_count
    assert np.isfinite(seg.values).all() and np.isfinite(seg.energy)
    assert seg.vertex_labels.shape == (vertex_count,)
    assert np.isfinite(seg.vertex_weights.weights).all()
    assert np.isfinite(seg.boundaries["centroid"]).all()


def test_open_nonmanifold_and_degenerate_meshes_give_complete_labels():
    rng = np.random.default_rng(3)
    v, t = icosphere(1.0, 2)
    cases = {
        "open": (v, t[v[t].mean(axis=1)[:, 2] > -0.3]),
        "non-manifold fan": (
            np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1.0]]),
            np.array([[0, 1, 2], [1, 0, 3], [0, 1, 4], [1, 0, 5]]),
        ),
        "degenerate and duplicate faces": (
            v,
            np.vstack([t, t[:5], [[0, 0, 1], [2, 2, 2]], [[0, 1, 2]]]),
        ),
        "unused vertices": (np.vstack([v, [[9.0, 9, 9]]]), t),
        "one face": (v, t[:1]),
    }
    for name, (vertices, triangles) in cases.items():
        values = rng.random(len(triangles))
        values[::7] = np.nan  # missing values are filled
        for mode in ("auto", "cgal"):
            seg = shape_diameter.segment(vertices, triangles, values, clusters=5, mode=mode)
            _check_complete(seg, len(triangles), len(vertices))
        seg = shape_diameter.segment(vertices, triangles, np.full(len(triangles), 2.0))
        _check_complete(seg, len(triangles), len(vertices))
        assert (seg.clusters == 0).all(), name  # a constant field is one cluster


def test_computed_sdf_of_an_open_mesh_segments():
    v, t = icosphere(1.0, 3)
    seg = shape_diameter.segment(v, t[v[t].mean(axis=1)[:, 2] > -0.5], clusters=3)
    _check_complete(seg, int((v[t].mean(axis=1)[:, 2] > -0.5).sum()), len(v))


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"values": np.zeros(3)}, "one entry per face"),
        ({"values": np.full(80, np.inf)}, "finite or NaN"),
        ({"values": np.array(["a"] * 80)}, "real numbers"),
        ({"clusters": 0}, "clusters must be an integer"),
        ({"clusters": 2.5}, "clusters must be an integer"),
        ({"smoothness": -1.0}, "smoothness must be a finite number"),
        ({"smoothness": float("nan")}, "smoothness must be a finite number"),
        ({"mode": "fast"}, "mode must be one of"),
        ({"postprocess": "yes"}, "postprocess must be"),
        ({"weight_rings": -1}, "weight_rings must be an integer"),
        ({"threads": -1}, "threads must be an integer"),
        ({"values": np.zeros(80), "rays": 10}, "apply only with values=None"),
        ({"points": "vertices"}, "points must be 'faces'"),
    ],
)
def test_bad_input_says_what_is_wrong(kwargs, message):
    v, t = icosphere(1.0, 1)
    assert len(t) == 80
    with pytest.raises(ValueError, match=message):
        shape_diameter.segment(v, t, **kwargs)


def test_bad_mesh_is_refused_like_compute():
    v, t = icosphere(1.0, 1)
    with pytest.raises(ValueError, match="only 42 vertices"):
        shape_diameter.segment(v, t + 100, np.zeros(len(t)))
    with pytest.raises(ValueError, match="no triangles"):
        shape_diameter.segment(v, np.zeros((0, 3), np.int64), np.zeros(0))
