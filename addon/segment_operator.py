# SPDX-License-Identifier: GPL-3.0-or-later
"""Segment by Thickness (object.shape_diameter_segment): the selected meshes split into parts
by their SDF, written as face sets, a part attribute, part colours, vertex groups, material
slots and a proto-skeleton. Thin over segmenting.py and part_writing.py, and run as Compute
is (operators.WorkerRun: worker thread, progress, Esc, undo, headless)."""

import time

import bpy

from . import operators, part_writing, props, segmenting

last_run = {}


def summary(parts, written, seconds):
    pieces = []
    for part, out in zip(parts, written):
        count = part.segmentation.segment_count
        source = "SDF reused" if part.reused else "SDF computed"
        rig = f", armature {out.armature}" if out.armature else ""
        pieces.append(
            f"{part.object_name}: {count} part{'s' if count != 1 else ''} ({source}{rig})"
        )
    return f"Segment: {'; '.join(pieces)}; {seconds:.2f} s"


@props.segment_operator_options
class OBJECT_OT_shape_diameter_segment(operators.WorkerRun, bpy.types.Operator):
    """Split the selected meshes into parts by thickness: face sets, vertex groups, part
    colours and a proto-skeleton to start rigging from"""

    bl_idname = "object.shape_diameter_segment"
    bl_label = "Segment by Thickness"
    bl_options = {"REGISTER", "UNDO"}
    title = "Segment"

    @staticmethod
    def work(tasks, options, progress=None, cancelled=None):
        return segmenting.compute(tasks, options, progress, cancelled)

    def _prepare(self, context):
        values = props.segment_option_values(self)
        values["engine"] = operators.resolve_engine(context, values["engine"])
        options = segmenting.SegmentOptions.from_keywords(**values)
        parts, warnings = segmenting.prepare(
            context.evaluated_depsgraph_get(),
            context.selected_objects,
            options,
            active=context.active_object,
        )
        for warning in warnings:
            self.report({"WARNING"}, warning)
        return options, parts

    def _finish(self, context, options, parts, started):
        written = part_writing.write(context, parts, options)
        for part in parts:
            for warning in part.warnings:
                self.report({"WARNING"}, warning)
        text = summary(parts, written, time.perf_counter() - started)
        last_run.clear()
        last_run.update(text=text, objects=[p.object_name for p in parts])
        self.report({"INFO"}, text)

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        layout.use_property_decorate = False
        draw_segment_settings(layout, self)


def draw_segment_settings(layout, settings):
    """The segmentation options and outputs (operator and panel)."""
    for name in ("segments", "clusters", "smoothness", "mode", "min_part_area", "reuse_values"):
        layout.prop(settings, name)
    col = layout.column(heading="Outputs")
    col.prop(settings, "face_sets")
    col.prop(settings, "label_name")
    col.prop(settings, "segment_color_name")
    col.prop(settings, "vertex_groups")
    sub = col.column()
    sub.active = settings.vertex_groups or settings.armature
    sub.prop(settings, "group_prefix")
    sub.prop(settings, "soft_weights")
    col.prop(settings, "materials")
    col.prop(settings, "armature")
    sub = col.column()
    sub.active = settings.armature
    sub.prop(settings, "armature_name")


classes = (OBJECT_OT_shape_diameter_segment,)


def register():
    for cls in classes:
        bpy.utils.register_class(cls)


def unregister():
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
