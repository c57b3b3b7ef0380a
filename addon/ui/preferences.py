# SPDX-License-Identifier: GPL-3.0-or-later
"""The add-on preferences: the default engine, and what the core offers on this machine."""

import bpy
from bpy.props import StringProperty

from .. import core, props

# The add-on's own package (`bl_ext.<repository>.shape_diameter`), the key of its preferences.
ADDON_PACKAGE = __package__.rpartition(".")[0]


class ShapeDiameterPreferences(bpy.types.AddonPreferences):
    bl_idname = ADDON_PACKAGE

    default_engine_name: StringProperty(default="auto", options={"HIDDEN"})
    default_engine: props.stored_engine_property(
        "default_engine_name", False, "The engine runs use unless they name another"
    )

    def draw(self, context):
        draw_status(self.layout, with_engines=True)
        self.layout.prop(self, "default_engine")


def draw_status(layout, with_engines=False):
    """The core's state: its version and engines, or why it could not be loaded."""
    loaded, text = core.status()
    box = layout.box()
    if not loaded:
        box.label(text="The native core could not be loaded", icon="ERROR")
        box.label(text=text)
        return
    box.label(text=text, icon="CHECKMARK")
    if with_engines:
        for engine in core.engines():
            box.label(text=f"{engine['name']}: {engine.get('description', '')}")


classes = (ShapeDiameterPreferences,)
