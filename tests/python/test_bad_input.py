# SPDX-License-Identifier: GPL-3.0-or-later
"""Bad, unusual and degenerate input: every ValueError of the API with a message that names
the problem; every accepted dtype and memory layout giving the same answer; degenerate and
open meshes giving finite values; the progress callback; the GIL released while computing."""

from __future__ import annotations

import os
import signal
import threading
import time
import warnings
from pathlib import Path

import numpy as np
import pytest
import shape_diameter
import shapes
from shape_diameter.api import MAX_RAYS
from shape_diameter.mesh_io import load_mesh

DATA = Path(__file__).resolve().parents[1] / "data"


@pytest.fixture(scope="module")
def sphere():
    """A small closed mesh for the many calls here (1280 faces)."""
    return shapes.icosphere(1.0, 3)


@pytest.fixture(scope="module")
def sphere_result(sphere):
    V, F = sphere
    return shape_diameter.compute(V, F)


def _with(array, flat_index, value):
    """A copy of array with one element, given by its flat index, replaced."""
    out = np.array(array, copy=True)
    out.reshape(-1)[flat_index] = value
    return out


def _neighbours(F: np.ndarray, face: int) -> np.ndarray:
    """Faces sharing at least one vertex with face (the fill's neighbourhood)."""
    shares = np.isin(F, F[face]).any(axis=1)
    shares[face] = False
    return np.flatnonzero(shares)


# --------------------------------------------------------------------------- bad meshes


_VSHAPE = r"vertices must have shape \(n, 3\), "
_TSHAPE = r"triangles must have shape \(m, 3\), "
_DEPTH = r"octree_depth must be an integer in "
_LEAF = r"octree_leaf_size must be an integer in "
_CONE = r"cone_angle must be a number in \(0, 180\) degrees, "


@pytest.mark.parametrize(
    "make, match",
    [
        (lambda V, F: (V[:, :2], F), _VSHAPE + r"got \(\d+, 2\)"),
        (lambda V, F: (np.column_stack([V, V[:, :1]]), F), _VSHAPE + r"got \(\d+, 4\)"),
        (lambda V, F: (V.reshape(-1), F), _VSHAPE + r"got \(\d+,\)"),
        (lambda V, F: (V[..., None], F), _VSHAPE + r"got \(\d+, 3, 1\)"),
        (lambda V, F: (np.float64(1.0), F), _VSHAPE + r"got \(\)"),
        (lambda V, F: (None, F), _VSHAPE),
        (lambda V, F: (V, np.column_stack([F, F[:, :1]])), _TSHAPE + r"got \(\d+, 4\)"),
        (lambda V, F: (V, F[:, :2]), _TSHAPE + r"got \(\d+, 2\)"),
        (lambda V, F: (V, F.reshape(-1)), _TSHAPE + r"got \(\d+,\)"),
    ],
    ids=["V(n,2)", "V(n,4)", "V-1d", "V(n,3,1)", "V-scalar", "V-None", "F(m,4)", "F(m,2)", "F-1d"],
)
def test_wrong_shapes(sphere, make, match):
    V, F = make(*sphere)
    with pytest.raises(ValueError, match=match):
        shape_diameter.compute(V, F)
    # sample_points validates the same way.
    with pytest.raises(ValueError, match=match):
        shape_diameter.sample_points(V, F)


@pytest.mark.parametrize(
    "dtype, match",
    [
        (np.complex128, r"vertices must be real numbers, got dtype complex128"),
        (np.bool_, r"vertices must be real numbers, got dtype bool"),
        (np.str_, r"vertices must be real numbers, got dtype <U"),
        (object, r"vertices must be real numbers, got dtype object"),
    ],
)
def test_vertices_of_a_wrong_dtype(sphere, dtype, match):
    V, F = sphere
    with pytest.raises(ValueError, match=match):
        shape_diameter.compute(V.astype(dtype), F)


@pytest.mark.parametrize("dtype", [np.float64, np.float32, np.bool_, object])
def test_triangles_of_a_wrong_dtype(sphere, dtype):
    V, F = sphere
    with pytest.raises(ValueError, match=r"triangles must be integers, got dtype"):
        shape_diameter.compute(V, F.astype(dtype))


def test_ragged_vertices_are_refused(sphere):
    _, F = sphere
    with pytest.raises(
        ValueError,
        match=r"^vertices must have shape \(n, 3\), but its rows "
        r"differ in length$",
    ):
        shape_diameter.compute([[0.0, 0.0, 0.0], [1.0, 0.0]], F)


def test_polygons_are_refused_with_advice():
    # Quads mixed with triangles got numpy's words, naming no argument.
    V = np.eye(5, 3)
    with pytest.raises(
        ValueError,
        match=r"^triangles must have shape \(m, 3\), but its rows "
        r"differ in length \(of polygons: triangulate",
    ):
        shape_diameter.compute(V, [[0, 1, 2, 3], [0, 1, 4]])
    with pytest.raises(
        ValueError,
        match=r"got \(1, 4\): 4-corner polygons: triangulate them "
        r"first \(load_mesh does\)$",
    ):
        shape_diameter.compute(V, [[0, 1, 2, 3]])


# Positions in the flat triangle array: the first, one in the middle, the last. A validator
# that looks at only one end of the array (or only at the first column) misses the others.
_POSITIONS = {"first": 0, "middle": 3 * 37 + 1, "last": -1}


@pytest.mark.parametrize("where", sorted(_POSITIONS))
@pytest.mark.parametrize("bad", ["n", "n+1", "huge"])
def test_vertex_index_too_large(sphere, where, bad):
    V, F = sphere
    n = len(V)
    value = {"n": n, "n+1": n + 1, "huge": 2**40}[bad]
    flat = _POSITIONS[where] % F.size
    with pytest.raises(ValueError, match=rf"vertex index {value}, but there are only {n} vertices"):
        shape_diameter.compute(V, _with(F, flat, value))


@pytest.mark.parametrize("where", sorted(_POSITIONS))
@pytest.mark.parametrize("value", [-1, -(2**40)])
def test_negative_vertex_index(sphere, where, value):
    V, F = sphere
    flat = _POSITIONS[where] % F.size
    with pytest.raises(ValueError, match=rf"negative vertex index \({value}\)"):
        shape_diameter.compute(V, _with(F, flat, value))


def test_unsigned_index_beyond_int64_is_refused(sphere):
    # 2**64 - 1 as uint64 would wrap to -1 if cast to int64 before the range check.
    V, F = sphere
    bad = _with(F.astype(np.uint64), 3 * 37 + 2, np.uint64(2**64 - 1))
    with pytest.raises(ValueError, match=rf"vertex index {2**64 - 1}, but there are only"):
        shape_diameter.compute(V, bad)


@pytest.mark.parametrize("value", [np.nan, np.inf, -np.inf])
@pytest.mark.parametrize("where", sorted(_POSITIONS))
def test_non_finite_coordinates(sphere, value, where):
    V, F = sphere
    flat = _POSITIONS[where] % V.size
    vertex = (flat % V.size) // 3
    with pytest.raises(
        ValueError,
        match=rf"vertices must be finite: 1 have NaN or infinite "
        rf"coordinates \(first: vertex {vertex}\)",
    ):
        shape_diameter.compute(_with(V, flat, value), F)


def test_non_finite_coordinates_are_counted(sphere):
    V, F = sphere
    bad = V.copy()
    bad[[5, 9, 30], [0, 2, 1]] = [np.nan, np.inf, -np.inf]
    with pytest.raises(ValueError, match=r"3 have NaN or infinite coordinates \(first: vertex 5\)"):
        shape_diameter.compute(bad, F)


@pytest.mark.parametrize(
    "V, F, match",
    [
        (np.zeros((0, 3)), np.zeros((1, 3), np.int64), r"empty: no vertices"),
        (np.zeros((3, 3)), np.zeros((0, 3), np.int64), r"empty: no triangles"),
        (np.zeros((0, 3)), np.zeros((0, 3), np.int64), r"empty: no vertices"),
    ],
    ids=["no-vertices", "no-triangles", "nothing"],
)
def test_empty_mesh(V, F, match):
    with pytest.raises(ValueError, match=match):
        shape_diameter.compute(V, F)
    with pytest.raises(ValueError, match=match):
        shape_diameter.sample_points(V, F)


# --------------------------------------------------------------------------- bad options


@pytest.mark.parametrize(
    "options, match",
    [
        ({"rays": 0}, rf"rays must be an integer in \[1, {MAX_RAYS}\], got 0"),
        ({"rays": -5}, r"rays must be an integer in .* got -5"),
        ({"rays": MAX_RAYS + 1}, rf"rays must be an integer in .* got {MAX_RAYS + 1}"),
        ({"rays": 2.5}, r"rays must be an integer in .* got 2.5"),
        ({"rays": 30.0}, r"rays must be an integer in .* got 30.0"),
        ({"rays": True}, r"rays must be an integer in .* got True"),
        ({"rays": "30"}, r"rays must be an integer in .* got '30'"),
        ({"rays": None}, r"rays must be an integer in .* got None"),
        ({"cone_angle": 0}, _CONE + r"got 0"),
        ({"cone_angle": 180}, _CONE + r"got 180"),
        ({"cone_angle": -30.0}, _CONE + r"got -30"),
        ({"cone_angle": 200.0}, _CONE + r"got 200"),
        ({"cone_angle": np.nan}, _CONE + r"got nan"),
        ({"cone_angle": np.inf}, _CONE + r"got inf"),
        ({"sampling": "uniform"}, r"sampling must be one of .*'fibonacci'.* got 'uniform'"),
        ({"sampling": "FIBONACCI"}, r"sampling must be one of .* got 'FIBONACCI'"),
        ({"sampling": None}, r"sampling must be one of .* got None"),
        ({"points": "edges"}, r"points must be one of .*'faces'.* got 'edges'"),
        ({"normalize": "sqrt"}, r"normalize must be one of .*'linear'.* got 'sqrt'"),
        ({"engine": "cuda"}, r"unknown engine 'cuda'; available here: auto, cpu"),
        ({"engine": 5}, r"unknown engine 5; available here: auto, cpu"),
        ({"engine": "opencl:99"}, r"no OpenCL device 99"),
        ({"engine": "opencl:no-such-device"}, r"no OpenCL device matches 'no-such-device'"),
        ({"accel": "kdtree"}, r"accel must be one of \('bvh', 'octree'\), got 'kdtree'"),
        ({"accel": None}, r"accel must be one of .* got None"),
        (
            {"bvh_quality": "best"},
            r"bvh_quality must be one of \('auto', 'high', 'fast'\), got 'best'",
        ),
        ({"accel": "octree", "octree_depth": -1}, _DEPTH + r"\[0, 16\], got -1"),
        ({"accel": "octree", "octree_depth": 17}, _DEPTH + r".* got 17"),
        ({"accel": "octree", "octree_depth": 2.5}, _DEPTH + r".* got 2.5"),
        ({"accel": "octree", "octree_depth": True}, _DEPTH + r".* got True"),
        ({"accel": "octree", "octree_leaf_size": 0}, _LEAF + r"\[1, \d+\], got 0"),
        ({"accel": "octree", "octree_leaf_size": 2**31}, _LEAF + r".* got 2147483648"),
        ({"progress": 42}, r"progress must be a callable"),
        ({"progress": "print"}, r"progress must be a callable"),
        ({"seed": -1}, r"seed must be an integer in \[0, 4294967295\], got -1"),
        ({"seed": 2**32}, rf"seed must be an integer in .* got {2**32}"),
        ({"seed": 1.5}, r"seed must be an integer in .* got 1.5"),
        ({"seed": True}, r"seed must be an integer in .* got True"),
        ({"threads": -1}, r"threads must be an integer in \[0, 4096\], got -1"),
        ({"threads": 4097}, r"threads must be an integer in \[0, 4096\], got 4097"),
        ({"threads": 2**40}, rf"threads must be an integer in .* got {2**40}"),
        ({"threads": 1.5}, r"threads must be an integer in .* got 1.5"),
        ({"threads": True}, r"threads must be an integer in .* got True"),
        ({"threads": "2"}, r"threads must be an integer in .* got '2'"),
    ],
    ids=lambda x: repr(x) if isinstance(x, dict) else "",
)
def test_bad_options(sphere, options, match):
    V, F = sphere
    with pytest.raises(ValueError, match=match):
        shape_diameter.compute(V, F, **options)


_NON_NUMBERS = pytest.mark.parametrize(
    "value",
    ["abc", "90", None, 90 + 1j, np.array([90.0, 100.0]), True],
    ids=["str", "numeric-str", "None", "complex", "array", "bool"],
)


@_NON_NUMBERS
def test_non_numeric_cone_angle_is_a_value_error_naming_it(sphere, value):
    # The contract: bad input -> ValueError naming the problem, as rays=2.5 or seed=None get.
    V, F = sphere
    with pytest.raises(ValueError, match=_CONE):
        shape_diameter.compute(V, F, cone_angle=value)
    with pytest.raises(ValueError, match=_CONE):
        shape_diameter.cone_rays([0.0, 0.0, 1.0], cone_angle=value)


@pytest.mark.parametrize(
    "value",
    [
        pytest.param(v, id=i)
        for v, i in (
            ("abc", "str"),
            ("90", "numeric-str"),
            (None, "None"),
            (90 + 1j, "complex"),
            (np.array([90.0, 100.0]), "array"),
        )
    ]
    + [pytest.param(True, id="bool")],
)
def test_reduce_lengths_non_numeric_cone_angle_is_a_value_error_naming_it(value):
    with pytest.raises(ValueError, match=r"cone_angle"):
        shape_diameter.reduce_lengths([1.0, 2.0], [0.1, 0.2], cone_angle=value)


def test_octree_too_large_for_its_pointers_is_a_value_error(sphere):
    # Depth 16 with one triangle per leaf splits every cell touching a vertex down to the
    # bottom: more leaves than the paper's 24-bit child pointers can address.
    V, F = sphere
    with pytest.raises(
        ValueError,
        match=r"octree needs more than 2\^24 leaf words.*octree_depth.*octree_leaf_size.*"
        r"accel='bvh'",
    ):
        shape_diameter.compute(V, F, accel="octree", octree_depth=16, octree_leaf_size=1)
    assert (shape_diameter.compute(V, F, accel="octree").valid_rays > 0).all()


def test_boundary_options_are_accepted(sphere):
    V, F = sphere
    # The ends of every range, and numpy integers where Python ints are expected.
    for options in (
        {"rays": 1},
        {"rays": np.int64(7)},
        {"cone_angle": 0.5},
        {"cone_angle": 179.9},
        {"seed": 2**32 - 1, "sampling": "random"},
        {"seed": np.uint32(5), "sampling": "random"},
        {"engine": "cpu"},
        {"normalize": "log"},
        {"threads": 1},
        {"threads": np.int32(3)},
        {"progress": None},
        {"accel": "octree", "octree_depth": 0},
        {"accel": "octree", "octree_depth": 16},
        {"accel": "octree", "octree_depth": 4, "octree_leaf_size": 1},
    ):
        result = shape_diameter.compute(V, F, **options)
        assert np.isfinite(result.raw).all() and (result.raw > 0).all(), options


def _on_axis_lengths(V, F, origins, axes):
    """Exact (float64) distance from each face's centroid along its inward axis to the first
    exit triangle, other than its own, of the closed mesh (V, F)."""
    p0 = V[F[:, 0]]
    e1, e2 = V[F[:, 1]] - p0, V[F[:, 2]] - p0
    out = np.empty(len(origins))
    for face, (o, d) in enumerate(zip(origins, axes)):
        p = np.cross(d, e2)
        det = np.einsum("ij,ij->i", e1, p)
        s = o - p0
        u = np.einsum("ij,ij->i", s, p) / det
        q = np.cross(s, e1)
        v = q @ d / det
        t = np.einsum("ij,ij->i", e2, q) / det
        hit = (u >= -1e-9) & (v >= -1e-9) & (u + v <= 1 + 1e-9) & (det < 0) & (t > 0)
        hit[face] = False
        out[face] = t[hit].min()
    return out


@pytest.fixture(scope="module")
def sphere_thickness(sphere):
    V, F = sphere
    origins, axes, _ = shape_diameter.sample_points(V, F)
    return _on_axis_lengths(V, F, origins.astype(np.float64), axes.astype(np.float64))


@pytest.mark.parametrize("sampling", ["fibonacci", "random", "cgal"])
def test_tiny_cone_angle_approaches_the_on_axis_thickness(sphere, sphere_thickness, sampling):
    # Any angle in (0, 180) is accepted, so a very narrow cone must give the on-axis chord.
    # (The core now carries 1 - cos(half angle), exact for narrow cones, where cos itself
    # rounds to 1 in float32 below ~0.025 degrees and the weights' angle floor became 0.)
    # Measured: within 6e-7 of the float64 on-axis length for every cone <= 0.01 degrees,
    # within 3.2e-5 for a 1 degree cone (its rays are up to 0.5 degrees off the axis).
    V, F = sphere
    for cone, tol in ((1.0, 1e-4), (0.01, 1e-5), (1e-3, 1e-5), (1e-4, 1e-5), (1e-6, 1e-5)):
        result = shape_diameter.compute(V, F, cone_angle=cone, sampling=sampling)
        assert np.isfinite(result.raw).all(), (
            f"cone_angle={cone}: {int((~np.isfinite(result.raw)).sum())} of {len(F)} values "
            f"are not finite (valid_rays min {result.valid_rays.min()})"
        )
        assert (result.valid_rays == 30).all(), cone
        rel = np.abs(result.raw / sphere_thickness - 1)
        assert rel.max() < tol, (
            f"cone_angle={cone}: off the on-axis thickness by up to {rel.max():.2e} "
            f"(face {int(rel.argmax())})"
        )
    # The rays themselves: distinct, finite, inside the cone, not all on the axis.
    half = np.radians(0.5e-3)
    d, a = shape_diameter.cone_rays(
        [0.2, -0.3, 0.9], 30, 1e-3, sampling, 4, point_index=2, tangent=[1.0, 0.0, 0.0]
    )
    assert np.isfinite(d).all() and np.isfinite(a).all()
    assert np.allclose(np.linalg.norm(d, axis=1), 1.0, atol=1e-6)
    assert (a <= half * (1 + 1e-3)).all() and a.max() > 0.5 * half
    assert np.isfinite(shape_diameter.reduce_lengths(np.ones(30), a, sampling, 30, 1e-3))


def test_stage_functions_refuse_bad_input():
    with pytest.raises(ValueError, match=r"normal must be a finite, non-zero vector"):
        shape_diameter.cone_rays([0.0, 0.0, 0.0])
    with pytest.raises(ValueError, match=r"normal must be a finite, non-zero vector"):
        shape_diameter.cone_rays([np.nan, 0.0, 1.0])
    with pytest.raises(ValueError, match=r"normal must have 3 components"):
        shape_diameter.cone_rays([0.0, 1.0])
    with pytest.raises(ValueError, match=r"rays must be an integer"):
        shape_diameter.cone_rays([0.0, 0.0, 1.0], rays=0)
    with pytest.raises(ValueError, match=_CONE + r"got 180.0"):
        shape_diameter.cone_rays([0.0, 0.0, 1.0], cone_angle=180.0)
    with pytest.raises(ValueError, match=r"tangent must be a finite, non-zero vector"):
        shape_diameter.cone_rays([0.0, 0.0, 1.0], tangent=[0.0, 0.0, 0.0])
    with pytest.raises(ValueError, match=r"tangent must be a finite, non-zero vector"):
        shape_diameter.cone_rays([0.0, 0.0, 1.0], tangent=[np.inf, 0.0, 0.0])
    with pytest.raises(ValueError, match=r"tangent must have 3 components"):
        shape_diameter.cone_rays([0.0, 0.0, 1.0], tangent=[1.0, 0.0])
    with pytest.raises(ValueError, match=r"tangent must not be parallel to the normal"):
        shape_diameter.cone_rays([0.0, 0.0, 1.0], tangent=[0.0, 0.0, -3.0])
    with pytest.raises(ValueError, match=r"sampling must be one of"):
        shape_diameter.cone_rays([0.0, 0.0, 1.0], sampling="halton")
    with pytest.raises(ValueError, match=r"seed must be an integer"):
        shape_diameter.cone_rays([0.0, 0.0, 1.0], seed=-3)
    with pytest.raises(ValueError, match=r"same length"):
        shape_diameter.reduce_lengths([1.0, 2.0], [0.1])
    with pytest.raises(ValueError, match=r"more lengths than the most rays"):
        shape_diameter.reduce_lengths(np.ones(MAX_RAYS + 1), np.ones(MAX_RAYS + 1))
    with pytest.raises(ValueError, match=r"sampling must be one of"):
        shape_diameter.reduce_lengths([1.0], [0.1], "median")
    with pytest.raises(ValueError, match=rf"rays must be an integer in \[1, {MAX_RAYS}\]"):
        shape_diameter.reduce_lengths([1.0], [0.1], rays=MAX_RAYS + 1)
    with pytest.raises(ValueError, match=r"cone_angle must be a number in"):
        shape_diameter.reduce_lengths([1.0], [0.1], cone_angle=0.0)
    assert np.isnan(shape_diameter.reduce_lengths([], []))
    # A NaN length gave NaN, a negative one a meaningless mean.
    for lengths in ([1.0, np.nan], [-1.0, 2.0], [1.0, np.inf]):
        with pytest.raises(ValueError, match=r"lengths must be finite and >= 0"):
            shape_diameter.reduce_lengths(lengths, [0.1, 0.2])
    with pytest.raises(ValueError, match=r"angles must be finite and >= 0"):
        shape_diameter.reduce_lengths([1.0, 2.0], [0.1, -0.2])
    # One number normalises to one number (it came back with shape (1,)).
    assert shape_diameter.normalize(3.0).shape == ()
    assert shape_diameter.normalize(np.ones((2, 3))).shape == (2, 3)
    V, F = shapes.icosphere(1.0, 0)
    with pytest.raises(ValueError, match=r"points must be one of .* got 'edges'"):
        shape_diameter.sample_points(V, F, "edges")
    # Stage 1 gives three arrays: origins, inward axes, tangents.
    assert [a.shape for a in shape_diameter.sample_points(V, F)] == [(20, 3)] * 3


@pytest.mark.parametrize(
    "index", [-1, 2**32, 1.5, "3", None], ids=["negative", "2**32", "float", "str", "None"]
)
def test_cone_rays_point_index_out_of_range_is_a_value_error(index):
    # point_index seeds random sampling as a uint32; outside that range the call says so
    # (rather than pybind11's TypeError listing the C++ signature).
    with pytest.raises(ValueError, match=r"point_index must be an integer in \[0, 4294967295\]"):
        shape_diameter.cone_rays([0.0, 0.0, 1.0], sampling="random", point_index=index)


def test_cone_rays_point_index_range_ends_are_accepted():
    for index in (0, 2**32 - 1, np.uint32(2**32 - 1)):
        d, a = shape_diameter.cone_rays([0.0, 0.0, 1.0], sampling="random", point_index=index)
        assert np.isfinite(d).all() and np.isfinite(a).all()
    # Different points draw different random rays.
    first, _ = shape_diameter.cone_rays([0.0, 0.0, 1.0], sampling="random", point_index=0)
    last, _ = shape_diameter.cone_rays([0.0, 0.0, 1.0], sampling="random", point_index=2**32 - 1)
    assert not np.array_equal(first, last)


@pytest.mark.parametrize("rays", [-1, 0, 2.5, True, "3"])
def test_reduce_lengths_bad_rays_is_a_value_error(rays):
    # rays=-1 (or 0) used to be silently read as "the number of lengths".
    with pytest.raises(ValueError, match=rf"rays must be an integer in \[1, {MAX_RAYS}\]"):
        shape_diameter.reduce_lengths([1.0, 2.0], [0.1, 0.2], rays=rays)


@pytest.mark.parametrize("cone_angle", [0.0, 180.0, -1.0, np.nan, np.inf])
def test_reduce_lengths_cone_angle_out_of_range_is_a_value_error(cone_angle):
    with pytest.raises(ValueError, match=r"cone_angle must be a number in \(0, 180\) degrees"):
        shape_diameter.reduce_lengths([1.0, 2.0], [0.1, 0.2], cone_angle=cone_angle)


# --------------------------------------------------------------------------- accepted input


@pytest.mark.parametrize(
    "dtype", [np.int8, np.int16, np.int32, np.uint16, np.uint32, np.uint64, np.intp]
)
def test_any_integer_dtype_for_triangles(dtype):
    V, F = shapes.icosphere(1.0, 1)  # 42 vertices: indices fit even in int8
    expected = shape_diameter.compute(V, F)
    result = shape_diameter.compute(V, F.astype(dtype))
    assert np.array_equal(result.raw, expected.raw)
    assert np.array_equal(result.valid_rays, expected.valid_rays)


@pytest.mark.parametrize(
    "dtype", [np.float32, np.float16, np.longdouble, np.int64, np.int32, np.uint8]
)
def test_any_real_dtype_for_vertices(dtype):
    # A box with integer corners is exact in every one of these dtypes, so the float64 call is
    # the reference for all of them.
    V, F = shapes.box(4.0, 6.0, 2.0, (4, 6, 2))
    V = V + [2.0, 3.0, 1.0]  # corners 0..6: representable even in uint8
    assert np.array_equal(V.astype(dtype).astype(np.float64), V)
    expected = shape_diameter.compute(V, F)
    result = shape_diameter.compute(V.astype(dtype), F)
    assert np.array_equal(result.raw, expected.raw)
    assert np.array_equal(result.valid_rays, expected.valid_rays)


def test_float32_vertices_match_their_float64_values(sphere):
    V, F = sphere
    V32 = V.astype(np.float32)
    assert np.array_equal(
        shape_diameter.compute(V32, F).raw, shape_diameter.compute(V32.astype(np.float64), F).raw
    )


def test_python_lists_are_accepted(sphere, sphere_result):
    V, F = sphere
    result = shape_diameter.compute(V.tolist(), F.tolist())
    assert np.array_equal(result.raw, sphere_result.raw)


def test_non_contiguous_views(sphere, sphere_result):
    V, F = sphere
    fortran = np.asfortranarray(V)
    assert not fortran[:, ::1].flags.c_contiguous
    assert np.array_equal(shape_diameter.compute(fortran[:, ::1], F).raw, sphere_result.raw)

    # Every other column of a wider array: a strided view.
    wide = np.zeros((len(V), 6))
    wide[:, ::2] = V
    assert not wide[:, ::2].flags.c_contiguous
    triangles_wide = np.zeros((len(F), 6), dtype=np.int32)
    triangles_wide[:, 1::2] = F
    result = shape_diameter.compute(wide[:, ::2], triangles_wide[:, 1::2])
    assert np.array_equal(result.raw, sphere_result.raw)

    # Reversed rows: the same triangles in the opposite order give the same values, reversed.
    reversed_result = shape_diameter.compute(V, F[::-1])
    assert np.array_equal(reversed_result.raw, sphere_result.raw[::-1])
    # Reversed vertex order, triangles renumbered to match.
    renumbered = shape_diameter.compute(V[::-1], len(V) - 1 - F)
    assert np.array_equal(renumbered.raw, sphere_result.raw)


def test_read_only_inputs_are_accepted(sphere, sphere_result):
    V, F = (a.copy() for a in sphere)
    V.flags.writeable = False
    F.flags.writeable = False
    assert np.array_equal(shape_diameter.compute(V, F).raw, sphere_result.raw)


# --------------------------------------------------------------------------- degenerate meshes


def _closed_sphere_with_degenerates():
    """The 1280-face sphere plus (a) a triangle with three equal vertices, (b) a collinear
    triangle and (c) a copy of an existing triangle.

    The collinear triangle is (a/2, a, a/4) for a sphere vertex a, a sliver along a radius
    inside the solid (a zero-area triangle is never hit, so it blocks no ray). The bounding
    box stays centred on 0, so the core's float32 vertices are A, A/2, A/4 exactly, and its edges
    A - A/2 = A/2 and A/4 - A/2 = -A/4 are exact too (Sterbenz); their cross product is
    exactly zero. An attempt with a midpoint of two vertices would be nearly, not exactly,
    collinear after rounding, and would get a (meaningless) normal."""
    V, F = shapes.icosphere(1.0, 3)
    a, duplicated = 7, 100
    extra = np.array([V[a] / 2, V[a] / 4])
    V2 = np.concatenate([V, extra])
    half, quarter = len(V), len(V) + 1
    degenerate = np.array([[a, a, a], [half, a, quarter]])
    F2 = np.concatenate([F, degenerate, F[duplicated : duplicated + 1]])
    m = len(F)
    faces = {"equal": m, "collinear": m + 1, "duplicate": m + 2, "original": duplicated}
    return V, F, V2, F2, faces


def test_zero_area_and_duplicated_triangles():
    V, F, V2, F2, idx = _closed_sphere_with_degenerates()
    zero_area = [idx["equal"], idx["collinear"]]
    # Precondition: the core sees both as zero-area (no axis to cast around).
    _, axes, tangents = shape_diameter.sample_points(V2, F2)
    assert (axes[zero_area] == 0).all()
    assert (tangents[zero_area] == 0).all()  # no axis, no tangent
    assert (axes[idx["duplicate"]] != 0).any()

    clean = shape_diameter.compute(V, F)
    result = shape_diameter.compute(V2, F2)
    assert np.isfinite(result.raw).all()
    # Exactly the zero-area faces have no valid ray; the duplicate casts like its twin.
    assert np.array_equal(np.flatnonzero(result.valid_rays == 0), zero_area)
    assert result.valid_rays[idx["duplicate"]] == result.valid_rays[idx["original"]] == 30
    assert result.raw[idx["duplicate"]] == result.raw[idx["original"]]
    # The extra faces do not disturb the others: zero-area faces are never hit, and a ray
    # meets either copy of the duplicated face at the same distance.
    assert np.allclose(result.raw[: len(F)], clean.raw, rtol=1e-6)
    # Filled values are a mean of the neighbours that have a value.
    for face in zero_area:
        around = [q for q in _neighbours(F2, face) if result.valid_rays[q] > 0]
        assert len(around) >= 5
        values = result.raw[around]
        assert values.min() <= result.raw[face] <= values.max()
        assert result.raw[face] > 0


@pytest.mark.parametrize("points", ["faces", "vertices"])
@pytest.mark.parametrize("far", [1e3, 1e8])
def test_zero_area_faces_reaching_far_vertices_change_nothing_else(points, far):
    # One face (0, 0, k) to a stray vertex far away set the near-hit cutoff and the
    # centre (bunny00 with a vertex 1000 units off: 8.8% of faces >5% off; a building at UTM
    # coordinates with one reaching the origin: every value 0). Now such faces' corners take
    # no part in the box: the rest is bit for bit the clean mesh's. Three kinds: a repeated
    # corner, three corners at one far position, three distinct corners on one line.
    V, F = shapes.icosphere(1.0, 3)
    n, m = len(V), len(F)
    stray = np.array(
        [
            [far, 0.0, 0.0],
            [far, 0.0, 0.0],
            [far, 0.0, 0.0],
            [2 * far, 0.0, 0.0],
            [1.5 * far, 0.0, 0.0],
        ]
    )
    V2 = np.vstack([V, stray])
    F2 = np.vstack([F, [[0, 0, n], [n, n + 1, n + 2], [n, n + 3, n + 4]]])
    clean = shape_diameter.compute(V, F, points=points)
    result = shape_diameter.compute(V2, F2, points=points)
    assert result.near_cutoff == clean.near_cutoff
    count = m if points == "faces" else n
    assert np.array_equal(result.raw[:count], clean.raw)
    if points == "faces":
        assert (result.valid_rays[m:] == 0).all() and np.isfinite(result.raw[m:]).all()
    # Where no face has area, every used vertex makes the box (it cannot be empty).
    with pytest.warns(RuntimeWarning, match="no ray of any point"):
        only = shape_diameter.compute(V2, F2[m:], points=points)
    width = np.ptp(V2[np.unique(F2[m:])], axis=0).max()
    assert (only.valid_rays == 0).all() and only.near_cutoff == pytest.approx(2e-5 * width)


def test_open_mesh_fills_faces_whose_rays_all_escape():
    # Keep a dish of the sphere: the faces more than 130 degrees from +z. A ray from a face at
    # angle beta (from +z) at angle t to its inward normal meets the sphere 2t from the face's
    # antipode, so a face's rays stay within 120 degrees of that antipode. Faces beyond 170
    # degrees see only the missing part (every ray escapes); nearer the rim some rays meet the
    # dish on the other side.
    V, F = shapes.icosphere(1.0, 4)
    centroids = V[F].mean(axis=1)
    polar = np.degrees(np.arccos(centroids[:, 2] / np.linalg.norm(centroids, axis=1)))
    F = F[polar > 130.0]
    # Not the warning that no ray found anything (some faces have values), but the one that
    # few did: 2.3 of 30 a face.
    with pytest.warns(RuntimeWarning, match=r"only \d\.\d of 30 rays .*open or flat"):
        result = shape_diameter.compute(V, F)
    assert result.raw.shape == (len(F),)
    assert np.isfinite(result.raw).all() and (result.raw > 0).all()

    # Predict each face's kept rays from where they meet the ideal sphere: kept if the hit
    # lies on the dish. The dish's rim is jagged (faces were cut by their centroids), so hits
    # within 3 degrees of 130 may go either way.
    origins, axes, tangents = shape_diameter.sample_points(V, F)
    origins = origins.astype(np.float64)
    low = np.empty(len(F), dtype=np.int64)
    high = np.empty(len(F), dtype=np.int64)
    for f in range(len(F)):
        d, _ = shape_diameter.cone_rays(
            axes[f], 30, 120.0, "fibonacci", 0, point_index=f, tangent=tangents[f]
        )
        d = d.astype(np.float64)
        b = d @ origins[f]
        t = -b + np.sqrt(b * b - (origins[f] @ origins[f] - 1.0))
        hit = origins[f] + t[:, None] * d
        hit_polar = np.degrees(np.arccos(np.clip(hit[:, 2], -1, 1)))
        low[f] = (hit_polar > 133.0).sum()
        high[f] = (hit_polar > 127.0).sum()
    assert ((low <= result.valid_rays) & (result.valid_rays <= high)).all(), (
        "kept rays outside the predicted range at faces "
        f"{np.flatnonzero((result.valid_rays < low) | (result.valid_rays > high))[:10].tolist()}"
    )
    escaped = np.flatnonzero(high == 0)
    assert len(escaped) >= 20 and (result.valid_rays[escaped] == 0).all()
    assert (result.valid_rays[low > 0] > 0).all()
    assert (low > 0).sum() >= 100

    # Every filled value is a mean of neighbour values (of earlier fill layers or measured),
    # so it lies within its neighbours' range.
    for face in np.flatnonzero(result.valid_rays == 0):
        values = result.raw[_neighbours(F, face)]
        assert values.min() - 1e-6 <= result.raw[face] <= values.max() + 1e-6, face


def test_components_keep_their_own_scale():
    # Two spheres, radius 1 and 2, 100 apart. On a sphere every ray from a face is a chord,
    # 2 r cos(angle), so each component's value is 2 r times the reduction of the cosines.
    V1, F1 = shapes.icosphere(1.0, 4)
    V2, F2 = shapes.icosphere(2.0, 4)
    V = np.concatenate([V1, V2 + [100.0, 0.0, 0.0]])
    F = np.concatenate([F1, F2 + len(V1)])
    result = shape_diameter.compute(V, F)
    assert (result.valid_rays == 30).all()
    _, angles = shape_diameter.cone_rays([0.0, 0.0, 1.0])
    unit = shape_diameter.reduce_lengths(2 * np.cos(angles.astype(np.float64)), angles)
    for radius, part in ((1.0, slice(0, len(F1))), (2.0, slice(len(F1), None))):
        values = result.raw[part].astype(np.float64)
        expected = radius * unit
        # Per face within 2 %: facets sit up to ~0.2 % inside the sphere at 4 subdivisions,
        # and the outlier rule can turn that into ~1.5 % at a face (test_analytic_shapes).
        assert np.abs(values / expected - 1).max() < 0.02, radius
        assert abs(values.mean() / expected - 1) < 2e-3, radius


@pytest.mark.parametrize("points", ["faces", "vertices"])
def test_a_thin_part_in_a_large_scene_reads_high_and_is_warned_of(points):
    # Hits nearer than 2e-5 of the whole mesh's size are ignored, so a 1 mm plate
    # beside a ball tens of metres away lost its shortest rays and read high, without a word.
    plate_v, plate_f = shapes.box(1.0, 1.0, 0.001, 8)
    ball_v, ball_f = shapes.icosphere(0.25, 2)
    alone = shape_diameter.compute(plate_v, plate_f, points=points)
    assert alone.near_cutoff == pytest.approx(2e-5, rel=1e-6)
    plate_points = len(plate_f) if points == "faces" else len(plate_v)
    for distance, reads_high in ((0.0, False), (60.0, True)):
        v = np.concatenate([plate_v, ball_v + [distance + 2.0, 0.0, 0.0]])
        f = np.concatenate([plate_f, ball_f + len(plate_v)])
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            result = shape_diameter.compute(v, f, points=points)
        assert result.near_cutoff == pytest.approx(2e-5 * (distance + 2.75), rel=1e-6)
        plate = np.median(result.raw[:plate_points])
        said = [str(w.message) for w in caught if "near-hit cutoff" in str(w.message)]
        if reads_high:
            assert plate > 1.1 * np.median(alone.raw)
            assert len(said) == 1 and said[0].startswith("1 of the mesh's 2 parts ("), said
            assert "Compute those parts on their own" in said[0]
        else:
            np.testing.assert_allclose(plate, np.median(alone.raw), rtol=0.02)
            assert not said


@pytest.mark.parametrize("points", ["faces", "vertices"])
def test_a_part_that_keeps_no_ray_is_warned_of(points):
    # A 1 mm cube beside a 100 m slab keeps no ray (every hit within the 2 mm
    # cutoff) and took the slab's median, 14,000x its size, without a word; so did an
    # inside-out ball left as it was, and an open sheet beside a solid.
    slab_v, slab_f = shapes.box(100.0, 100.0, 10.0, 2)
    ball_v, ball_f = shapes.icosphere(1.0, 2)
    sheet_v = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]])
    sheet_f = np.array([[0, 1, 2], [1, 3, 2], [0, 2, 1], [1, 2, 3]])  # a sheet, both sides
    cases = {
        "tiny": (shapes.box(0.001, 0.001, 0.001, 1), "as_is"),
        "inside out": ((ball_v, ball_f[:, ::-1]), "as_is"),
        "open": ((sheet_v, sheet_f), "auto"),
    }
    for name, ((part_v, part_f), orientation) in cases.items():
        v = np.concatenate([slab_v, part_v + [0.0, 0.0, 20.0]])
        f = np.concatenate([slab_f, part_f + len(slab_v)])
        with shape_diameter.collect_warnings() as caught:
            result = shape_diameter.compute(v, f, points=points, orientation=orientation)
        said = [m for m in caught if "kept no ray" in m]
        assert len(said) == 1 and said[0].startswith(
            f"1 of the mesh's 2 parts ({len(part_f)} faces) kept no ray"
        ), (name, caught)
        part = slice(len(slab_f), None) if points == "faces" else slice(len(slab_v), None)
        assert (result.valid_rays[part] == 0).all()
    # Alone (nothing measured anywhere), the whole mesh's own warning says it, not this one.
    with shape_diameter.collect_warnings() as caught:
        shape_diameter.compute(ball_v, ball_f[:, ::-1], points=points, orientation="as_is")
    assert not any("kept no ray" in m for m in caught) and caught


def test_ordinary_models_thin_in_places_are_not_warned_of_the_cutoff():
    # Faces of real models come near the cutoff here and there (ChineseDragon: 12 of 20k
    # within 4x): only whole parts much smaller than the mesh are worth the warning.
    v, f = load_mesh(DATA / "ChineseDragon-10kv.off")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        result = shape_diameter.compute(v, f)
    assert ((result.raw < 4 * result.near_cutoff) & (result.valid_rays > 0)).sum() >= 5


def test_unused_vertices_change_nothing(sphere, sphere_result):
    V, F = sphere
    # Unused vertices inside the bounding box, first and last: the mesh the core builds is
    # the same (same box, same centre), so faces get bitwise the same values.
    extra_front = np.array([[0.0, 0.0, 0.0], [0.1, -0.2, 0.3]])
    V2 = np.concatenate([extra_front, V, [[0.5, 0.5, 0.0]]])
    F2 = F + len(extra_front)
    result = shape_diameter.compute(V2, F2)
    assert np.array_equal(result.raw, sphere_result.raw)

    # Per vertex: the unused ones have no normal, so no ray, and a finite filled value.
    per_vertex = shape_diameter.compute(V2, F2, points="vertices")
    unused = [0, 1, len(V2) - 1]
    assert np.isfinite(per_vertex.raw).all()
    assert (per_vertex.valid_rays[unused] == 0).all()
    used = np.setdiff1d(np.arange(len(V2)), unused)
    assert (per_vertex.valid_rays[used] > 0).all()
    alone = shape_diameter.compute(V, F, points="vertices")
    assert np.array_equal(per_vertex.raw[used], alone.raw)
    assert (per_vertex.raw[unused] > 0).all()


@pytest.mark.parametrize("widths_away", [10.0, 1e4, 1e20])
@pytest.mark.parametrize("smoothing", ["none", "projected"])
def test_an_unused_vertex_far_away_changes_nothing(sphere, widths_away, smoothing):
    # A stray vertex far outside the mesh (one at a georeferenced mesh's origin): it took part
    # in the bounding box, and so in the near-hit threshold and the unit scaling: 10 widths
    # away changed values by up to 28%, 1e4 widths away left faces without a ray.
    V, F = sphere
    stray = V.min(axis=0) - widths_away * np.ptp(V, axis=0).max()
    alone = shape_diameter.compute(V, F, smoothing=smoothing)
    with_stray = shape_diameter.compute(np.vstack([V, stray]), F, smoothing=smoothing)
    assert np.array_equal(with_stray.values, alone.values)
    assert np.array_equal(with_stray.normalized, alone.normalized)
    per_vertex = shape_diameter.compute(np.vstack([V, stray]), F, points="vertices")
    by_itself = shape_diameter.compute(V, F, points="vertices")
    assert np.array_equal(per_vertex.raw[:-1], by_itself.raw)
    assert per_vertex.valid_rays[-1] == 0


def test_smoothing_alone_ignores_an_unused_vertex_far_away(sphere):
    V, F = sphere
    values = shape_diameter.compute(V, F).raw
    stray = np.vstack([V, V.min(axis=0) - 1e12])  # the mesh alone is unit size: not scaled
    np.testing.assert_array_equal(
        shape_diameter.smooth(stray, F, values, "projected"),
        shape_diameter.smooth(V, F, values, "projected"),
    )


@pytest.mark.parametrize("scale, stray", [(1.0, 1e31), (1e-25, 1e8)])
@pytest.mark.parametrize("points", ["faces", "vertices"])
def test_a_vertex_beyond_the_float_range_is_refused_by_name(sphere, scale, stray, points):
    # Beyond 1e30 units, or beyond 1e30 widths of a mesh far below unit size, which compute()
    # scales up (a stray vertex of a 1e-25-wide mesh overflowed floats: found by fuzzing).
    V, F = sphere
    with pytest.raises(
        ValueError,
        match=rf"vertex {len(V)}, used by no triangle with area, "
        r"lies too far from the mesh for 32-bit floats",
    ):
        shape_diameter.compute(np.vstack([V * scale, [stray, 0.0, 0.0]]), F, points=points)
    # A little nearer, it takes no part.
    near = shape_diameter.compute(np.vstack([V * scale, [stray / 1e3, 0.0, 0.0]]), F, points=points)
    alone = shape_diameter.compute(V * scale, F, points=points)
    assert np.array_equal(near.raw[: len(alone.raw)], alone.raw)


def test_single_triangle_warns_and_gives_zeros():
    V = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    F = np.array([[0, 1, 2]])
    for points, count in (("faces", 1), ("vertices", 3)):
        with pytest.warns(RuntimeWarning, match=r"no ray of any point"):
            result = shape_diameter.compute(V, F, points=points)
        assert result.raw.shape == (count,)
        assert (result.raw == 0).all() and (result.valid_rays == 0).all()
        assert (result.normalized == 0).all()


def test_inside_out_mesh_warns_when_its_winding_is_trusted(sphere):
    # Reversed winding kept as is: every ray meets the surface from the outside (det > 0),
    # none exits. (orientation="auto", the default, turns it outward: test_orientation.py.)
    V, F = sphere
    with pytest.warns(RuntimeWarning, match=r"inside out"):
        result = shape_diameter.compute(V, F[:, ::-1], orientation="as_is")
    assert (result.raw == 0).all() and (result.valid_rays == 0).all()


@pytest.mark.parametrize("name, orientation", [("horse.ply", "as_is"), ("spot.obj", "flip")])
def test_a_real_mesh_wound_inside_out_warns_that_few_rays_were_kept(name, orientation):
    # Rays that leave through the near wall: 1.5-2.5 of 30 kept, half the faces none. Some
    # still hit (the legs, the ears), so the all-or-nothing warning above never fired.
    V, F = load_mesh(DATA / name)
    with pytest.warns(
        RuntimeWarning, match=rf"only \d+\.\d of 30 rays .*inside out.*{orientation}"
    ):
        result = shape_diameter.compute(V, F, orientation=orientation)
    assert result.valid_rays.mean() < 0.25 * 30


def test_meshes_wound_outward_or_merely_open_do_not_warn():
    # An open hemisphere keeps 13 of 30 rays: open, but measured.
    V, F = shapes.icosphere(1.0, 3)
    hemisphere = F[V[F].mean(axis=1)[:, 2] > 0]
    for v, f in ((V, hemisphere), load_mesh(DATA / "horse.ply")):
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            shape_diameter.compute(v, f)


@pytest.mark.parametrize("cut", ["by a plane", "by truncating its face list"])
def test_a_solid_cut_open_warns_that_faces_along_the_opening_kept_few_rays(cut):
    # Half of the horse: its faces keep 18-21 of 30 rays on average (no few-rays warning), but
    # 1500-1700 along the opening keep under 5, some none: values that measure what lies
    # beyond the opening, or are their neighbours'.
    V, F = load_mesh(DATA / "horse.ply")
    if cut == "by a plane":
        x = V[F].mean(axis=1)[:, 0]
        half = F[x > np.median(x)]
    else:
        half = F[: len(F) // 2]
    with pytest.warns(
        RuntimeWarning,
        match=r"^\d+ of the \d+ faces \(\d\.\d%\) kept fewer than 5 of their 30 rays, \d+ of "
        r"them none: is the mesh open or cut",
    ) as caught:
        result = shape_diameter.compute(V, half)
    assert len(caught) == 1
    assert result.valid_rays.mean() >= 0.25 * 30
    assert np.count_nonzero(result.valid_rays < 5) >= 0.005 * len(half)


@pytest.mark.parametrize("points", ["faces", "vertices"])
@pytest.mark.parametrize(
    "name",
    sorted(
        str(p.relative_to(DATA)) for p in DATA.rglob("*") if p.suffix in (".obj", ".off", ".ply")
    ),
)
def test_the_meshes_of_the_tests_do_not_warn_of_poorly_measured_points(name, points):
    # Closed, or nearly (Suzanne's eyes are open: 23 of her faces keep under 5 of 30 rays; the
    # dragon's vertices 22, the most of the closed ones).
    V, F = load_mesh(DATA / name)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        shape_diameter.compute(V, F, points=points)


@pytest.mark.parametrize("points", ["faces", "vertices"])
def test_zero_area_faces_are_not_taken_for_an_opening(points):
    # Every ninth face of a closed sphere collapsed to a segment: those faces (and on vertices
    # none, since their corners belong to faces with area too) cast no ray, and keep none, as
    # on any mesh; that says nothing of an opening.
    V, F = shapes.icosphere(1.0, 4)
    F = F.copy()
    F[::9, 1] = F[::9, 0]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        result = shape_diameter.compute(V, F, points=points, orientation="as_is")
    if points == "faces":
        assert np.count_nonzero(result.valid_rays[::9] == 0) == len(F[::9])


def test_the_poorly_measured_rule_needs_both_a_count_and_a_share():
    from shape_diameter.api import poorly_measured

    def rays_kept(poor, total):
        return np.array([4] * poor + [30] * (total - poor), dtype=np.int32)

    assert poorly_measured(rays_kept(49, 1000), 30) is None  # under 50 points
    assert poorly_measured(rays_kept(50, 10001), 30) is None  # under 0.5%
    message = poorly_measured(rays_kept(50, 10000), 30)
    assert message.startswith("50 of the 10000 faces (0.5%) kept fewer than 5 of their 30")
    on_vertices = poorly_measured(rays_kept(50, 1000), 30, "vertices")
    assert on_vertices.startswith("50 of the 1000 vertices")
    # Under a sixth, rounded up: 2 of 8 rays.
    assert poorly_measured(np.array([2] * 100, dtype=np.int32), 8) is None
    assert "fewer than 2 of their 8 rays" in poorly_measured(np.array([1] * 100), 8)


# --------------------------------------------------------------------------- progress


@pytest.fixture(scope="module")
def medium_sphere():
    # 20 chunks of 256 faces: the engine reports progress between chunks.
    return shapes.icosphere(1.0, 4)


def test_progress_is_monotonic_and_ends_at_one(medium_sphere):
    V, F = medium_sphere
    seen = []
    result = shape_diameter.compute(V, F, progress=seen.append)
    assert len(seen) >= 2
    assert all(isinstance(x, float) for x in seen)
    assert all(0.0 <= x <= 1.0 for x in seen)
    assert all(a <= b for a, b in zip(seen, seen[1:])), seen
    assert seen[-1] == 1.0
    assert seen[0] == 0.0
    # Reporting progress does not change the values.
    assert np.array_equal(result.raw, shape_diameter.compute(V, F).raw)


class _Stop(Exception):
    pass


@pytest.mark.parametrize("exception", [_Stop, KeyboardInterrupt])
@pytest.mark.parametrize("when", ["first call", "while casting"])
def test_progress_exception_propagates_and_leaves_no_trace(medium_sphere, exception, when):
    V, F = medium_sphere
    calls = []

    def progress(fraction):
        calls.append(fraction)
        # The casting stage reports fractions strictly between 0.05 and 0.99.
        if when == "first call" or 0.05 < fraction < 1.0:
            raise exception("stop here")

    with pytest.raises(exception, match="stop here"):
        shape_diameter.compute(V, F, rays=60, progress=progress)
    if when == "first call":
        assert calls == [0.0]
    else:
        assert 0.05 < calls[-1] < 1.0, calls
        assert sum(0.05 < c < 1.0 for c in calls) == 1, "progress was called after it raised"
    # The next computation is unaffected.
    after = shape_diameter.compute(V, F, rays=60)
    assert np.isfinite(after.raw).all() and (after.valid_rays > 0).all()


class _Signalled(Exception):
    pass


@pytest.mark.parametrize("call", ["compute", "smooth"])
def test_a_signal_stops_native_work_without_a_progress_callback(call):
    # Ctrl-C during compute() with no progress callback waited for the whole computation
    # (22 s at 128 rays on a large mesh): Python's signal handlers run
    # only between bytecodes. The core now runs them whenever it would report progress.
    # SIGUSR1 with a handler that raises stands in for SIGINT's KeyboardInterrupt.
    V, F = shapes.icosphere(1.0, 6)  # 81920 faces

    def work():
        if call == "compute":
            return shape_diameter.compute(V, F, rays=128, engine="cpu", threads=1)
        values = np.linspace(0.0, 1.0, len(F)).astype(np.float32)
        return shape_diameter.smooth(V, F, values, "kring", k=12, threads=1)

    clock = time.perf_counter()
    work()
    whole = time.perf_counter() - clock

    def on_signal(signum, frame):
        raise _Signalled()

    previous = signal.signal(signal.SIGUSR1, on_signal)
    timer = threading.Timer(0.1 * whole, os.kill, (os.getpid(), signal.SIGUSR1))
    try:
        timer.start()
        clock = time.perf_counter()
        with pytest.raises(_Signalled):
            work()
        stopped_after = time.perf_counter() - clock
    finally:
        timer.cancel()
        signal.signal(signal.SIGUSR1, previous)
    assert stopped_after < 0.6 * whole, (stopped_after, whole)
    after = shape_diameter.compute(V, F, rays=8)  # the next computation is unaffected
    assert (after.valid_rays > 0).all()


# --------------------------------------------------------------------------- GIL


def test_gil_is_released_while_computing():
    V, F = shapes.icosphere(1.0, 6)  # 81920 faces
    assert len(F) > 80000
    stamps = []
    stop = threading.Event()

    def tick():
        while not stop.is_set():
            stamps.append(time.perf_counter())
            time.sleep(0.001)

    ticker = threading.Thread(target=tick)
    ticker.start()
    try:
        time.sleep(0.05)
        start = time.perf_counter()
        # 24 rays: about 0.6 s of casting on one thread here, well above the 0.2 s needed
        # to tell (8 rays fell to 0.2 s once the CPU engine got faster).
        result = shape_diameter.compute(V, F, rays=24, threads=1, engine="cpu")  # not a GPU
        end = time.perf_counter()
    finally:
        stop.set()
        ticker.join()
    cast = result.timings["cast"]
    assert cast > 0.2, "the computation was too short to tell anything"
    during = np.array([s for s in stamps if start <= s <= end])
    # Held GIL: the ticker would stop for the whole cast. Released: it ticks every ~1 ms.
    assert len(during) > 20, f"only {len(during)} ticks during a {end - start:.2f} s compute"
    edges = np.concatenate([[start], during, [end]])
    longest_pause = np.diff(edges).max()
    assert longest_pause < 0.5 * cast, (
        f"the other thread stalled {longest_pause:.3f} s during a {cast:.3f} s cast"
    )


def test_mesh_checks_span_the_native_chunks():
    # The checks run natively in chunks of 32768 items merged in order: the count sums every
    # chunk, the first bad vertex is the first overall, the index range spans every chunk.
    rng = np.random.default_rng(7)
    V = rng.random((100_000, 3))
    V[[90_000, 40_000, 70_000], [1, 2, 0]] = [np.inf, np.nan, -np.inf]
    F = rng.integers(5, 99_000, size=(60_000, 3))
    F[45_000, 1], F[11_000, 2] = 2, 99_999
    from shape_diameter import _core

    assert _core.mesh_values(V, F) == (3, 40_000, 2, 99_999)
    F[20_000, 0] = -7
    assert _core.mesh_values(V, F)[2] == -7
    with pytest.raises(
        ValueError, match=r"3 have NaN or infinite coordinates \(first: vertex 40000\)"
    ):
        shape_diameter.compute(V, F)
