# SPDX-License-Identifier: GPL-3.0-or-later
"""The BVH and the faces' points made on the device (kernels/cl/sdf_lbvh_kernels.cl): the same
values as the CPU engine's, bit for bit, on every device and cast kernel, for meshes that
stress the build (zero-area faces, faces that share one Morton cell, one triangle, faces to
reverse). GPUs make this tree by default (engine 'auto'/'opencl', points 'faces'); the
opencl_tree test override forces it ('device') or the host's ('host') anywhere, PoCL
included."""

import warnings

import numpy as np
import pytest
import shape_diameter as sd
from opencl_devices import OPENCL
from shape_diameter import _testing
from shape_diameter.mesh_io import load_mesh
from shapes import box
from test_opencl import DATA

KERNELS = ["bvh_per_ray", "bvh_per_point"]


def same_bits(a, b):
    differ = np.flatnonzero((a.raw != b.raw) | (a.valid_rays != b.valid_rays))
    assert differ.size == 0, f"{differ.size} of {a.raw.size} points differ, first {differ[:5]}"


def on_device_tree(v, f, engine, kernel="bvh_per_ray", **options):
    with _testing.overrides(opencl_tree="device", opencl_kernel=kernel):
        result = sd.compute(v, f, engine=engine, **options)
    made = {"build (device)", "rewind (device)"} & set(result.timings)
    assert len(made) == 1 and "build wait" not in result.timings
    return result


def clustered_mesh():
    """A shell of 400 small triangles whose centres fall in a handful of Morton cells (equal
    codes: the tree splits them by index), around a box that spreads the code range."""
    rng = np.random.default_rng(3)
    v, f = [], []
    for _ in range(400):
        centre = np.array([0.5, 0.5, 0.5]) + 1e-5 * rng.standard_normal(3)
        corners = centre + 0.05 * rng.standard_normal((3, 3))
        f.append([len(v), len(v) + 1, len(v) + 2])
        v.extend(corners)
    box_v, box_f = load_mesh(DATA / "fandisk.obj")
    f = np.vstack([np.array(f), box_f + len(v)])
    v = np.vstack([np.array(v), box_v])
    return v, f


def spread_bits_10(x):
    x = x.astype(np.uint32) & 0x3FF
    for shift, mask in ((16, 0x030000FF), (8, 0x0300F00F), (4, 0x030C30C3), (2, 0x09249249)):
        x = (x | (x << shift)) & mask
    return x


def reference_keys(v, f):
    """The faces' order, codes, count with area and margin, as the device's kernels make them,
    in numpy float32: the mesh centred as the core centres it, each face's box (+0 corners),
    the Morton code of its centre, a stable sort (zero-area faces last), bvh_margin's
    formula."""
    v = np.asarray(v, np.float64)
    v = (v - 0.5 * (v.min(axis=0) + v.max(axis=0))).astype(np.float32)
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    e1, e2 = b - a, c - a
    area = (np.cross(e1, e2) != 0).any(axis=1)
    lo = np.minimum(a, np.minimum(b, c)) + np.float32(0)
    hi = np.maximum(a, np.maximum(b, c)) + np.float32(0)
    all_lo, all_hi = lo[area].min(axis=0), hi[area].max(axis=0)
    scale = np.float32(1023) / np.maximum(all_hi - all_lo, np.float32(1e-30))
    centre = (lo + hi) * np.float32(0.5)
    cell = np.clip((centre - all_lo) * scale, 0, 1023).astype(np.uint32)
    code = (
        spread_bits_10(cell[:, 0])
        | (spread_bits_10(cell[:, 1]) << 1)
        | (spread_bits_10(cell[:, 2]) << 2)
    )
    code = np.where(area, code, np.uint32(1 << 30))
    order = np.argsort(code, kind="stable").astype(np.uint32)
    edge = np.abs(np.concatenate([e1[area], e2[area]])).max()
    coordinate = np.abs(np.concatenate([all_lo, all_hi])).max()
    margin = (
        np.float32(4) * np.float32(1e-5) * edge
        + np.float32(np.ldexp(coordinate, -20))
        + np.finfo(np.float32).tiny
    )
    return order, code[order][: area.sum()], int(area.sum()), np.float32(margin)


@pytest.mark.parametrize("engine", OPENCL)
@pytest.mark.parametrize("mesh", ["fandisk.obj", "bunny00.off", "clustered"])
def test_the_devices_sort_of_the_faces_matches_a_reference(engine, mesh):
    # Every face once, faces with area first in Morton order of their box centres with ties in
    # face order, then the zero-area ones: 75k faces are 300 tiles of the sort, 8 passes.
    if mesh == "clustered":
        v, f = clustered_mesh()
        f[::9, 1] = f[::9, 0]
    else:
        v, f = load_mesh(DATA / mesh)
    order, codes, with_area, margin = _testing.opencl_tree_keys(v, f, int(engine.split(":")[1]))
    want_order, want_codes, want_with_area, want_margin = reference_keys(v, f)
    assert with_area == want_with_area
    np.testing.assert_array_equal(codes, want_codes)
    np.testing.assert_array_equal(order, want_order)
    assert np.float32(margin) == want_margin


@pytest.mark.parametrize("engine", OPENCL)
@pytest.mark.parametrize("kernel", KERNELS)
@pytest.mark.parametrize("mesh", ["fandisk.obj", "teapot.obj", "spot.obj"])
def test_device_tree_gives_the_cpu_engines_bits(engine, kernel, mesh):
    v, f = load_mesh(DATA / mesh)
    cpu = sd.compute(v, f, engine="cpu")
    same_bits(on_device_tree(v, f, engine, kernel), cpu)


@pytest.mark.parametrize("engine", OPENCL)
# The collapsed faces leave holes beside them, through which some neighbours' rays escape: the
# warning about poorly measured points is right there, and not what this test is about.
@pytest.mark.filterwarnings("ignore:.*kept fewer than:RuntimeWarning")
def test_zero_area_and_clustered_faces(engine):
    v, f = clustered_mesh()
    f = f.copy()
    f[::9, 1] = f[::9, 0]  # zero-area faces among the rest: no triangle record, still a point
    cpu = sd.compute(v, f, engine="cpu", orientation="as_is")
    same_bits(on_device_tree(v, f, engine, orientation="as_is"), cpu)


@pytest.mark.parametrize("engine", OPENCL)
def test_reversed_faces_are_oriented_before_the_points_are_made(engine):
    v, f = load_mesh(DATA / "spot.obj")
    flipped = f.copy()
    flipped[::3] = flipped[::3, ::-1]
    cpu = sd.compute(v, flipped, engine="cpu")
    device = on_device_tree(v, flipped, engine)
    assert device.flipped_faces == cpu.flipped_faces > 0
    np.testing.assert_array_equal(device.reversed_faces, cpu.reversed_faces)
    same_bits(device, cpu)
    # The orientation was decided beside a cast of the mesh as wound, then the faces reversed
    # and the mesh cast again, on the first cast's tree rewound (not made again).
    assert {"cast (discarded)", "orientation: reverse faces", "cast"} <= set(device.timings)
    assert "rewind (device)" in device.timings and "build (device)" not in device.timings


@pytest.mark.parametrize("engine", OPENCL)
def test_a_mesh_wound_right_is_cast_while_its_orientation_is_decided(engine):
    v, f = load_mesh(DATA / "spot.obj")
    device = on_device_tree(v, f, engine)
    assert device.flipped_faces == 0
    assert "orientation (beside cast)" in device.timings
    assert "cast (discarded)" not in device.timings
    assert not any(k.startswith("prepare: orientation") for k in device.timings)
    same_bits(device, sd.compute(v, f, engine="cpu"))


@pytest.mark.parametrize("orientation", ["flip", "as_is"])
def test_other_orientations_are_applied_before_the_cast(orientation):
    v, f = load_mesh(DATA / "spot.obj")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # 'flip' turns spot inside out
        cpu = sd.compute(v, f, engine="cpu", orientation=orientation)
        device = on_device_tree(v, f, OPENCL[0], orientation=orientation)
    assert "orientation (beside cast)" not in device.timings
    same_bits(device, cpu)


@pytest.mark.parametrize("engine", OPENCL)
@pytest.mark.parametrize("faces", [1, 2, 4])
def test_tiny_meshes(engine, faces):
    # One triangle (the root is its leaf), two facing each other, a tetrahedron.
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [0, 1, 1]], float)
    f = {1: [[0, 1, 2]], 2: [[0, 2, 1], [3, 4, 5]], 4: [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]}
    f = np.array(f[faces])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # one triangle hits nothing
        cpu = sd.compute(v, f, engine="cpu", orientation="as_is")
        device = on_device_tree(v, f, engine, orientation="as_is")
    same_bits(device, cpu)
    assert faces == 1 or (cpu.valid_rays > 0).any()


@pytest.mark.parametrize("engine", OPENCL)
def test_only_zero_area_faces_cast_nothing(engine):
    v = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    f = np.array([[0, 1, 2], [3, 3, 1], [0, 0, 0]])
    with _testing.overrides(opencl_tree="device"), pytest.warns(RuntimeWarning, match=r"no ray"):
        result = sd.compute(v, f, engine=engine)
    assert (result.raw == 0).all() and (result.valid_rays == 0).all()


@pytest.mark.parametrize("engine", OPENCL)
def test_random_sampling_equals_the_host_trees_values(engine):
    # Random rays are made with the device's sin and cos, so the reference is the same device
    # casting the host's tree: the same rays (seeded by face), the same nearest hits.
    v, f = load_mesh(DATA / "teapot.obj")
    options = dict(engine=engine, sampling="random", seed=11, rays=21)
    with _testing.overrides(opencl_kernel="bvh_per_ray", opencl_tree="host"):
        host = sd.compute(v, f, **options)
    with _testing.overrides(opencl_kernel="bvh_per_ray", opencl_tree="device"):
        same_bits(sd.compute(v, f, **options), host)


@pytest.mark.parametrize("engine", OPENCL)
def test_smoothing_inside_compute_gets_the_hosts_points(engine):
    # The device makes the cast's points; projected smoothing beside the cast needs them on
    # the host too, and must smooth as after a host-made cast.
    v, f = load_mesh(DATA / "spot.obj")
    cpu = sd.compute(v, f, engine="cpu", smoothing="projected")
    device = on_device_tree(v, f, engine, smoothing="projected")
    np.testing.assert_array_equal(device.raw, cpu.raw)
    np.testing.assert_allclose(device.values, cpu.values, rtol=0, atol=0)


def test_device_memory_stays_under_200_bytes_a_face():
    # 142 bytes a face: the mesh (about 18 here) and 124 (device_tree.cpp's phases); the bound
    # keeps a little room and catches a buffer that outlives its phase.
    v, f = load_mesh(DATA / "bunny00.off")
    result = on_device_tree(v, f, OPENCL[0])
    assert 0 < result.device_memory <= 150 * len(f)


def test_a_triangle_soup_stays_under_200_bytes_a_face():
    # Three vertices of its own a face: the mesh itself takes 48 bytes a face on the device.
    v, f = load_mesh(DATA / "bunny00.off")
    corners = v[f].reshape(-1, 3)
    soup = np.arange(len(corners), dtype=np.int32).reshape(-1, 3)
    result = on_device_tree(corners, soup, OPENCL[0], orientation="as_is")
    assert 0 < result.device_memory <= 200 * len(soup)


def test_an_unknown_tree_name_is_refused():
    with pytest.raises(ValueError, match="opencl_tree='gpu': use engine, host, device"):
        _testing.overrides(opencl_tree="gpu")
    assert _testing.current_overrides()["opencl_tree"] == "engine"  # nothing was set


def test_vertex_points_and_the_octree_keep_the_host_path():
    # The device makes face points only, and only the BVH.
    v, f = load_mesh(DATA / "fandisk.obj")
    for options in (dict(points="vertices"), dict(accel="octree")):
        with _testing.overrides(opencl_tree="device"):
            result = sd.compute(v, f, engine=OPENCL[0], **options)
        assert "build (device)" not in result.timings and "build" in result.timings


@pytest.mark.parametrize("leaf_size", [2, 4])
def test_leaves_of_several_triangles_give_the_same_bits(leaf_size):
    # The default leaf holds one triangle; the build option gathers small ranges into leaves.
    v, f = load_mesh(DATA / "teapot.obj")
    cpu = sd.compute(v, f, engine="cpu")
    with _testing.overrides(opencl_extra_options=f"-DSDF_LBVH_LEAF_SIZE={leaf_size}"):
        same_bits(on_device_tree(v, f, OPENCL[0]), cpu)


@pytest.mark.parametrize("orientation", ["auto", "as_is", "flip"])
def test_twins_found_beside_the_cast_give_the_cpu_engines_bits(orientation):
    # A double-sided mesh: the device stops casting when the host finds the twins beside it,
    # and the mesh without them is cast again.
    v, f = load_mesh(DATA / "spot.obj")
    f = np.vstack([f, f[:, [2, 1, 0]]])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # 'flip' turns spot inside out
        cpu = sd.compute(v, f, engine="cpu", orientation=orientation)
        device = on_device_tree(v, f, OPENCL[0], orientation=orientation)
    assert device.twin_faces == cpu.twin_faces == len(f) // 2
    same_bits(device, cpu)


def test_twins_among_faces_to_reverse_are_found_beside_the_second_cast():
    # Every third face of spot reversed ('auto' puts them back: the first cast stops and the
    # mesh is cast again), and a double-sided box beside it: its twins are told in the
    # caller's winding, found beside the second cast.
    v, f = load_mesh(DATA / "spot.obj")
    g = f.copy()
    g[::3] = g[::3, ::-1]
    bv, bf = box(0.3, 0.2, 0.1, divisions=2)
    back = bf[:, [0, 2, 1]] + len(bv)
    v = np.vstack([v, bv + [2.0, 0.0, 0.0], bv + [2.0, 0.0, 0.0]])
    g = np.vstack([g, bf + len(v) - 2 * len(bv), back + len(v) - 2 * len(bv)])
    cpu = sd.compute(v, g, engine="cpu")
    device = on_device_tree(v, g, OPENCL[0])
    assert device.twin_faces == cpu.twin_faces == len(bf)
    assert device.flipped_faces == cpu.flipped_faces > 0
    same_bits(device, cpu)
    np.testing.assert_array_equal(device.raw[-len(bf) :], device.raw[-2 * len(bf) : -len(bf)])
