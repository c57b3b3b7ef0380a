# SPDX-License-Identifier: GPL-3.0-or-later
"""Smoothing methods and the UV bake, on Spot (tests/data/spot.obj: triangles with UVs, UV
seams), against shape_diameter.compute and shape_diameter.smooth on the same triangles."""

import bpy
import numpy as np
import pytest
import shape_diameter
from helpers import (
    addon_module,
    attribute_array,
    import_obj,
    run,
    snapshot_all,
    world_triangles,
)


def corner_uvs(ob, name=None):
    """(m, 3, 2): the UV map at each loop triangle's corners, read independently here."""
    me = ob.data
    layer = me.uv_layers[name] if name else me.uv_layers.active
    uv = np.empty(len(me.loops) * 2, dtype=np.float32)
    layer.data.foreach_get("uv", uv)
    me.calc_loop_triangles()
    loops = np.empty(len(me.loop_triangles) * 3, dtype=np.int32)
    me.loop_triangles.foreach_get("loops", loops)
    return uv.reshape(-1, 2)[loops].reshape(-1, 3, 2)


SMOOTHING = {
    "kring": ({"smoothing_rings": 2}, {"k": 2}),
    "projected": ({"smoothing_iterations": 2}, {"iterations": 2}),
    "projected, the paper's rule": (
        {"smoothing_iterations": 1, "smoothing_rule": "paper"},
        {"iterations": 1, "rule": "paper"},
    ),
    "texture": (
        {"texture_size": 256, "texture_radius": 3.0},
        {"texture_size": 256, "radius": 3.0},
    ),
}


@pytest.mark.parametrize("method", SMOOTHING)
def test_smoothing_methods(method):
    ob = import_obj("spot.obj")
    operator_options, smooth_options = SMOOTHING[method]
    method = method.split(",")[0]
    assert run(rays=16) == {"FINISHED"}
    plain = attribute_array(ob.data, "sdf")
    assert run(rays=16, smoothing=method, **operator_options) == {"FINISHED"}
    smoothed = attribute_array(ob.data, "sdf")

    v, t, p = world_triangles(ob)
    assert (p == np.arange(len(p))).all()  # Spot is all triangles: polygon i = triangle i
    raw = shape_diameter.compute(v, t, rays=16).values
    expected = shape_diameter.smooth(
        v, t, raw, method, uvs=corner_uvs(ob), points="faces", **smooth_options
    )
    np.testing.assert_allclose(smoothed, expected, rtol=1e-5, atol=1e-7)
    assert not np.allclose(smoothed, plain)
    assert smoothed.min() >= plain.min() - 1e-6 and smoothed.max() <= plain.max() + 1e-6
    assert np.std(smoothed) < np.std(plain)


def test_smoothing_on_vertices():
    ob = import_obj("spot.obj")
    assert run(rays=16, points="vertices", smoothing="kring", smoothing_rings=1) == {"FINISHED"}
    v, t, _ = world_triangles(ob)
    raw = shape_diameter.compute(v, t, rays=16, points="vertices").values
    expected = shape_diameter.smooth(v, t, raw, "kring", points="vertices", k=1)
    np.testing.assert_allclose(attribute_array(ob.data, "sdf"), expected, rtol=1e-5, atol=1e-7)


def image_pixels(image):
    width, height = image.size
    out = np.empty(width * height * 4, dtype=np.float32)
    image.pixels.foreach_get(out)
    return out.reshape(height, width, 4)


@pytest.mark.parametrize("smoothing", ["none", "texture"])
def test_uv_bake(smoothing):
    ob = import_obj("spot.obj")
    options = {"texture_radius": 2.0} if smoothing == "texture" else {}
    assert run(rays=16, bake_image=True, texture_size=128, smoothing=smoothing, **options) == {
        "FINISHED"
    }
    image = bpy.data.images["spot_sdf"]
    assert tuple(image.size) == (128, 128)
    assert image.is_float and image.packed_file is not None
    # The same bake from the package: the normalised attribute, through the same UV corners.
    normalized = attribute_array(ob.data, "sdf_normalized")
    v, t, _ = world_triangles(ob)
    expected = shape_diameter.smooth(
        v,
        t,
        normalized,
        "texture",
        uvs=corner_uvs(ob),
        points="faces",
        texture_size=128,
        radius=2.0 if smoothing == "texture" else 0.0,
        margin=4,
        return_image=True,
    )
    # One channel packed (test_bake_image.py checks the file): Blender shows it grey, opaque; the
    # texels no face covers are 0.
    pixels = image_pixels(image)
    covered = expected.mask
    assert 0.3 < covered.mean() < 0.95  # Spot's islands, and empty space between them
    assert (pixels[..., 0] == pixels[..., 1]).all() and (pixels[..., 1] == pixels[..., 2]).all()
    assert (pixels[..., 3] == 1).all()
    grey = pixels[covered][:, 0]
    assert grey.min() >= 0.0 and grey.max() <= 1.0 and np.std(grey) > 0.05  # not blank
    assert (pixels[~covered][:, 0] == 0).all()
    # Half floats: 11 significant bits, a relative error of at most 2^-11 (rounding).
    np.testing.assert_allclose(pixels[..., 0], expected.image, rtol=2.0**-11, atol=1e-7)


def test_bake_replaces_the_image_and_keeps_its_users():
    ob = import_obj("spot.obj")
    old = bpy.data.images.new("spot_sdf", 32, 32)
    material = bpy.data.materials.new("spot")
    material.use_nodes = True
    node = material.node_tree.nodes.new("ShaderNodeTexImage")
    node.image = old
    ob.data.materials.append(material)
    assert run(rays=8, bake_image=True, texture_size=64) == {"FINISHED"}
    assert [im.name for im in bpy.data.images if im.name.startswith("spot_sdf")] == ["spot_sdf"]
    assert node.image == bpy.data.images["spot_sdf"]
    assert tuple(node.image.size) == (64, 64) and node.image.is_float


def test_a_baked_image_survives_saving_the_file(tmp_path):
    # The new image had no user, and a save and reload dropped it.
    import_obj("spot.obj")
    assert run(rays=8, bake_image=True, texture_size=32) == {"FINISHED"}
    image = bpy.data.images["spot_sdf"]
    assert image.use_fake_user and image.colorspace_settings.name == "Non-Color"
    expected = image_pixels(image)
    path = str(tmp_path / "baked.blend")
    bpy.ops.wm.save_as_mainfile(filepath=path)
    bpy.ops.wm.open_mainfile(filepath=path)
    np.testing.assert_array_equal(image_pixels(bpy.data.images["spot_sdf"]), expected)


def test_bake_through_a_chosen_uv_map_and_the_api():
    api = addon_module("api")
    ob = import_obj("spot.obj")
    second = ob.data.uv_layers.new(name="Flat")
    uv = np.empty(len(ob.data.loops) * 2, dtype=np.float32)
    ob.data.uv_layers[0].data.foreach_get("uv", uv)
    second.data.foreach_set("uv", uv * 0.5)  # everything in the lower left quarter
    result = api.compute_object(
        ob, rays=8, bake_image=True, uv_map="Flat", texture_size=64, image_name="flat {object}"
    )
    assert result.image == "flat spot"
    # The bake's own time is in the object's timings, and within its total.
    assert 0 < result.timings["bake"] < result.timings["total"]
    assert result.timings["total"] > result.timings["cast"] + result.timings["bake"]
    pixels = image_pixels(bpy.data.images["flat spot"])
    covered = pixels[..., 0] > 0  # (the thinnest faces' 0 aside)
    assert covered[:28, :28].any() and not covered[36:, :].any() and not covered[:, 36:].any()


@pytest.mark.parametrize("engine", ["cpu", "opencl"])
def test_the_bake_runs_on_the_chosen_engine_and_threads(monkeypatch, engine):
    # The bake's rasterising and blur ran on engine 'auto' and every core whatever the user
    # chose for the run.
    api = addon_module("api")
    ob = import_obj("spot.obj")
    seen = []
    smooth = shape_diameter.smooth

    def recording_smooth(*args, **kwargs):
        seen.append((kwargs.get("engine"), kwargs.get("threads")))
        return smooth(*args, **kwargs)

    monkeypatch.setattr(shape_diameter, "smooth", recording_smooth)
    api.compute_object(ob, rays=8, bake_image=True, texture_size=32, engine=engine, threads=1)
    assert seen == [(engine, 1)]


def test_a_bake_of_udim_tiles_makes_an_image_per_tile_named_by_its_number():
    # UVs moved one tile up and right (UDIM tiles 1011, 1012 and 1022 by their centroids): an
    # image per tile, NAME.TILE, beside NAME for tile 1001 (empty here), without a warning;
    # "{object}" alone names the image after the object (it was refused as empty).
    import bpy

    api = addon_module("api")
    ob = import_obj("spot.obj")
    uv = np.empty(len(ob.data.loops) * 2, dtype=np.float32)
    ob.data.uv_layers[0].data.foreach_get("uv", uv)
    ob.data.uv_layers[0].data.foreach_set("uv", uv + 1.0)
    result = api.compute_object(ob, rays=8, bake_image=True, texture_size=32, image_name="{object}")
    assert result.image == "spot"
    assert not [w for w in result.warnings if "UV" in w]
    assert 1001 in result.tile_images and 1012 in result.tile_images
    assert result.tile_images[1012] == "spot.1012"

    def value(name):
        image = bpy.data.images[name]
        assert tuple(image.size) == (32, 32) and image.packed_file is not None
        pixels = np.empty(32 * 32 * 4, dtype=np.float32)
        image.pixels.foreach_get(pixels)
        return pixels[0::4]

    assert (value("spot") == 0).all()  # no face in tile 1001
    assert (value("spot.1012") > 0).sum() > 100  # most of spot
    assert set(result.tile_images.values()) <= {im.name for im in bpy.data.images}


def test_a_bake_of_uvs_outside_every_tile_warns():
    # UVs at negative u and v lie in no tile: the bake leaves those faces out, which the run's
    # warnings say (it went to stderr only), before the work.
    api = addon_module("api")
    ob = import_obj("spot.obj")
    uv = np.empty(len(ob.data.loops) * 2, dtype=np.float32)
    ob.data.uv_layers[0].data.foreach_get("uv", uv)
    ob.data.uv_layers[0].data.foreach_set("uv", uv - 2.0)
    # Found before the run (the UV layout), said then as a warning of the whole run, once.
    with pytest.warns(RuntimeWarning, match="outside every UDIM tile"):
        result = api.compute_object(ob, rays=8, bake_image=True, texture_size=32)
    (bake,) = [w for w in result.warnings if "outside every UDIM tile" in w]
    assert bake.startswith("spot: ") and "the images leave them out" in bake


BAD_TEXTURE_OPTIONS = [
    ({"texture_size": 8}, r"texture_size must be an integer in \[16, 16384\], got 8"),
    ({"texture_size": 0}, r"texture_size must be an integer in \[16, 16384\], got 0"),
    ({"texture_size": 16385}, r"texture_size must be an integer in \[16, 16384\], got 16385"),
    ({"texture_size": 1024.0}, r"texture_size must be an integer in \[16, 16384\], got 1024.0"),
    ({"texture_size": "1024"}, r"texture_size must be an integer in \[16, 16384\], got '1024'"),
    ({"texture_size": True}, r"texture_size must be an integer in \[16, 16384\], got True"),
    ({"texture_radius": -1.0}, r"texture_radius must be a number in \[0, 1024\].*got -1.0"),
    ({"texture_radius": float("nan")}, r"texture_radius must be a number in \[0, 1024\]"),
    # bake_margin failed after the cast (-1, 100000), or passed as 2.5 and '4'.
    ({"bake_margin": -1}, r"bake_margin must be an integer in \[0, 16384\] texels, got -1"),
    ({"bake_margin": 16385}, r"bake_margin must be an integer in \[0, 16384\].*got 16385"),
    ({"bake_margin": 2.5}, r"bake_margin must be an integer in \[0, 16384\].*got 2.5"),
    ({"bake_margin": "4"}, r"bake_margin must be an integer in \[0, 16384\].*got '4'"),
]


@pytest.mark.parametrize(
    "what",
    [{"bake_image": True}, {"smoothing": "texture"}, {"bake_image": True, "write": False}],
    ids=["bake", "texture-smoothing", "dry-run"],
)
@pytest.mark.parametrize(
    "bad, message",
    BAD_TEXTURE_OPTIONS,
    ids=[repr(next(iter(b.values()))) for b, _ in BAD_TEXTURE_OPTIONS],
)
def test_the_api_refuses_texture_options_out_of_range_before_any_work(
    monkeypatch, what, bad, message
):
    # The operator's Resolution is 16..16384 and its Radius 0..1024; the API took anything:
    # texture_size=8 baked an 8 x 8 image, 0 or 16385 failed in the bake after the whole cast.
    api, core = addon_module("api"), addon_module("core")
    ob = import_obj("spot.obj")
    cast = []
    monkeypatch.setattr(core, "compute", lambda *args, **kwargs: cast.append(args))
    before = snapshot_all()
    images = sorted(bpy.data.images.keys())
    with pytest.raises(ValueError, match=message):
        api.compute_object(ob, rays=8, **what, **bad)
    assert not cast  # refused before any work
    assert snapshot_all() == before and sorted(bpy.data.images.keys()) == images


def stop_before_casting(monkeypatch):
    """The core's compute() replaced by one that stops the run: what came before it was
    up front."""
    core = addon_module("core")

    def stop(*args, **kwargs):
        raise RuntimeError("the cast was reached")

    monkeypatch.setattr(core, "compute", stop)


def test_long_texture_work_is_announced_before_it_starts(monkeypatch):
    # A 2048^2 bake with texture smoothing at a radius of 1024 texels (two blurs over the whole
    # image) ran for half a minute (32.6 s on 2 cores) without a word.
    api = addon_module("api")
    ob = import_obj("spot.obj")
    stop_before_casting(monkeypatch)
    options = {
        "smoothing": "texture",
        "texture_size": 2048,
        "texture_radius": 1024.0,
        "bake_image": True,
        "threads": 1,
    }  # one thread: the same estimate anywhere
    with pytest.warns(RuntimeWarning) as seen, pytest.raises(RuntimeError, match="cast was"):
        api.compute_object(ob, **options)
    (warning,) = [str(w.message) for w in seen]
    assert warning.startswith(
        "Long or large texture work ahead: texture smoothing and the "
        "bake of 1 object at 2048 x 2048 texels with a blur radius of "
        "1024 texels (default 16): about "
    )
    # Two blurs reading 2 x 2048 texels around each of Spot's about 2.1M island texels, at
    # 4 ns a read on one thread: about 70 s (32.6 s measured on 2 threads).
    seconds = float(warning.split("about ")[1].split(" s on 1 CPU thread ")[0])
    assert 55 < seconds < 90, warning
    # The default radius, and a smaller texture: nothing to say (warnings are errors here).
    with pytest.raises(RuntimeError, match="cast was"):
        api.compute_object(ob, **{**options, "texture_radius": 0.0, "texture_size": 1024})


def test_texture_work_that_cannot_fit_in_memory_is_refused(monkeypatch):
    api, process = addon_module("api"), addon_module("process")
    good = import_obj("spot.obj")
    assert run(rays=4) == {"FINISHED"}
    monkeypatch.setattr(process, "physical_memory", lambda: 1 << 30)  # a 1 GiB machine
    stop_before_casting(monkeypatch)
    before = snapshot_all()
    images = sorted(bpy.data.images.keys())
    # A 8192^2 bake in half floats: 8 bytes a texel while encoded, 2 held after (and the
    # core's texture buffers, smaller): 1.1 GiB estimated.
    message = (
        r"Too large: the bake of 1 object at 8192 x 8192 texels would need about 1.1 GiB "
        r"of memory, more than 80% of this machine's 1.0 GiB; lower the resolution$"
    )
    with pytest.raises(api.UserError, match=message):
        api.compute_object(good, bake_image=True, texture_size=8192)
    with pytest.raises(RuntimeError, match=message):  # the operator reports it
        run(bake_image=True, texture_size=8192)
    assert snapshot_all() == before and sorted(bpy.data.images.keys()) == images
    # Large, not too large: a warning (a quarter of the memory and more), then the work.
    with (
        pytest.warns(RuntimeWarning, match=r"and 288 MiB of memory"),
        pytest.raises(RuntimeError, match="cast was"),
    ):
        api.compute_object(good, bake_image=True, texture_size=4096)
