# SPDX-License-Identifier: GPL-3.0-or-later
"""An operator's own invoke() and modal() on a stand-in instance and context: the parts a
headless Blender cannot drive (no window, no event loop), driven by hand with the events
Blender would send."""

import dataclasses
import functools
import math
import types

import bpy
from helpers import addon_module


class FakeWindowManager:
    """What the modal path asks of the window manager, recorded."""

    def __init__(self):
        self.calls = []

    def __getattr__(self, name):  # event_timer_add, progress_update, modal_handler_add, ...
        return lambda *args, **kwargs: self.calls.append(name) or name


def event(kind, value="NOTHING"):
    return types.SimpleNamespace(type=kind, value=value)


def defaults(option_class, leave_out=("extra",)):
    """Every field of one of the add-on's option dataclasses at its default."""
    return {
        f.name: getattr(option_class(), f.name)
        for f in dataclasses.fields(option_class)
        if f.name not in leave_out
    }


def stand_in(monkeypatch, cls, methods, options, values, **context):
    """cls's `methods` bound to a stand-in carrying `options` with the cone angle a property
    holds (radians) and then `values`, and a stand-in context (plus `context`'s entries).
    Returns (operator, context, reports)."""
    operators = addon_module("operators")
    monkeypatch.setattr(operators, "can_run_modal", lambda context: True)
    options = {**options, "cone_angle": math.radians(120.0), **values}
    reports = []
    op = types.SimpleNamespace(report=lambda kind, text: reports.append((kind, text)), **options)
    for name in methods:
        setattr(op, name, functools.partial(getattr(cls, name), op))
    op.work, op.title = cls.work, cls.title  # a static method and a string: no instance
    fake = types.SimpleNamespace(
        window=object(),
        window_manager=FakeWindowManager(),
        workspace=None,
        screen=None,
        selected_objects=bpy.context.selected_objects,
        active_object=bpy.context.active_object,
        evaluated_depsgraph_get=bpy.context.evaluated_depsgraph_get,
        preferences=bpy.context.preferences,
        **context,
    )
    return op, fake, reports
