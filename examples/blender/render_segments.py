# SPDX-License-Identifier: GPL-3.0-or-later
"""Renders a mesh split into parts by the extension (Workbench, headless): each part in its
colour (the segment_color attribute) and the proto-skeleton drawn in front of it.

    blender -b --python-exit-code 1 --python render_segments.py -- MESH OUT.png [--size 640]
        [--clusters 5] [--up y|z] [--view-x 0.8 --view-y -1.6 --view-z 0.5]

MESH as for render_sdf.py (.obj, .ply, .stl, or .off read here). A render shows no armature
(bones are drawn by the viewport's overlays), so each bone is drawn as Blender's octahedral
bone shape, a mesh in dark grey, shown in front of the surface.
"""

import argparse
import importlib
import sys
from pathlib import Path

import bpy
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from render_sdf import EXTENSION, load, render  # noqa: E402

BONE_COLOR = (0.08, 0.08, 0.08, 1.0)


def arguments():
    argv = sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else []
    parser = argparse.ArgumentParser(prog="render_segments.py")
    parser.add_argument("mesh", type=Path)
    parser.add_argument("out", type=Path)
    parser.add_argument("--size", type=int, default=640, help="image width; height is 3/4")
    parser.add_argument("--clusters", type=int, default=5)
    parser.add_argument("--up", choices=("y", "z"), default=None)
    parser.add_argument("--view-x", type=float, default=0.8)
    parser.add_argument("--view-y", type=float, default=-1.6)
    parser.add_argument("--view-z", type=float, default=0.5)
    return parser.parse_args(argv)


def octahedron(head, tail, width):
    """Blender's octahedral bone between two points, `width` wide at its waist: 6 vertices,
    8 triangles."""
    axis = tail - head
    length = np.linalg.norm(axis)
    y = axis / length
    helper = np.array([0.0, 0.0, 1.0]) if abs(y[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    x = np.cross(y, helper)
    x /= np.linalg.norm(x)
    z = np.cross(x, y)
    waist = head + 0.1 * axis
    r = min(width, 0.1 * length)
    vertices = [head, waist + r * x, waist + r * z, waist - r * x, waist - r * z, tail]
    faces = [(0, 2, 1), (0, 3, 2), (0, 4, 3), (0, 1, 4), (5, 1, 2), (5, 2, 3), (5, 3, 4), (5, 4, 1)]
    return np.array(vertices), np.array(faces)


def bone_mesh(arm, width):
    """One mesh object holding every bone's octahedron, in world space, dark and in front."""
    matrix = np.array(arm.matrix_world)
    parts = []
    for bone in arm.data.bones:
        head = (matrix @ np.append(bone.head_local, 1.0))[:3]
        tail = (matrix @ np.append(bone.tail_local, 1.0))[:3]
        parts.append(octahedron(head, tail, width))
    offsets = np.cumsum([0] + [len(v) for v, _ in parts[:-1]])
    vertices = np.vstack([v for v, _ in parts])
    faces = np.vstack([f + o for (_, f), o in zip(parts, offsets)])
    me = bpy.data.meshes.new("bones")
    me.from_pydata(vertices.tolist(), [], faces.tolist())
    colors = me.color_attributes.new("bone_color", "FLOAT_COLOR", "POINT")
    colors.data.foreach_set("color", np.tile(BONE_COLOR, len(vertices)).astype(np.float32))
    me.color_attributes.active_color = colors
    ob = bpy.data.objects.new("bones", me)
    ob.show_in_front = True
    bpy.context.scene.collection.objects.link(ob)
    return ob


def main():
    args = arguments()
    bpy.ops.wm.read_homefile(use_empty=True)
    if EXTENSION not in bpy.context.preferences.addons:
        import addon_utils  # Blender's own module: importable once bpy is

        addon_utils.enable(EXTENSION, default_set=True, handle_error=None)
    api = importlib.import_module(EXTENSION + ".api")
    scene = bpy.context.scene
    ob = load(args.mesh, args.up)
    result = api.segment_object(ob, clusters=args.clusters, vertex_groups=True)
    print(f"{ob.name}: {result.segment_count} parts, armature {result.armature}")
    ob.data.polygons.foreach_set("use_smooth", np.ones(len(ob.data.polygons), dtype=bool))
    bpy.context.view_layer.update()
    size = max(ob.dimensions)
    bone_mesh(bpy.data.objects[result.armature], 0.015 * size)

    render(scene, ob, args)


if __name__ == "__main__":
    main()
