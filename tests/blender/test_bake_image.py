# SPDX-License-Identifier: GPL-3.0-or-later
"""The baked image as Blender holds it: a packed one-channel OpenEXR (half floats by default,
32-bit on request), one image per UDIM tile or one tiled image; write=False bakes nothing; a
bake's progress only moves forward; a cancelled bake leaves nothing behind."""

import struct
import time

import bpy
import numpy as np
import pytest
from helpers import addon_module, import_obj, select_only, snapshot_all
from modal_stand_in import defaults, event, stand_in

EXR_TYPES = {1: "half", 2: "float"}


def exr_channels(data):
    """{channel name: pixel type} from an OpenEXR file's header (its 'channels' attribute),
    read independently of the add-on's writer; also checks the magic number."""
    assert struct.unpack("<i", data[:4])[0] == 20000630
    at = data.index(b"channels\0chlist\0") + len(b"channels\0chlist\0")
    (size,) = struct.unpack("<i", data[at : at + 4])
    entries, channels = data[at + 4 : at + 4 + size], {}
    while entries[:1] != b"\0":
        name, entries = entries.split(b"\0", 1)
        channels[name.decode()] = EXR_TYPES[struct.unpack("<i", entries[:4])[0]]
        entries = entries[16:]  # type, linear flag and reserved bytes, x and y sampling
    return channels


def pixels(image):
    width, height = image.size
    out = np.empty(width * height * 4, dtype=np.float32)
    image.pixels.foreach_get(out)
    return out.reshape(height, width, 4)


def bake(ob, **options):
    api = addon_module("api")
    return api.compute_object(ob, rays=8, bake_image=True, texture_size=64, **options)


def test_a_bake_is_packed_as_one_channel_of_half_floats_by_default():
    ob = import_obj("spot.obj")
    result = bake(ob)
    image = bpy.data.images[result.image]
    data = image.packed_file.data
    assert exr_channels(data) == {"Y": "half"}
    assert image.file_format == "OPEN_EXR" and image.is_float and tuple(image.size) == (64, 64)
    # Spot at 64^2, one half-float channel: at most 8 KiB raw; compressed, less.
    assert len(data) < 64 * 64 * 2
    values = pixels(image)
    assert (values[..., 0] == values[..., 2]).all() and (values[..., 3] == 1).all()
    assert values[..., 0].min() >= 0.0 and values[..., 0].max() <= 1.0


def test_a_32_bit_bake_holds_the_values_exactly():
    ob = import_obj("spot.obj")
    half = pixels(bpy.data.images[bake(ob, image_name="half").image])[..., 0]
    full_image = bpy.data.images[bake(ob, image_name="full", bake_depth="32").image]
    assert exr_channels(full_image.packed_file.data) == {"Y": "float"}
    full = full_image.pixels[:][0::4]
    full = np.asarray(full, dtype=np.float32).reshape(64, 64)
    assert not np.array_equal(half, full)  # half floats round
    np.testing.assert_allclose(half, full.astype(np.float16).astype(np.float32), rtol=0, atol=0)


def test_udim_tiles_baked_into_one_tiled_image():
    ob = import_obj("spot.obj")
    uv = np.empty(len(ob.data.loops) * 2, dtype=np.float32)
    ob.data.uv_layers[0].data.foreach_get("uv", uv)
    ob.data.uv_layers[0].data.foreach_set("uv", uv + 1.0)  # tiles 1011, 1012, 1022
    result = bake(ob, bake_tiles="TILED", image_name="{object}")
    image = bpy.data.images["spot"]
    assert image.source == "TILED"
    tiles = sorted(t.number for t in image.tiles)
    assert tiles == sorted(result.tile_images) and 1001 in tiles and 1012 in tiles
    assert set(result.tile_images.values()) == {"spot"}
    packed = {p.tile_number: p.packed_file.data for p in image.packed_files}
    assert sorted(packed) == tiles
    assert all(exr_channels(data) == {"Y": "half"} for data in packed.values())
    assert not [im for im in bpy.data.images if im.name.startswith("spot.")]  # no image a tile


def test_write_false_never_bakes():
    ob = import_obj("spot.obj")
    before = {im.name for im in bpy.data.images}
    api = addon_module("api")
    with pytest.warns(RuntimeWarning, match="bake_image is skipped with write=False"):
        result = api.compute_object(ob, rays=8, bake_image=True, texture_size=64, write=False)
    assert {im.name for im in bpy.data.images} == before
    assert result.image == "" and result.tile_images == {}
    assert "bake" not in result.timings


def test_a_bakes_progress_only_moves_forward():
    ob = import_obj("spot.obj")
    seen = []
    bake(ob, progress=seen.append, smoothing="texture", texture_radius=2.0)
    assert seen[-1] == 1.0
    assert all(b >= a for a, b in zip(seen, seen[1:])), seen
    assert any(0.5 < f < 1.0 for f in seen)  # the bake's own steps, after the cast's


def test_a_bake_cancelled_while_baking_leaves_nothing():
    # Cancelled in the bake's part of the progress (after the cast's half): no image, no
    # packed file, no attribute.
    ob = import_obj("spot.obj")
    before, images = snapshot_all(), {im.name for im in bpy.data.images}
    api = addon_module("api")
    with pytest.raises(api.Cancelled):
        bake(ob, progress=lambda fraction: fraction <= 0.6)
    assert snapshot_all() == before and {im.name for im in bpy.data.images} == images
    assert not [im for im in bpy.data.images if im.packed_file is not None]


def test_escape_during_a_bake_stops_it_and_leaves_nothing(monkeypatch):
    # The operator's modal path (modal_stand_in.py): Esc once the job is in the bake (a large
    # texture, so the bake lasts) ends it, the worker stopped, nothing written.
    process = addon_module("process")
    operators = addon_module("operators")
    cls = operators.OBJECT_OT_shape_diameter
    methods = ("_options", "_prepare", "_finish", "_report_error", "_stop", "invoke", "modal")
    import_obj("spot.obj")
    before, images = snapshot_all(), {im.name for im in bpy.data.images}
    values = {"rays": 8, "bake_image": True, "texture_size": 4096}
    op, context, reports = stand_in(monkeypatch, cls, methods, defaults(process.Options), values)
    assert op.invoke(context, event("LEFTMOUSE")) == {"RUNNING_MODAL"}
    job = operators.running
    while job.progress <= process.CAST_SHARE_WHEN_BAKING and not job.done:
        time.sleep(0.005)
    assert not job.done  # in the bake
    pressed = time.perf_counter()
    assert op.modal(context, event("ESC", "PRESS")) == {"CANCELLED"}
    print(f"cancel took {time.perf_counter() - pressed:.3f} s")
    assert job.done and operators.running is None
    assert snapshot_all() == before and {im.name for im in bpy.data.images} == images
    assert reports == [({"WARNING"}, "Shape Diameter cancelled: nothing was changed")]


def test_overlapping_uvs_are_reported_before_the_run_and_found_once(monkeypatch):
    # Spot joined with a moved copy of itself: two shells on the same UVs. The layout is found
    # when the run is prepared (reported then, before any work) and handed to the cast's
    # texture smoothing and the bake, which do not search again.
    import shape_diameter.uv_plan

    ob = import_obj("spot.obj")
    copy = ob.copy()
    copy.data = ob.data.copy()
    copy.location.x += 3.0
    bpy.context.collection.objects.link(copy)
    select_only(ob, copy)
    bpy.ops.object.join()
    calls = []
    search = shape_diameter.uv_plan._core.uv_layout
    monkeypatch.setattr(
        shape_diameter.uv_plan._core, "uv_layout", lambda *a: calls.append(a) or search(*a)
    )
    with pytest.warns(RuntimeWarning, match="overlapping another UV island") as said:
        result = bake(ob, smoothing="texture", texture_radius=2.0)
    overlaps = [w for w in result.warnings if "overlapping another UV island" in w]
    assert len(overlaps) == 1 and overlaps[0].startswith("spot: ")
    assert len([w for w in said if "overlapping" in str(w.message)]) == 1
    assert len(calls) == 1


@pytest.mark.parametrize("half", [True, False], ids=["half", "float"])
@pytest.mark.parametrize("size", [17, 37])
def test_blender_reads_the_files_back_exactly(half, size):
    # The encoder against Blender's own OpenEXR reader: sizes that are no multiple of the
    # 16-line blocks, and noise that zlib cannot shrink (those blocks are stored raw). Rows
    # are given from v = 0, as Blender's pixels are.
    exr = addon_module("exr")
    values = np.random.default_rng(size).random((size, size), dtype=np.float32)
    values[0, :] = 0.0  # the bottom row, to see that rows keep their order
    data = exr.encode(values, half)
    image = bpy.data.images.new("read back", 1, 1, float_buffer=True)
    image.pack(data=data, data_len=len(data))
    image.source = "FILE"
    assert tuple(image.size) == (size, size)
    expected = values.astype(np.float16).astype(np.float32) if half else values
    np.testing.assert_array_equal(pixels(image)[..., 0], expected)
