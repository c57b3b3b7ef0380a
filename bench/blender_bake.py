# SPDX-License-Identifier: GPL-3.0-or-later
"""A UV bake's cost on each side of Blender, in real Blender (bpy from PyPI), the extension's
bake against the RGBA float image it replaces, in one run:

    scripts/build_extension.sh
    .venv-bpy45/bin/python bench/blender_bake.py [dist/shape_diameter-...zip]
        [--sizes 1024 2048 4096] [--rounds 3]

Spot (tests/data/spot.obj) baked without blur at each size. Prints a table: size; the core's
drawing (worker thread); the one-channel OpenEXR's encoding (worker thread) at 16 and 32 bits;
Blender's main thread handing the bytes over (Image.pack(data=...)); the packed file's size;
and the image it replaces: an RGBA float image filled with Image.pixels.foreach_set and
packed with Image.pack() (main thread throughout), its seconds and packed size. Best of
`rounds`; the ratios are the main thread's seconds and the packed bytes, old over new.
"""

import argparse
import os
import sys
import time

from blender_addon import ADDON, ROOT, install, newest_zip  # before bpy: it gives bpy a user folder

# isort: split
import bpy
import numpy as np


def arguments():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("zip", nargs="?", default=newest_zip())
    parser.add_argument("--sizes", type=int, nargs="+", default=[1024, 2048, 4096])
    parser.add_argument("--rounds", type=int, default=3)
    return parser.parse_args()


def best(rounds, work):
    """(best seconds, last result) of `rounds` calls."""
    seconds, out = float("inf"), None
    for _ in range(rounds):
        start = time.perf_counter()
        out = work()
        seconds = min(seconds, time.perf_counter() - start)
    return seconds, out


def old_image(values):
    """The replaced bake: RGBA float32, the value in R, G and B, packed by Blender."""
    height, width = values.shape
    rgba = np.empty((height, width, 4), dtype=np.float32)
    rgba[..., :3] = values[..., None]
    rgba[..., 3] = 1.0
    image = bpy.data.images.new("old", width, height, alpha=True, float_buffer=True)
    image.pixels.foreach_set(rgba.reshape(-1))
    image.pack()
    size = image.packed_file.size
    bpy.data.images.remove(image)
    return size


def row(size, rounds, ob, modules):
    """One size's line of the table."""
    process, baking = modules["process"], modules["baking"]
    exr, core = sys.modules[f"{ADDON}.exr"], sys.modules[f"{ADDON}.core"]
    options = process.Options(rays=8, bake_image=True, texture_size=size)
    (task,), _ = process.prepare(bpy.context.evaluated_depsgraph_get(), [ob], options)
    mesh = task.mesh
    values = np.linspace(0.0, 1.0, len(mesh.triangles), dtype=np.float32)
    draw, tiles = best(rounds, lambda: core.bake(
        mesh.vertices, mesh.triangles, values, "faces", task.corner_uvs, size, 0.0, 4))  # fmt: skip
    image = tiles[1001]
    half, data = best(rounds, lambda: exr.encode(image, True))
    full, _ = best(rounds, lambda: exr.encode(image, False))
    task.image, task.image_size, task.image_name = {1001: data}, size, "bench"

    def hand_over():
        for made, _ in baking.make_images(bpy.data, task, options):
            bpy.data.images.remove(made)

    main_thread, _ = best(rounds, hand_over)
    old, old_bytes = best(rounds, lambda: old_image(image))
    return (f"{size:>6}{draw:>9.3f}{half:>9.3f}{full:>9.3f}{main_thread:>9.4f}"
            f"{len(data) / 2**20:>8.2f}MB{old:>12.3f}{old_bytes / 2**20:>10.1f}MB"
            f"{old / main_thread:>8.0f}{old_bytes / len(data):>9.0f}")  # fmt: skip


def main():
    args = arguments()
    modules = install(args.zip, ("process", "baking"))
    bpy.ops.wm.obj_import(filepath=os.path.join(ROOT, "tests", "data", "spot.obj"))
    ob = bpy.context.selected_objects[0]
    print(f"{'size':>6}{'draw s':>9}{'exr16 s':>9}{'exr32 s':>9}{'main s':>9}{'packed':>10}"
          f"{'old main s':>12}{'old packed':>12}{'main x':>8}{'bytes x':>9}")  # fmt: skip
    for size in args.sizes:
        print(row(size, args.rounds, ob, modules))
    print(f"(bpy {bpy.app.version_string}, Spot, {len(ob.data.polygons)} faces, values "
          "a ramp over the faces, no blur, margin 4)")  # fmt: skip


if __name__ == "__main__":
    main()
