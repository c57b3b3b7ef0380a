# SPDX-License-Identifier: GPL-3.0-or-later
"""The worker thread behind the interactive operator. Under `blender -b` (and in bpy from
PyPI) there is no window, so modal operators and timers cannot run: these tests drive
process.Job, the part of the modal path that does the work, directly from the main thread
as the modal timer does, and check the operator's guard while a job runs."""

import time

import bpy
import numpy as np
import pytest
from helpers import addon_module, select_only


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
