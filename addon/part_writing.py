# SPDX-License-Identifier: GPL-3.0-or-later
"""Writes a segmentation run's outputs on every object, all or none: attributes through
process.put_attribute's restorers, new vertex groups and the armature under temporary names;
only once everything is written do the previous run's groups and armature go and the new
ones take their names (steps that cannot fail half-way). Main thread only."""

from dataclasses import dataclass, field

import bpy
import numpy as np

from . import armature, core, mesh_data, part_outputs, process
from .segmenting import names_problem

UserError = process.UserError
TEMPORARY = ".sdf-new"  # suffix of the new groups and armature until the old ones are gone


@dataclass
class Written:
    """What one object got."""

    attributes: list = field(default_factory=list)
    vertex_groups: list = field(default_factory=list)
    materials: list = field(default_factory=list)
    armature: str = ""


def _target(bpy_data, part, options):
    task = part.task
    ob = process._find_object(bpy_data, task.object_uid)
    if ob is None or ob.type != "MESH":
        raise UserError(f"{task.object_name} was deleted while computing; nothing was written")
    if ob.data.session_uid != task.mesh_uid or not mesh_data.topology(ob.data).matches(
        task.topology
    ):
        raise UserError(f"{ob.name}'s mesh changed while computing; nothing was written")
    problem = (
        process._mode_problem(ob)
        or process._editable_problem(ob)
        or names_problem(ob, options, part.segmentation.segment_count)
    )
    if problem:
        raise UserError(problem + "; nothing was written")
    return ob


def write(context, parts, options):
    """Writes every task's outputs; returns a Written per task, in order."""
    targets = [(_target(bpy.data, part, options), part) for part in parts]
    undo, finishing = [], []
    try:
        written = [_write_one(context, ob, part, options, undo, finishing) for ob, part in targets]
    except BaseException:
        for take_back in reversed(undo):
            take_back()
        context.view_layer.update()  # (see below)
        raise
    for finish in finishing:
        finish()
    for ob, _ in targets:
        ob.data.update()
    # Objects removed (the previous armature) leave the view layer's list stale until it
    # is synced: iterating it gave None.
    context.view_layer.update()
    return written


def _attributes(ob, part, options, undo):
    me = ob.data
    labels = part.polygon_labels
    data = []
    if options.face_sets:
        data.append(part_outputs.face_set_data(labels))
    if options.label_name:
        data.append((options.label_name, "INT", "FACE", labels))
    if options.segment_color_name:
        loop_totals = part.task.topology.loop_totals
        data.append(
            part_outputs.color_data(options.segment_color_name, part.polygon_colors, loop_totals)
        )
    if data:
        undo.append(process._colors_restorer(me))
        part_outputs.write_attributes(me, data, undo)
    if options.segment_color_name:
        part_outputs.show_colors(me, options.segment_color_name, undo)
    return [name for name, _, _, _ in data]


def _write_one(context, ob, part, options, undo, finishing):
    seg = part.segmentation
    names = part_outputs.part_names(options.group_prefix, seg.segment_count)
    record = part_outputs.object_record(ob)
    new_record = dict(record)
    out = Written(attributes=_attributes(ob, part, options, undo))
    if options.writes_groups:
        weights = seg.vertex_weights if options.soft_weights else None
        groups = part_outputs.new_groups(ob, names, seg.vertex_labels, weights, undo)
        old = [name for name in record.get("groups", []) if ob.vertex_groups.get(name)]
        finishing.append(lambda: part_outputs.replace_groups(ob, groups, names, old))
        new_record["groups"] = out.vertex_groups = names
    if options.materials:
        part_outputs.set_materials(ob, names, _segment_colors(len(names)), undo)
        part_outputs.write_material_indices(ob.data, part.polygon_labels, undo)
        new_record["materials"] = out.materials = names
    if options.armature:
        name = options.armature_name.replace("{object}", ob.name)
        arm = armature.build(context, ob, names, part.skeleton, name + TEMPORARY, undo)
        modifier = armature.attach(ob, arm, record.get("modifier"), undo)
        finishing.append(lambda: _replace_armature(arm, name))
        new_record.update(armature=name, modifier=modifier.name)
        out.armature = name
    part_outputs.set_object_record(ob, new_record, undo)
    return out


def _segment_colors(count):
    """One sRGB colour per segment, the colour its polygons get."""
    return core.segment_colors(np.arange(count))


def _replace_armature(arm, name):
    old = bpy.data.objects.get((name, None))
    if old is not None and old != arm and old.get(armature.MARK):
        armature.remove(old)
    arm.name = name
    arm.data.name = name
