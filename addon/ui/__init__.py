# SPDX-License-Identifier: GPL-3.0-or-later
"""The add-on's interface: the sidebar panel and its sub-panels, and the preferences."""

import bpy

from . import panel, preferences

classes = (*preferences.classes, *panel.classes)


def register():
    for cls in classes:
        bpy.utils.register_class(cls)


def unregister():
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
