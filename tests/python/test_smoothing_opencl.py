# SPDX-License-Identifier: GPL-3.0-or-later
"""The OpenCL versions of projected-points and texture-space smoothing: the same
kernel code as the CPU versions (kernels/sdf_smooth_*.h), so they agree within 1e-4 relative
on real meshes; a constant field stays constant; compute() smooths on the engine that cast;
bad engine names fail clearly. On PoCL here; on a GPU machine, the GPU (listed first)."""

from pathlib import Path

import numpy as np
import pytest
import shape_diameter as sd
from opencl_devices import OPENCL
from shape_diameter.mesh_io import load_mesh, load_mesh_with_uvs

DATA = Path(__file__).resolve().parents[1] / "data"
DEVICE = OPENCL[0]


def assert_agree(opencl, cpu, what):
    """At least 99.9% of points within 1e-4 relative (the rest: float rounding that tips a
    comparison, e.g. a node just inside or outside a sphere), and none wildly off."""
    opencl, cpu = np.asarray(opencl), np.asarray(cpu)
    assert opencl.shape == cpu.shape and opencl.dtype == cpu.dtype
    assert np.isfinite(opencl).all(), what
    rel = np.abs(opencl - cpu) / np.maximum(np.abs(cpu), 1e-30)
    bad = rel > 1e-4
    worst = [(int(i), float(opencl[i]), float(cpu[i])) for i in np.argsort(-rel)[:5] if bad[i]]
    assert bad.mean() <= 1e-3, f"{what}: {int(bad.sum())} of {len(cpu)} points differ: {worst}"
    assert rel.max() < 0.05, f"{what}: {worst}"


@pytest.fixture(scope="module")
def spot():
    v, t, uvs = load_mesh_with_uvs(DATA / "spot.obj")
    faces = sd.compute(v, t, engine="cpu").raw
    vertices = sd.compute(v, t, engine="cpu", points="vertices").raw
    return v, t, uvs, faces, vertices


@pytest.fixture(scope="module", params=["bunny00.off", "armadillo.off", "fandisk.obj", "horse.ply"])
def mesh_sdf(request):
    v, t = load_mesh(DATA / request.param)
    return request.param, v, t, sd.compute(v, t, engine="cpu").raw


@pytest.mark.parametrize("points", ["faces", "vertices"])
def test_projected_octree_built_on_the_device_is_the_cpus_to_the_bit(spot, points):
    """The device builds the octree level by level with atomics, the host from a Morton sort;
    both follow one set of rules (fixed-point sums, breadth-first nodes), so the trees are the
    same node for node and, with the same gather code, the values are the CPU's exactly: on
    spot with each option, and on points that all coincide, at tiny and huge scales."""
    v, t, _, faces, vertices = spot
    values = faces if points == "faces" else vertices
    for options in [
        {},
        {"iterations": 3},
        {"branch_on": "min"},
        {"max_depth": 12},
        {"max_depth": 4, "min_points": 0.0},
        {"node_size_ratio": 4.0},
        {"radius": 0.1, "node_size_ratio": 16.0, "min_points": 2e-5, "max_depth": 14},
    ]:
        cpu = sd.smooth(v, t, values, "projected", points=points, engine="cpu", **options)
        opencl = sd.smooth(v, t, values, "projected", points=points, engine=DEVICE, **options)
        np.testing.assert_array_equal(opencl, cpu, err_msg=str(options))
    rng = np.random.default_rng(5)
    for scale in (1e-12, 1.0, 1e12):
        for spread in (0.0, 1.0):  # 0: every centroid at one place
            m = 5000
            corner = rng.random((m, 1, 3)) * spread
            tri = corner + np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]]) * rng.random((m, 1, 1))
            mv, mt = (tri.reshape(-1, 3) * scale), np.arange(3 * m).reshape(m, 3)
            field = ((rng.random(m) + 0.01) * scale).astype(np.float32)
            cpu = sd.smooth(mv, mt, field, "projected", engine="cpu")
            opencl = sd.smooth(mv, mt, field, "projected", engine=DEVICE)
            np.testing.assert_array_equal(opencl, cpu, err_msg=f"scale {scale} spread {spread}")
    # -0 among the values: a node's minimum is 0 (its bits are the largest of all floats).
    field[::2] = -0.0
    for options in [{"branch_on": "min"}, {"branch_on": "min", "node_size_ratio": 0.0}]:
        cpu = sd.smooth(mv, mt, field, "projected", engine="cpu", **options)
        opencl = sd.smooth(mv, mt, field, "projected", engine=DEVICE, **options)
        np.testing.assert_array_equal(opencl, cpu, err_msg=f"-0 {options}")


@pytest.mark.parametrize("points", ["faces", "vertices"])
def test_compute_smooths_projected_from_the_cast_points_oriented(points):
    """On a device, compute() uploads the cast's own points while it casts (oriented: the
    horse is inside out, and every other face of a second copy is reversed) and smooths from
    them: the CPU engine's values exactly."""
    v, t = load_mesh(DATA / "horse.ply")
    messy = t[:, [0, 2, 1]].copy()
    messy[::2] = t[::2]
    for tris in (t, messy):
        cpu = sd.compute(v, tris, rays=10, points=points, engine="cpu", smoothing="projected")
        device = sd.compute(v, tris, rays=10, points=points, engine=DEVICE, smoothing="projected")
        assert device.flipped_faces > 0 and "beside cast: upload" in device.timings
        np.testing.assert_array_equal(device.raw, cpu.raw)
        np.testing.assert_array_equal(device.values, cpu.values)


@pytest.mark.parametrize(
    "options", [{}, {"iterations": 3}, {"branch_on": "min"}, {"max_depth": 4, "min_points": 0.0}]
)
@pytest.mark.parametrize("points", ["faces", "vertices"])
def test_projected_on_spot_agrees_with_cpu(spot, points, options):
    v, t, _, faces, vertices = spot
    values = faces if points == "faces" else vertices
    cpu = sd.smooth(v, t, values, "projected", engine="cpu", **options)
    opencl = sd.smooth(v, t, values, "projected", engine=DEVICE, **options)
    assert_agree(opencl, cpu, f"projected {points} {options}")
    assert opencl.min() >= values.min() and opencl.max() <= values.max()


def test_projected_on_real_meshes_agrees_with_cpu(mesh_sdf):
    name, v, t, raw = mesh_sdf
    cpu = sd.smooth(v, t, raw, "projected", engine="cpu")
    opencl = sd.smooth(v, t, raw, "projected", engine=DEVICE)
    assert_agree(opencl, cpu, f"projected on {name}")
    assert not np.array_equal(opencl, raw)  # it did smooth


@pytest.mark.parametrize(
    "options",
    [
        {},
        {"bilateral": True},
        {"texture_size": (300, 200)},
        {"radius": 30, "margin": 0},
        {"radius": 0.5, "margin": 5},
    ],
)
@pytest.mark.parametrize("points", ["faces", "vertices"])
def test_texture_on_spot_agrees_with_cpu(spot, points, options):
    v, t, uvs, faces, vertices = spot
    values = faces if points == "faces" else vertices
    options = {"texture_size": 512, **options}
    cpu = sd.smooth(v, t, values, "texture", uvs=uvs, engine="cpu", return_image=True, **options)
    opencl = sd.smooth(
        v, t, values, "texture", uvs=uvs, engine=DEVICE, return_image=True, **options
    )
    assert_agree(opencl.values, cpu.values, f"texture {points} {options}")
    np.testing.assert_array_equal(opencl.mask, cpu.mask)
    assert_agree(opencl.image[cpu.mask], cpu.image[cpu.mask], f"texture image {options}")
    assert (opencl.image[~cpu.mask] == 0).all()


def test_texture_default_size_agrees_with_cpu(spot):
    v, t, uvs, faces, _ = spot
    cpu = sd.smooth(v, t, faces, "texture", uvs=uvs, engine="cpu")
    assert_agree(sd.smooth(v, t, faces, "texture", uvs=uvs, engine=DEVICE), cpu, "texture 1024")


@pytest.mark.parametrize("points", ["faces", "vertices"])
@pytest.mark.filterwarnings("ignore:.*outside every UDIM tile:RuntimeWarning")
def test_texture_drawing_on_the_device_is_the_cpus_to_the_bit(points):
    """Overlapping, mirrored, sliver and out-of-image UV triangles: which face a texel takes
    (device: two passes of 32-bit maxima; CPU: one of 64-bit) and what it reads back are the
    CPU's exactly (the same kernel code in double; no exp without bilateral weights)."""
    rng = np.random.default_rng(7)
    m = 4000
    v = rng.random((3 * m, 3))
    t = np.arange(3 * m).reshape(m, 3)
    uvs = rng.random((m, 3, 2)) * 1.4 - 0.2
    uvs[::50, 2] = uvs[::50, 0]  # zero-area UV triangles
    values = rng.random(m if points == "faces" else 3 * m).astype(np.float32)
    for size in (37, (200, 64)):
        options = {"texture_size": size, "weld_tolerance": None, "return_image": True}
        # Each triangle its own island, most overlapping others: drawn as laid out (the overlap
        # search gives up on a soup), one image for each of tiles 1001, 1002, 1011 and 1012.
        with pytest.warns(RuntimeWarning, match=r"the UVs overlap everywhere"):
            cpu = sd.smooth(v, t, values, "texture", uvs=uvs, engine="cpu", **options)
        with pytest.warns(RuntimeWarning, match=r"the UVs overlap everywhere"):
            opencl = sd.smooth(v, t, values, "texture", uvs=uvs, engine=DEVICE, **options)
        np.testing.assert_array_equal(opencl.mask, cpu.mask)
        np.testing.assert_array_equal(opencl.image, cpu.image)
        np.testing.assert_array_equal(opencl.values, cpu.values)
        assert list(cpu.tiles) == [1001, 1002, 1011, 1012] == list(opencl.tiles)
        for number, (image, mask) in cpu.tiles.items():
            np.testing.assert_array_equal(opencl.tiles[number][0], image)
            np.testing.assert_array_equal(opencl.tiles[number][1], mask)


@pytest.mark.parametrize("method", ["projected", "texture"])
@pytest.mark.parametrize("points", ["faces", "vertices"])
def test_constant_field_stays_exactly_constant(spot, method, points):
    v, t, uvs, _, _ = spot
    n = len(t) if points == "faces" else len(v)
    values = np.full(n, 0.37, dtype=np.float32)
    out = sd.smooth(v, t, values, method, uvs=uvs, points=points, engine=DEVICE,
                    texture_size=256) if method == "texture" else \
        sd.smooth(v, t, values, method, points=points, engine=DEVICE)  # fmt: skip
    assert out.dtype == np.float32 and (out == np.float32(0.37)).all()


@pytest.mark.parametrize("method", ["projected", "texture"])
def test_compute_smooths_on_the_engine_that_cast(spot, method):
    v, t, uvs, _, _ = spot
    options = {"texture_size": 256} if method == "texture" else {}
    result = sd.compute(v, t, engine=DEVICE, smoothing=method, uvs=uvs, smoothing_options=options)
    assert "opencl" in result.engine and "fell back" not in result.engine
    alone = sd.smooth(v, t, result.raw, method, uvs=uvs, engine=DEVICE, **options)
    np.testing.assert_array_equal(result.values, alone)
    cpu = sd.compute(v, t, engine="cpu", smoothing=method, uvs=uvs, smoothing_options=options)
    np.testing.assert_array_equal(
        cpu.values, sd.smooth(v, t, cpu.raw, method, uvs=uvs, engine="cpu", **options)
    )


@pytest.mark.parametrize("engine", ["cpu", DEVICE])
def test_work_beside_the_cast_runs_once_and_its_error_ends_the_computation(spot, engine):
    """compute() finds texture smoothing's UV islands while a device casts (_testing.compute's
    beside_cast hook): it runs once; an exception raised there stops the devices and
    propagates, and the next computation runs normally."""
    from shape_diameter import _testing

    v, t, _, _, _ = spot
    calls = []

    def args(hook):
        return (v.astype(np.float64), t.astype(np.int64), 30, 120.0, "fibonacci", 0, "faces",
                0, None, engine, "bvh", 10, 8, "auto", "auto", hook)  # fmt: skip

    out = _testing.compute(*args(lambda points: calls.append(points)))
    assert len(calls) == 1 and "beside cast" in out["timings"]
    # The cast's points are lent for the call only: kept past it, they refer to nothing.
    if engine != "cpu":
        with pytest.raises(ValueError, match="only during"):
            _testing.prepare_projected(calls[0], 0, engine)

    def fail(points):
        raise KeyError("beside the cast")

    with pytest.raises(KeyError, match="beside the cast"):
        _testing.compute(*args(fail))
    again = _testing.compute(*args(None))
    np.testing.assert_array_equal(again["raw"], out["raw"])


def test_work_beside_the_cast_runs_on_a_mesh_with_nothing_to_cast():
    """Every face of zero area: no tree to cast against, and the hook still runs once."""
    from shape_diameter import _testing

    calls = []
    v = np.array([[0.0, 0, 0], [1, 0, 0], [2, 0, 0]])
    t = np.array([[0, 1, 2]])
    _testing.compute(v, t, 30, 120.0, "fibonacci", 0, "faces", 0, None, DEVICE, "bvh", 10, 8,
                  "auto", "auto", lambda points: calls.append(1))  # fmt: skip
    assert calls == [1]


def test_a_failure_finding_uv_islands_is_not_taken_for_a_device_failure(spot):
    """With engine='auto', an OpenCL failure casts again on the CPU; an error while finding the
    UV islands beside the cast is not one: it propagates as raised. (UVs that are not finite,
    which compute() refuses before any work, passed to the core directly.)"""
    from shape_diameter import _core
    from shape_diameter.smoothing import check_smoothing

    v, t, uvs, _, _ = spot
    corners = np.ascontiguousarray(uvs, dtype=np.float32).copy()
    corners[0, 0, 0] = np.nan
    cast = {
        "rays": 30, "cone_angle": 120.0, "sampling": "fibonacci", "seed": 0,
        "points": "faces", "threads": 0, "engine": DEVICE, "accel": "bvh",
        "octree_depth": 10, "octree_leaf_size": 8, "orientation": "auto",
        "bvh_quality": "auto",
    }  # fmt: skip
    options = check_smoothing("texture", {"texture_size": 64}, uvs=uvs, face_count=len(t),
                              vertex_count=len(v), triangles=t)  # fmt: skip
    del options["uvs"]  # the checked ones; the core gets the broken ones
    with pytest.raises(ValueError, match="finite"):
        _core.compute_field(v.astype(np.float64), t.astype(np.int64), cast, True, "texture",
                            options, corners, "linear", None)  # fmt: skip


def test_a_prepared_texture_gives_the_same_values_and_refuses_other_options(spot):
    # compute() prepares the mesh, UVs and islands while the device casts (and uploads the UVs
    # and islands on the device's side queue); smoothing them must give smooth()'s values.
    from shape_diameter import _testing

    v, t, uvs, faces, vertices = spot
    corner_uvs = np.ascontiguousarray(uvs, dtype=np.float32)
    v64, t64 = v.astype(np.float64), t.astype(np.int64)

    def prepare(need_merged, engine=DEVICE, size=64):
        return _testing.prepare_texture(v64, t64, corner_uvs, size, size, 1e-6, need_merged, 0,
                                     engine)  # fmt: skip

    def prepared(values, points, ready, engine=DEVICE):
        return _testing.smooth_texture_prepared(ready, values, points, 2.0, False, 0.1, 2, False,
                                             0, None, engine)["values"]  # fmt: skip

    def plain(values, points):
        return _testing.smooth_texture(v64, t64, values, points, corner_uvs, 64, 64, 2.0, False,
                                    0.1, 2, 1e-6, False, 0, None, DEVICE)["values"]  # fmt: skip

    for_faces, for_vertices = prepare(False), prepare(True)
    np.testing.assert_array_equal(prepared(faces, "faces", for_faces), plain(faces, "faces"))
    np.testing.assert_array_equal(prepared(vertices, "vertices", for_vertices),
                                  plain(vertices, "vertices"))  # fmt: skip
    # Prepared for the CPU (nothing uploaded) and smoothed on the device, or the other way.
    np.testing.assert_array_equal(prepared(faces, "faces", prepare(False, "cpu")),
                                  plain(faces, "faces"))  # fmt: skip
    np.testing.assert_array_equal(prepared(faces, "faces", for_faces, "cpu"),
                                  plain(faces, "faces"))  # fmt: skip
    with pytest.raises(ValueError, match="prepared for other options"):
        prepared(vertices, "vertices", for_faces)  # not merged for vertex values
    with pytest.raises(ValueError, match="one entry per point"):
        prepared(faces[:-1], "faces", for_faces)
    with pytest.raises(ValueError, match="not finite"):
        bad = corner_uvs.copy()
        bad[3, 1, 0] = np.nan
        _testing.prepare_texture(v64, t64, bad, 64, 64, 1e-6, False, 0, DEVICE)


def test_a_prepared_texture_keeps_its_uvs_alive(spot):
    # It holds the UVs by reference, not by copy: the array (here the float32 copy made of a
    # float64 one) must outlive the caller's, whatever reuses the freed memory.
    import gc

    from shape_diameter import _testing

    v, t, uvs, faces, _ = spot
    v64, t64 = v.astype(np.float64), t.astype(np.int64)
    corner_uvs = np.array(uvs, dtype=np.float64)
    expected = _testing.smooth_texture(
        v64,
        t64,
        faces,
        "faces",
        corner_uvs.astype(np.float32),
        64,
        64,
        2.0,
        False,
        0.1,
        2,
        1e-6,
        False,
        0,
        None,
        DEVICE,
    )
    ready = _testing.prepare_texture(v64, t64, corner_uvs, 64, 64, 1e-6, False, 0, DEVICE)
    del corner_uvs
    gc.collect()
    noise = [np.random.default_rng(k).random(uvs.size).astype(np.float32) for k in range(8)]
    for engine in (DEVICE, "cpu"):
        out = _testing.smooth_texture_prepared(ready, faces, "faces", 2.0, False, 0.1, 2, False, 0,
                                            None, engine)  # fmt: skip
        np.testing.assert_array_equal(out["values"], expected["values"])
    assert len(noise) == 8


@pytest.mark.filterwarnings("ignore:no ray of any point:RuntimeWarning")  # a flat square
def test_faces_spanning_many_texels_are_drawn_on_the_cpu():
    """A device walks each face in one work item: a face spanning more than 2^16 texels (two
    triangles over a 512 x 512 texture) leaves the method to the CPU threads, same values."""
    from shape_diameter import _testing

    v = np.array([[0.0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]])
    t = np.array([[0, 1, 2], [0, 2, 3]])
    uvs = np.ascontiguousarray(v[t][:, :, :2], dtype=np.float32)
    values = np.array([1.0, 2.0], dtype=np.float32)

    def stages(size):
        out = _testing.smooth_texture(v, t, values, "faces", uvs, size, size, 4.0, False, 0.1, 2,
                                   1e-6, False, 0, None, DEVICE)  # fmt: skip
        return set(out["timings"])

    assert "rasterise" in stages(512)
    has_double = next(e for e in sd.engines() if e["name"] == DEVICE)["double"]
    assert ("device: kernels" in stages(128)) == has_double
    # ... and says so, naming the caller's line.
    with pytest.warns(RuntimeWarning, match="ran on the CPU threads") as caught:
        out = sd.smooth(v, t, values, "texture", uvs=uvs, texture_size=512, engine=DEVICE)
    assert caught[0].filename == __file__
    np.testing.assert_array_equal(
        out, sd.smooth(v, t, values, "texture", uvs=uvs, texture_size=512, engine="cpu")
    )
    with pytest.warns(RuntimeWarning, match="ran on the CPU threads") as caught:
        sd.compute(
            v,
            t,
            rays=4,
            engine=DEVICE,
            smoothing="texture",
            uvs=uvs,
            smoothing_options={"texture_size": 512},
        )
    assert [w.filename for w in caught if "CPU threads" in str(w.message)] == [__file__]


def test_kring_runs_on_the_cpu_whatever_the_engine(spot):
    v, t, _, faces, _ = spot
    np.testing.assert_array_equal(
        sd.smooth(v, t, faces, "kring", engine=DEVICE),
        sd.smooth(v, t, faces, "kring", engine="cpu"),
    )


@pytest.mark.parametrize("method", ["projected", "texture"])
def test_a_device_that_does_not_exist_is_a_clear_error(spot, method):
    v, t, uvs, faces, _ = spot
    with pytest.raises(ValueError, match="no-such-device-xyz"):
        sd.smooth(v, t, faces, method, uvs=uvs, engine="opencl:no-such-device-xyz")
    with pytest.raises(ValueError, match="no OpenCL device 99; devices here: opencl:0"):
        sd.smooth(v, t, faces, method, uvs=uvs, engine="opencl:99")
    with pytest.raises(ValueError, match="unknown engine 'gpu'; available here: auto, cpu"):
        sd.smooth(v, t, faces, method, uvs=uvs, engine="gpu")


@pytest.mark.parametrize("method", ["projected", "texture"])
def test_opencl_all_smooths_on_its_first_device(spot, method):
    v, t, uvs, faces, _ = spot
    options = {"uvs": uvs, "texture_size": 256} if method == "texture" else {}
    np.testing.assert_array_equal(
        sd.smooth(v, t, faces, method, engine="opencl:all", **options),
        sd.smooth(v, t, faces, method, engine=DEVICE, **options),
    )


@pytest.mark.parametrize("method", ["projected", "texture"])
def test_a_cancel_raising_runtime_error_is_not_taken_for_a_device_failure(
    spot, method, monkeypatch
):
    """engine='auto' runs the work again on the CPU after an OpenCL failure only: a progress
    callback's own exception, a RuntimeError included, propagates from compute() and
    smooth() (they once took it for a device failure and ran on)."""
    import shape_diameter.api as api
    import shape_diameter.smoothing as smoothing

    v, t, uvs, faces, _ = spot
    monkeypatch.setattr(api, "_resolve_engine", lambda engine: DEVICE)
    monkeypatch.setattr(smoothing, "_resolve_engine", lambda engine: DEVICE)

    def cancel(fraction):
        if fraction >= 0.95:
            raise RuntimeError("cancelled by the user")

    options = {"texture_size": 256} if method == "texture" else {}
    with pytest.raises(RuntimeError, match="cancelled by the user"):
        sd.compute(v, t, smoothing=method, uvs=uvs, smoothing_options=options, progress=cancel)
    with pytest.raises(RuntimeError, match="cancelled by the user"):
        sd.smooth(v, t, faces, method, uvs=uvs, progress=lambda f: cancel(1.0), **options)


@pytest.mark.parametrize("points", ["faces", "vertices"])
def test_texture_values_near_the_float_limit_blur_alike(spot, points):
    """Values near the float limit overflow the blur's float sums (inf - inf): such texels take
    the input's minimum on the host as on a device, and no texel is NaN (the vertex read-back
    takes NaN for "no sample")."""
    v, t, uvs, _, _ = spot
    n = len(t) if points == "faces" else len(v)
    values = np.where(np.arange(n) % 2 == 0, -3.4e38, 3.4e38).astype(np.float32)
    options = {"texture_size": 64, "radius": 4, "return_image": True}
    cpu = sd.smooth(v, t, values, "texture", uvs=uvs, points=points, engine="cpu", **options)
    opencl = sd.smooth(v, t, values, "texture", uvs=uvs, points=points, engine=DEVICE, **options)
    assert not np.isnan(cpu.image).any()
    np.testing.assert_array_equal(opencl.image, cpu.image)
    np.testing.assert_array_equal(opencl.values, cpu.values)
