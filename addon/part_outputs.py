# SPDX-License-Identifier: GPL-3.0-or-later
"""The bpy writers of a segmentation's outputs, each with numpy foreach_set (never a Python
loop over polygons or vertices): face sets, the segment attribute, the colour attribute,
vertex groups (one call per group and weight level), material slots. Each writer appends to
`undo` the functions that take its change back, so that a run writes everything or nothing.

What this add-on wrote is recorded on the object (OBJECT_RECORD: groups, armature, modifier,
materials) and, for attributes, on the mesh (mesh_data.OUTPUTS_PROPERTY): an existing output
of the same name is replaced only where the record says it is ours.

Called on the main thread only.
"""

import json

import bpy
import numpy as np

from . import mesh_data, process

FACE_SETS = ".sculpt_face_set"  # Sculpt Mode's face sets: INT per face, ids from 1
OBJECT_RECORD = "shape_diameter_parts"
MATERIAL_MARK = "shape_diameter_part"  # custom property of the materials this add-on made
# Soft weights are written one vg.add() call per distinct weight: rounded to this many levels
# (a weight is off by at most 1 / (2 * WEIGHT_LEVELS)), so a group takes at most
# WEIGHT_LEVELS + 1 calls however many vertices it has.
WEIGHT_LEVELS = 1024


def part_names(prefix, count):
    """The names of `count` segments' groups and bones: prefix + number from 1, two digits
    (three from 100 segments on), so that they sort in segment order."""
    width = max(2, len(str(count)))
    return [f"{prefix}{i + 1:0{width}d}" for i in range(count)]


def object_record(ob):
    """{groups: [...], armature: name, modifier: name, materials: [...]} written earlier."""
    try:
        record = json.loads(ob.get(OBJECT_RECORD, "{}"))
        return record if isinstance(record, dict) else {}
    except (TypeError, ValueError):
        return {}


def set_object_record(ob, record, undo):
    before = ob.get(OBJECT_RECORD)

    def take_back():
        if before is None:
            ob.pop(OBJECT_RECORD, None)
        else:
            ob[OBJECT_RECORD] = before

    undo.append(take_back)
    ob[OBJECT_RECORD] = json.dumps(record, sort_keys=True)


def write_attributes(me, data, undo):
    """data: [(name, data_type, domain, array)], written with process.put_attribute and added
    to the mesh's record."""
    undo.append(process._record_restorer(me))
    for name, data_type, domain, array in data:
        process.put_attribute(me, name, data_type, domain, array, undo)
    mesh_data.record_outputs(me, [(name, t, d) for name, t, d, _ in data])


def face_set_data(polygon_labels):
    """Sculpt Mode's face set ids: the segment + 1 (0 is no face set)."""
    return (FACE_SETS, "INT", "FACE", np.asarray(polygon_labels, dtype=np.int32) + 1)


def color_data(name, polygon_colors, loop_totals):
    """The colour attribute per corner, each polygon's colour. FLOAT_COLOR, written in
    scene-linear: Blender stores its floats as they are (0.02 s for 4M corners), where a
    BYTE_COLOR attribute converts every value on the way in (0.6 s)."""
    linear = np.empty_like(polygon_colors)
    linear[:, :3] = srgb_to_linear(polygon_colors[:, :3])
    linear[:, 3] = polygon_colors[:, 3]
    return (name, "FLOAT_COLOR", "CORNER", mesh_data.polygon_loop_expand(linear, loop_totals))


def show_colors(me, name, undo):
    """Makes the colour attribute `name` the active one (what Solid shading's Attribute
    colour shows)."""
    colors = me.color_attributes
    before = colors.active_color_name

    def take_back():
        colors.active_color_name = before

    undo.append(take_back)
    colors.active_color = colors[name]


def _add_weights(group, vertices, weights):
    """vg.add() once per distinct weight (rounded to WEIGHT_LEVELS)."""
    levels = np.rint(np.asarray(weights, dtype=np.float64) * WEIGHT_LEVELS).astype(np.int64)
    order = np.argsort(levels, kind="stable")
    levels, vertices = levels[order], np.asarray(vertices)[order]
    starts = np.flatnonzero(np.r_[True, levels[1:] != levels[:-1]])
    ends = np.r_[starts[1:], len(levels)]
    for start, end in zip(starts, ends):
        if levels[start] > 0:
            group.add(vertices[start:end].tolist(), levels[start] / WEIGHT_LEVELS, "REPLACE")


def new_groups(ob, names, vertex_labels, weights, undo):
    """Vertex groups holding each segment's vertices, under temporary names (the final names
    may still be taken by the previous run's groups); returns them in segment order.
    weights: the core's sparse soft weights (VertexWeights) or None for hard weights from
    vertex_labels (1 on each vertex of the segment, none elsewhere)."""
    groups = []

    def take_back():
        for group in groups:
            ob.vertex_groups.remove(group)

    undo.append(take_back)
    if weights is None:
        labels = np.asarray(vertex_labels)
        order = np.argsort(labels, kind="stable")
        bounds = np.searchsorted(labels[order], np.arange(len(names) + 1))
    else:
        row = np.repeat(np.arange(len(weights.offsets) - 1), np.diff(weights.offsets))
        order = np.argsort(weights.segments, kind="stable")
        bounds = np.searchsorted(weights.segments[order], np.arange(len(names) + 1))
    for index, name in enumerate(names):
        group = ob.vertex_groups.new(name=name + ".sdf-new")
        groups.append(group)
        chosen = order[bounds[index] : bounds[index + 1]]
        if weights is None:
            group.add(chosen.tolist(), 1.0, "REPLACE")
        else:
            _add_weights(group, row[chosen], weights.weights[chosen])
    return groups


def replace_groups(ob, groups, names, old_names):
    """Once everything is written: removes the previous run's groups and gives the new ones
    their names. Cannot fail half-way (names were checked free)."""
    for name in old_names:
        old = ob.vertex_groups.get(name)
        if old is not None:
            ob.vertex_groups.remove(old)
    for group, name in zip(groups, names):
        group.name = name


def set_materials(ob, names, colors, undo):
    """One material slot per segment, material_index per polygon set by the caller: the
    mesh's slots are replaced by materials of these names (made, or ours reused with the new
    colour). Returns the materials."""
    me = ob.data
    before_slots = list(me.materials)
    made = []

    def take_back():
        me.materials.clear()
        for material in before_slots:
            me.materials.append(material)
        for material in made:
            bpy.data.materials.remove(material)

    undo.append(take_back)
    materials = []
    for name, color in zip(names, colors):
        material = bpy.data.materials.get((name, None))
        if material is None:
            material = bpy.data.materials.new(name)
            material[MATERIAL_MARK] = True
            made.append(material)
        else:
            before = tuple(material.diffuse_color)
            undo.append(lambda m=material, c=before: setattr(m, "diffuse_color", c))
        material.diffuse_color = (*srgb_to_linear(color[:3]).tolist(), 1.0)
        materials.append(material)
    me.materials.clear()
    for material in materials:
        me.materials.append(material)
    return materials


def write_material_indices(me, polygon_labels, undo):
    """The polygons' material_index, through its attribute (polygons' material_index is read
    and written element by element: 0.6 s for a million)."""
    process.put_attribute(me, "material_index", "INT", "FACE", polygon_labels, undo)


def srgb_to_linear(srgb):
    """sRGB in [0, 1] to scene-linear (float colours and materials are linear)."""
    c = np.asarray(srgb, dtype=np.float32)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4).astype(np.float32)
