# SPDX-License-Identifier: GPL-3.0-or-later
"""The interactive path of the operator. Under `blender -b` (and in bpy from PyPI) there is no
window, so Blender itself cannot run a modal operator or a timer. These tests drive the parts
by hand: process.Job (the worker thread) polled from the main thread as the modal timer does,
and the operator's own invoke() and modal() on a stand-in instance and context, fed the
TIMER and ESC events Blender would send; plus the guard while a job runs. What they cannot
show: Blender's event loop calling modal(), the progress in the status bar, redraws."""

import time

import bpy
import numpy as np
import pytest
from helpers import addon_module, select_only
from modal_stand_in import defaults, event, stand_in


def big_sphere():
    bpy.ops.mesh.primitive_uv_sphere_add(segments=256, ring_count=128)
    ob = bpy.context.active_object
    select_only(ob)
    return ob


def prepare(**options):
    process = addon_module("process")
    opts = process.Options(**options)
    tasks, _ = process.prepare(
        bpy.context.evaluated_depsgraph_get(), bpy.context.selected_objects, opts
    )
    return process, opts, tasks


def test_job_gives_what_the_synchronous_run_gives():
    big_sphere()
    process, opts, tasks = prepare(rays=16)
    job = process.Job(tasks, opts).start()
    seen = []
    while not job.done:  # the modal timer's loop; bpy stays usable meanwhile
        seen.append(job.progress)
        assert bpy.context.active_object.name == "Sphere"
        time.sleep(0.005)
    assert job.wait() and job.error is None
    assert job.progress == 1.0 and seen == sorted(seen)
    _, _, sync = prepare(rays=16)
    process.compute(sync, opts)
    np.testing.assert_array_equal(tasks[0].values, sync[0].values)
    process.write(bpy.data, tasks, opts)
    assert "sdf" in bpy.context.active_object.data.attributes


def test_job_cancels():
    big_sphere()
    process, opts, tasks = prepare(rays=256)
    job = process.Job(tasks, opts).start()
    while job.progress == 0.0 and not job.done:
        time.sleep(0.001)
    job.cancel()
    started = time.perf_counter()
    assert job.wait(timeout=60)
    assert time.perf_counter() - started < 10
    assert isinstance(job.error, process.Cancelled), job.error
    assert tasks[0].values is None


def test_operator_waits_while_a_job_runs():
    operators = addon_module("operators")
    big_sphere()
    operators.running = object()
    try:
        assert not bpy.ops.object.shape_diameter.poll()
        with pytest.raises(RuntimeError, match="already running|computation is running|poll"):
            bpy.ops.object.shape_diameter()
    finally:
        operators.running = None
    assert bpy.ops.object.shape_diameter.poll()


def test_invoke_runs_synchronously_in_background():
    big_sphere()
    assert bpy.app.background
    assert bpy.ops.object.shape_diameter("INVOKE_DEFAULT", rays=4) == {"FINISHED"}
    assert "sdf" in bpy.context.active_object.data.attributes


def modal_operator(monkeypatch, **values):
    """The Compute operator's invoke() and modal() on a stand-in (modal_stand_in.py)."""
    process = addon_module("process")
    cls = addon_module("operators").OBJECT_OT_shape_diameter
    methods = ("_options", "_prepare", "_finish", "_report_error", "_stop", "invoke", "modal")
    return stand_in(monkeypatch, cls, methods, defaults(process.Options), values)


def test_modal_run_writes_when_the_job_is_done(monkeypatch):
    operators = addon_module("operators")
    ob = big_sphere()
    op, context, reports = modal_operator(monkeypatch, rays=8)
    assert op.invoke(context, event("LEFTMOUSE")) == {"RUNNING_MODAL"}
    assert operators.running is not None and not bpy.ops.object.shape_diameter.poll()
    assert "modal_handler_add" in context.window_manager.calls
    assert op.modal(context, event("MOUSEMOVE")) == {"PASS_THROUGH"}
    while True:
        result = op.modal(context, event("TIMER"))
        if result != {"PASS_THROUGH"}:
            break
        assert "sdf" not in ob.data.attributes  # nothing is written before the end
        time.sleep(0.01)
    assert result == {"FINISHED"}
    assert operators.running is None
    assert "sdf" in ob.data.attributes
    assert reports[-1][0] == {"INFO"} and "Shape Diameter: Sphere" in reports[-1][1]
    assert "event_timer_remove" in context.window_manager.calls


def test_modal_run_cancels_on_escape(monkeypatch):
    operators = addon_module("operators")
    ob = big_sphere()
    op, context, reports = modal_operator(monkeypatch, rays=256)
    assert op.invoke(context, event("LEFTMOUSE")) == {"RUNNING_MODAL"}
    assert op.modal(context, event("ESC", "PRESS")) == {"CANCELLED"}
    assert operators.running is None
    assert "sdf" not in ob.data.attributes
    assert reports == [({"WARNING"}, "Shape Diameter cancelled: nothing was changed")]


def test_modal_run_reports_an_engine_error(monkeypatch):
    operators = addon_module("operators")
    core = addon_module("core")
    ob = big_sphere()

    def broken(*args, **kwargs):
        raise RuntimeError("device lost")

    monkeypatch.setattr(core, "compute", broken)
    op, context, reports = modal_operator(monkeypatch)
    assert op.invoke(context, event("LEFTMOUSE")) == {"RUNNING_MODAL"}
    while (result := op.modal(context, event("TIMER"))) == {"PASS_THROUGH"}:
        time.sleep(0.01)
    assert result == {"CANCELLED"} and operators.running is None
    assert reports == [({"ERROR"}, "Shape Diameter failed: RuntimeError: device lost")]
    assert "sdf" not in ob.data.attributes
