# SPDX-License-Identifier: GPL-3.0-or-later
"""Renders a mesh coloured by its Shape Diameter (Workbench, headless), with the extension:

    blender -b --python-exit-code 1 --python render_sdf.py -- MESH OUT.png [--size 640]
        [--rays 30] [--up y|z] [--view-x 0.8 --view-y -1.6 --view-z 0.5]

MESH: .obj, .ply, .stl (Blender's importers) or .off (read here). The colours are the
extension's sdf_color attribute (perceptual colour map, thin = dark purple, thick = yellow),
shown by Workbench's "Attribute" colour with the Standard view transform, so they are the
colour map's own sRGB colours.
"""

import argparse
import importlib
import math
import sys
from pathlib import Path

import bpy
import numpy as np
from mathutils import Vector

EXTENSION = "bl_ext.user_default.shape_diameter"


def arguments():
    argv = sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else []
    parser = argparse.ArgumentParser(prog="render_sdf.py")
    parser.add_argument("mesh", type=Path)
    parser.add_argument("out", type=Path)
    parser.add_argument("--size", type=int, default=640, help="image width; height is 3/4")
    parser.add_argument("--rays", type=int, default=30)
    parser.add_argument(
        "--up",
        choices=("y", "z"),
        default=None,
        help="the file's up axis (default: y for .off, else the importer's)",
    )
    parser.add_argument("--view-x", type=float, default=0.8)
    parser.add_argument("--view-y", type=float, default=-1.6)
    parser.add_argument("--view-z", type=float, default=0.5)
    return parser.parse_args(argv)


def read_off(path):
    """An OFF file as a mesh object, built with foreach_set (no per-element loops)."""
    words = path.read_text().split("\n", 1)
    if not words[0].strip().startswith("OFF"):
        raise ValueError(f"{path} is not an OFF file")
    body = np.array(words[1].split(), dtype=np.float64)
    n_vertices, n_faces = int(body[0]), int(body[1])
    vertices = body[3 : 3 + 3 * n_vertices]
    faces = body[3 + 3 * n_vertices :].astype(np.int64)
    if not np.all(faces.reshape(-1, 4)[:, 0] == 3) or len(faces) != 4 * n_faces:
        raise ValueError(f"{path}: only triangle OFF files are read here")
    corners = faces.reshape(-1, 4)[:, 1:].reshape(-1)
    me = bpy.data.meshes.new(path.stem)
    me.vertices.add(n_vertices)
    me.vertices.foreach_set("co", vertices.astype(np.float32))
    me.loops.add(len(corners))
    me.loops.foreach_set("vertex_index", corners.astype(np.int32))
    me.polygons.add(n_faces)
    me.polygons.foreach_set("loop_start", np.arange(0, len(corners), 3, dtype=np.int32))
    me.polygons.foreach_set("loop_total", np.full(n_faces, 3, dtype=np.int32))
    me.update(calc_edges=True)
    me.validate()
    ob = bpy.data.objects.new(path.stem, me)
    bpy.context.scene.collection.objects.link(ob)
    return ob


def load(path, up):
    suffix = path.suffix.lower()
    if suffix == ".off":
        ob = read_off(path)
        up = up or "y"
    else:
        before = set(bpy.data.objects)
        {
            ".obj": bpy.ops.wm.obj_import,
            ".ply": bpy.ops.wm.ply_import,
            ".stl": bpy.ops.wm.stl_import,
        }[suffix](filepath=str(path))
        (ob,) = [o for o in bpy.data.objects if o not in before]
    if up == "y":
        ob.rotation_euler = (math.pi / 2, 0.0, 0.0)
    bpy.context.view_layer.update()
    return ob


def frame(scene, ob, direction, aspect):
    """A camera looking at the object from `direction`, as near as lets every vertex into the
    frame, with a small margin: a compact mesh fills it, a tall figure keeps its head."""
    points = np.empty(3 * len(ob.data.vertices))
    ob.data.vertices.foreach_get("co", points)
    matrix = np.array(ob.matrix_world)
    points = points.reshape(-1, 3) @ matrix[:3, :3].T + matrix[:3, 3]
    centre = (points.min(axis=0) + points.max(axis=0)) / 2.0
    camera = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
    scene.collection.objects.link(camera)
    camera.data.lens = 50.0
    direction = Vector(direction).normalized()
    rotation = (-direction).to_track_quat("-Z", "Y")
    right, up = rotation @ Vector((1.0, 0.0, 0.0)), rotation @ Vector((0.0, 1.0, 0.0))
    # The lens's angle spans the wider side of the image (sensor fit 'AUTO').
    tan_wide = math.tan(camera.data.angle / 2.0)
    tan_x, tan_y = (tan_wide, tan_wide / aspect) if aspect >= 1 else (tan_wide * aspect, tan_wide)
    # A point r (from the centre) is in the frame when its sideways offsets over its depth,
    # distance - r.direction, stay within the half-angles' tangents.
    offsets = points - centre
    distance = np.max(
        offsets @ np.array(direction)
        + np.maximum(
            np.abs(offsets @ np.array(right)) / tan_x, np.abs(offsets @ np.array(up)) / tan_y
        )
    )
    camera.location = Vector(centre) + direction * float(distance) * 1.04
    camera.rotation_euler = rotation.to_euler()
    scene.camera = camera


def render(scene, ob, args):
    """Workbench, studio light and cavity, the objects' active colour attributes on white,
    framed from (args.view_x, view_y, view_z), written as an RGB PNG to args.out."""
    scene.render.engine = "BLENDER_WORKBENCH"
    shading = scene.display.shading
    shading.light = "STUDIO"
    shading.color_type = "VERTEX"  # labelled "Attribute": each object's active color attribute
    shading.show_cavity = True
    shading.cavity_type = "WORLD"
    scene.view_settings.view_transform = "Standard"
    scene.render.resolution_x = args.size
    scene.render.resolution_y = args.size * 3 // 4
    scene.render.resolution_percentage = 100
    scene.render.film_transparent = False
    scene.render.image_settings.file_format = "PNG"
    scene.render.image_settings.color_mode = "RGB"
    scene.render.image_settings.compression = 100
    world = bpy.data.worlds.new("world")
    world.color = (1.0, 1.0, 1.0)
    scene.world = world
    frame(scene, ob, (args.view_x, args.view_y, args.view_z), 4 / 3)
    scene.render.filepath = str(args.out.resolve())
    args.out.parent.mkdir(parents=True, exist_ok=True)
    bpy.ops.render.render(write_still=True)
    print(f"wrote {args.out}")


def main():
    args = arguments()
    bpy.ops.wm.read_homefile(use_empty=True)
    if EXTENSION not in bpy.context.preferences.addons:
        import addon_utils  # Blender's own module: importable once bpy is

        addon_utils.enable(EXTENSION, default_set=True, handle_error=None)
    api = importlib.import_module(EXTENSION + ".api")

    scene = bpy.context.scene
    ob = load(args.mesh, args.up)
    result = api.compute_object(ob, rays=args.rays)
    print(f"{ob.name}: {len(result.values)} values, {result.engine}")
    ob.data.polygons.foreach_set("use_smooth", np.ones(len(ob.data.polygons), dtype=bool))

    render(scene, ob, args)


if __name__ == "__main__":
    main()
