# SPDX-License-Identifier: GPL-3.0-or-later
"""The UV bake: the normalised field drawn through a UV map into one-channel float images,
one per UDIM tile, packed into the .blend as OpenEXR files.

bake() runs on the worker thread (no bpy): the core draws and blurs the tiles, exr.encode
turns each into the bytes of a file (16-bit half floats by default, 32-bit on request),
checking for a cancel between blocks of lines. make_images() runs on the main thread and only
hands the bytes to Blender (Image.pack(data=...): no pixels pass through Python there), under
temporary names that write() swaps in once everything else is written.

What Blender allows: an Image is RGBA to Python (Image.channels is read-only, images.new
makes four), but it reads a one-channel ("Y") OpenEXR as a grey image, so the packed file
holds one channel and the image shows the value in R, G and B (alpha 1). A tiled (UDIM) image
cannot be packed from bytes ("Cannot pack tiled images from raw data"): its tiles are written
as files into a temporary folder, loaded as one tiled image, packed (the same bytes) and the
files deleted.
"""

import os
import shutil
import tempfile

from . import core, exr

TEMPORARY_SUFFIX = ".sdf-new"
# Shares of a bake's progress: the core's drawing and blur, then the files' encoding.
DRAWING_SHARE = 0.8


def tile_image_name(name, tile):
    """The baked image of UDIM tile `tile`, one image a tile: `name` itself for tile 1001
    (the [0, 1] square), NAME.TILE (spot_sdf.1002) for the others."""
    return name if tile == 1001 else f"{name}.{tile}"


def image_names(name, tiles, options):
    """tile number -> the image holding it: each its own (IMAGES), or all `name` (TILED)."""
    if options.bake_tiles == "TILED":
        return {tile: name for tile in tiles}
    return {tile: tile_image_name(name, tile) for tile in tiles}


def bake(task, options, values, step):
    """Fills task.image (tile -> OpenEXR bytes). `values` per polygon
    corner's triangle or vertex, as options.points says; `step(fraction)` reports progress
    (0 to 1) and raises to cancel."""
    mesh = task.mesh
    tiles = core.bake(
        mesh.vertices,
        mesh.triangles,
        values,
        options.points,
        task.corner_uvs,
        options.texture_size,
        options.bake_radius(),
        options.bake_margin,
        lambda fraction: step(DRAWING_SHARE * fraction),
        # The engine and threads the user chose for the cast (it ran on 'auto' whatever was
        # chosen).
        engine=options.engine,
        threads=int(options.extra.get("threads") or 0),
        uv_layout=task.uv_layout,
    )
    half = options.bake_depth == "16"
    encoded = {}
    for k, (tile, image) in enumerate(tiles.items()):
        share = (1.0 - DRAWING_SHARE) / len(tiles)
        encoded[tile] = exr.encode(image, half, lambda at=DRAWING_SHARE + k * share: step(at))
    task.image = encoded
    step(1.0)


def make_images(bpy_data, task, options):
    """The task's images under temporary names: [(image, the name it takes once everything
    is written)]. Removes what it made if it fails."""
    if not task.image:
        return []
    if options.bake_tiles == "TILED":
        return [(_tiled_image(bpy_data, task), task.image_name)]
    made = []
    try:
        for tile, data in task.image.items():
            name = tile_image_name(task.image_name, tile)
            made.append((_packed_image(bpy_data, name + TEMPORARY_SUFFIX, data, task), name))
    except BaseException:
        for image, _ in made:
            bpy_data.images.remove(image)
        raise
    return made


def _settle(image):
    """What every baked image is: kept by a fake user (Blender drops an image with no user
    when the file is saved, so the bake would be gone after a reload) and tagged Non-Color
    (it holds values, not colours)."""
    image.use_fake_user = True
    image.colorspace_settings.name = "Non-Color"


def _packed_image(bpy_data, name, data, task):
    # A 1 x 1 placeholder: the packed file is the image (its size, its pixels, read by
    # Blender when first used); a size x size one would allocate 16 bytes a texel for nothing
    # (64 MiB at 2048^2).
    image = bpy_data.images.new(name, 1, 1, float_buffer=True)
    try:
        image.pack(data=data, data_len=len(data))
        image.source = "FILE"
        image.filepath_raw = f"//{name.removesuffix(TEMPORARY_SUFFIX)}.exr"
        _settle(image)
    except BaseException:
        bpy_data.images.remove(image)
        raise
    return image


def _tiled_image(bpy_data, task):
    folder = tempfile.mkdtemp(prefix="shape-diameter-bake-")
    image = None
    try:
        for tile, data in task.image.items():
            with open(os.path.join(folder, f"bake.{tile}.exr"), "wb") as file:
                file.write(data)
        image = bpy_data.images.load(os.path.join(folder, "bake.<UDIM>.exr"), check_existing=False)
        image.name = task.image_name + TEMPORARY_SUFFIX
        image.source = "TILED"
        if sorted(t.number for t in image.tiles) != sorted(task.image):
            raise RuntimeError("Blender did not find every baked UDIM tile")
        image.pack()
        image.filepath_raw = f"//{task.image_name}.<UDIM>.exr"
        _settle(image)
    except BaseException:
        if image is not None:
            bpy_data.images.remove(image)
        raise
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    return image
