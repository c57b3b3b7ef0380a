# SPDX-License-Identifier: GPL-3.0-or-later
"""What the Blender tests share: scenes, mesh snapshots, and reference values computed with
the Python package directly (written independently of the add-on's own code)."""

import importlib
from pathlib import Path

import bmesh
import bpy
import numpy as np

ROOT = Path(__file__).resolve().parents[2]
DATA = ROOT / "tests" / "data"
ADDON = "bl_ext.user_default.shape_diameter"


def addon_module(name=""):
    return importlib.import_module(ADDON + ("." + name if name else ""))


def select_only(*objects):
    for ob in bpy.context.view_layer.objects:
        ob.select_set(False)
    for ob in objects:
        ob.select_set(True)
    bpy.context.view_layer.objects.active = objects[0] if objects else None


def import_obj(name):
    before = set(bpy.data.objects)
    bpy.ops.wm.obj_import(filepath=str(DATA / name))
    (ob,) = set(bpy.data.objects) - before
    select_only(ob)
    return ob


def suzanne_with_ngons():
    """Suzanne from tests/data/suzanne.obj (468 quads, 32 triangles, 3 parts), with a few
    pairs of neighbouring quads merged into hexagons, so the mesh has triangles, quads and
    n-gons. The same edges are dissolved every time (every 37th interior edge between two
    quads)."""
    ob = import_obj("suzanne.obj")
    bm = bmesh.new()
    bm.from_mesh(ob.data)
    bm.edges.ensure_lookup_table()
    edges = [
        e
        for e in bm.edges
        if len(e.link_faces) == 2 and all(len(f.verts) == 4 for f in e.link_faces)
    ]
    bmesh.ops.dissolve_edges(bm, edges=edges[::37], use_verts=False, use_face_split=False)
    bm.to_mesh(ob.data)
    bm.free()
    ob.data.update()
    return ob


def run(**options):
    """Runs the operator as a script does (EXEC_DEFAULT, with an undo step)."""
    return bpy.ops.object.shape_diameter("EXEC_DEFAULT", True, **options)


def loop_totals(me):
    out = np.empty(len(me.polygons), dtype=np.int32)
    me.polygons.foreach_get("loop_total", out)
    return out


def attribute_array(me, name):
    a = me.attributes[name]
    if a.data_type == "FLOAT":
        out = np.empty(len(a.data), dtype=np.float32)
        a.data.foreach_get("value", out)
    else:
        out = np.empty(len(a.data) * 4, dtype=np.float32)
        a.data.foreach_get("color_srgb" if a.data_type == "BYTE_COLOR" else "color", out)
        out = out.reshape(-1, 4)
    return out


def world_triangles(ob, apply_scale=True):
    """(vertices float64 (n,3), triangles int (m,3), polygon of each triangle) from Blender's
    loop triangles, with the 3x3 part of the object's matrix applied."""
    me = ob.data
    co = np.empty(len(me.vertices) * 3, dtype=np.float32)
    me.vertices.foreach_get("co", co)
    v = co.reshape(-1, 3).astype(np.float64)
    me.calc_loop_triangles()
    t = np.empty(len(me.loop_triangles) * 3, dtype=np.int32)
    me.loop_triangles.foreach_get("vertices", t)
    t = t.reshape(-1, 3)
    p = np.empty(len(me.loop_triangles), dtype=np.int32)
    me.loop_triangles.foreach_get("polygon_index", p)
    if apply_scale:
        m = np.array(ob.matrix_world.to_3x3(), dtype=np.float64)
        v = v @ m.T
        if np.linalg.det(m) < 0:
            t = t[:, ::-1]
    return v, t, p


def reference_face_values(ob, apply_scale=True, **options):
    """What the operator should write for points='faces': shape_diameter.compute on Blender's
    triangles, then each polygon's area-weighted mean of its triangles."""
    import shape_diameter

    v, t, p = world_triangles(ob, apply_scale)
    # Warnings about the mesh (a tapered Suzanne's open eyes) are the operator's to report;
    # the reference only gives the values.
    with shape_diameter.collect_warnings():
        tri = shape_diameter.compute(v, t, **options).values.astype(np.float64)
    a, b, c = v[t[:, 0]], v[t[:, 1]], v[t[:, 2]]
    area = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)
    n = len(ob.data.polygons)
    num = np.zeros(n)
    den = np.zeros(n)
    np.add.at(num, p, area * tri)
    np.add.at(den, p, area)
    return (num / den).astype(np.float32)


def snapshot(me):
    """Everything a run could change in a mesh: every attribute's name, type, domain and data
    (bytes), the active and default color attributes, the active attribute."""
    state = {
        "counts": (len(me.vertices), len(me.edges), len(me.loops), len(me.polygons)),
        "active_color": me.color_attributes.active_color_name,
        "default_color": me.color_attributes.default_color_name,
        "active_attribute": me.attributes.active_index,
        "attributes": [],
    }
    fields = {
        "FLOAT": ("value", 1, np.float32),
        "INT": ("value", 1, np.int32),
        "INT8": ("value", 1, np.int8),
        "BOOLEAN": ("value", 1, bool),
        "FLOAT2": ("vector", 2, np.float32),
        "INT32_2D": ("value", 2, np.int32),
        "FLOAT_VECTOR": ("vector", 3, np.float32),
        "FLOAT_COLOR": ("color", 4, np.float32),
        "BYTE_COLOR": ("color_srgb", 4, np.float32),
        "QUATERNION": ("value", 4, np.float32),
    }
    for a in me.attributes:
        field, width, dtype = fields.get(a.data_type, (None, 0, None))
        data = b""
        if field:
            arr = np.empty(len(a.data) * width, dtype=dtype)
            a.data.foreach_get(field, arr)
            data = arr.tobytes()
        state["attributes"].append((a.name, a.data_type, a.domain, len(a.data), data))
    state["attributes"].sort()
    return state


def snapshot_all():
    return {me.name: snapshot(me) for me in bpy.data.meshes}
