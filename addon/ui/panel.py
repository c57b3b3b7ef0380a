# SPDX-License-Identifier: GPL-3.0-or-later
"""The 3D view sidebar panel (tab "SDF") and its sub-panels, drawn from the scene's
settings (props.ShapeDiameterSettings); the button runs object.shape_diameter with them."""

import bpy

from .. import core, operators, props, segment_operator
from .preferences import draw_status


class ShapeDiameterPanel:
    """What every panel here shares (Cycles' CyclesButtonsPanel pattern)."""

    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "SDF"


class ShapeDiameterSubPanel(ShapeDiameterPanel):
    bl_parent_id = "VIEW3D_PT_shape_diameter"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        layout.use_property_decorate = False
        self.draw_settings(layout, context.scene.shape_diameter, context)


class VIEW3D_PT_shape_diameter(ShapeDiameterPanel, bpy.types.Panel):
    bl_label = "Shape Diameter"

    def draw(self, context):
        layout = self.layout
        settings = context.scene.shape_diameter
        meshes = [ob for ob in context.selected_objects if ob.type == "MESH"]
        job = operators.running
        if job is not None:
            layout.progress(
                factor=job.progress, text=f"Computing… {100 * job.progress:.0f}%  (Esc cancels)"
            )
        row = layout.row()
        row.scale_y = 1.5
        op = row.operator(
            operators.OBJECT_OT_shape_diameter.bl_idname,
            text=f"Compute ({len(meshes)} mesh{'es' if len(meshes) != 1 else ''})",
            icon="MOD_THICKNESS",
        )
        props.copy_options(settings, op)
        if not meshes:
            layout.label(text="Select one or more meshes", icon="INFO")
        loaded, _text = core.status()
        if not loaded:
            draw_status(layout)


class VIEW3D_PT_shape_diameter_rays(ShapeDiameterSubPanel, bpy.types.Panel):
    bl_label = "Rays"
    bl_options = set()

    def draw_settings(self, layout, settings, context):
        layout.prop(settings, "rays")
        layout.prop(settings, "cone_angle")
        layout.prop(settings, "sampling")
        if settings.sampling == "random":
            layout.prop(settings, "seed")


class VIEW3D_PT_shape_diameter_mesh(ShapeDiameterSubPanel, bpy.types.Panel):
    bl_label = "Mesh"

    def draw_settings(self, layout, settings, context):
        layout.prop(settings, "points")
        layout.prop(settings, "use_modifiers")
        layout.prop(settings, "apply_scale")


class VIEW3D_PT_shape_diameter_output(ShapeDiameterSubPanel, bpy.types.Panel):
    bl_label = "Output"

    def draw_settings(self, layout, settings, context):
        layout.prop(settings, "normalize")
        col = layout.column(heading="Attributes")
        col.prop(settings, "attribute_name")
        col.prop(settings, "normalized_name")
        col.prop(settings, "color_name")


class VIEW3D_PT_shape_diameter_smoothing(ShapeDiameterSubPanel, bpy.types.Panel):
    bl_label = "Smoothing"

    @classmethod
    def poll(cls, context):
        return core.supports("smoothing")

    def draw_settings(self, layout, settings, context):
        operators.draw_smoothing(layout, settings)


class VIEW3D_PT_shape_diameter_bake(ShapeDiameterSubPanel, bpy.types.Panel):
    bl_label = "Bake Image"

    @classmethod
    def poll(cls, context):
        return core.has("smooth")

    def draw_settings(self, layout, settings, context):
        operators.draw_bake(layout, settings, context)


class VIEW3D_PT_shape_diameter_engine(ShapeDiameterSubPanel, bpy.types.Panel):
    bl_label = "Engine"

    def draw_settings(self, layout, settings, context):
        layout.prop(settings, "engine")
        for name in ("orientation", "accel"):
            if core.supports(name):
                layout.prop(settings, name)
        layout.use_property_split = False
        draw_status(layout, with_engines=True)


class VIEW3D_PT_shape_diameter_result(ShapeDiameterSubPanel, bpy.types.Panel):
    bl_label = "Result"
    bl_options = set()

    def draw_settings(self, layout, settings, context):
        layout.use_property_split = False
        if operators.last_run:
            layout.label(text=operators.last_run["text"], icon="INFO")
        ob = context.active_object
        if ob is None or ob.type != "MESH":
            layout.label(text="No active mesh")
            return
        names = (settings.attribute_name, settings.normalized_name, settings.color_name)
        found = [ob.data.attributes.get(name) for name in names if name]
        found = [a for a in found if a is not None]
        if not found:
            layout.label(text=f"{ob.name}: no Shape Diameter attributes yet")
        for attribute in found:
            layout.label(
                text=f"{attribute.name}: {attribute.data_type} on {attribute.domain}",
                icon="GROUP_VERTEX" if attribute.domain == "POINT" else "FACESEL",
            )
        layout.operator(operators.VIEW3D_OT_shape_diameter_show.bl_idname, icon="SHADING_SOLID")


class VIEW3D_PT_shape_diameter_segment(ShapeDiameterSubPanel, bpy.types.Panel):
    """Parts from thickness: the Segment button and its options (the SDF's options above
    apply when the values are computed)."""

    bl_label = "Segment"
    bl_options = set()

    @classmethod
    def poll(cls, context):
        return core.has("segment")

    def draw_settings(self, layout, settings, context):
        meshes = [ob for ob in context.selected_objects if ob.type == "MESH"]
        row = layout.row()
        row.scale_y = 1.3
        op = row.operator(
            segment_operator.OBJECT_OT_shape_diameter_segment.bl_idname,
            text=f"Segment ({len(meshes)} mesh{'es' if len(meshes) != 1 else ''})",
            icon="MOD_EXPLODE",
        )
        props.copy_segment_options(settings, op)
        segment_operator.draw_segment_settings(layout, settings)
        if segment_operator.last_run:
            layout.label(text=segment_operator.last_run["text"], icon="INFO")


classes = (
    VIEW3D_PT_shape_diameter,
    VIEW3D_PT_shape_diameter_rays,
    VIEW3D_PT_shape_diameter_mesh,
    VIEW3D_PT_shape_diameter_smoothing,
    VIEW3D_PT_shape_diameter_output,
    VIEW3D_PT_shape_diameter_bake,
    VIEW3D_PT_shape_diameter_engine,
    VIEW3D_PT_shape_diameter_result,
    VIEW3D_PT_shape_diameter_segment,
)
