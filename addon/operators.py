# SPDX-License-Identifier: GPL-3.0-or-later
"""The operators: Compute Shape Diameter (object.shape_diameter), thin over process.py, and
Show SDF Colors (view3d.shape_diameter_show).

In the interactive UI the core runs on a worker thread (the GIL is released in native code)
while a modal timer shows progress and Esc cancels; bpy is touched on the main thread only
(docs.blender.org/api/current/info_gotchas_crashes.html). Under `blender -b` timers and modal
handlers do not run, so invoke() runs the same work synchronously there.
"""

import time

import bpy

from . import core, process, props

# The job of the modal run in progress, if any (one at a time), and the last run's summary
# for the panel.
running = None
last_run = {}


def _preferences(context):
    addon = context.preferences.addons.get(__package__)
    return addon.preferences if addon else None


def resolve_engine(context, engine):
    """'DEFAULT' means the engine chosen in the preferences."""
    if engine != "DEFAULT":
        return engine
    prefs = _preferences(context)
    return prefs.default_engine if prefs else "auto"


def _summary(tasks, seconds):
    triangles = sum(len(t.mesh.triangles) for t in tasks)
    engine = tasks[0].engine if tasks else ""
    names = ", ".join(t.object_name for t in tasks)
    return f"Shape Diameter: {names}; {triangles} triangles, {engine}, {seconds:.2f} s"


def can_run_modal(context):
    """Timers and modal handlers need a window; `blender -b` has none."""
    return not bpy.app.background and context.window is not None


def _redraw(context):
    screen = getattr(context, "screen", None)
    for area in screen.areas if screen else ():
        if area.type == "VIEW_3D":
            area.tag_redraw()


class WorkerRun:
    """What the operators that run the core share: in the interface the work runs on a worker
    thread (process.Job) while a modal timer shows progress and Esc cancels; headless, or
    through execute(), synchronously. Subclasses give _prepare(context) -> (options, tasks),
    `work` (process.compute's signature: tasks, options, progress, cancelled), _finish(context,
    options, tasks, started) and `title`, the name in messages."""

    title = "Shape Diameter"

    @classmethod
    def poll(cls, context):
        if running is not None:
            cls.poll_message_set("A Shape Diameter computation is running (Esc cancels it)")
            return False
        return True

    def _report_error(self, ex):
        if isinstance(ex, (process.UserError, core.CoreUnavailable)):
            self.report({"ERROR"}, str(ex))
        else:  # an engine error, or a bug: say what it was, keep Blender running
            self.report({"ERROR"}, f"{self.title} failed: {type(ex).__name__}: {ex}")

    def execute(self, context):
        started = time.perf_counter()
        wm = context.window_manager
        try:
            options, tasks = self._prepare(context)
            wm.progress_begin(0, 1000)
            try:
                self.work(tasks, options, lambda f: wm.progress_update(int(1000 * f)))
            finally:
                wm.progress_end()
            self._finish(context, options, tasks, started)
        except Exception as ex:
            self._report_error(ex)
            return {"CANCELLED"}
        return {"FINISHED"}

    def invoke(self, context, event):
        global running
        if not can_run_modal(context):
            return self.execute(context)
        self._started = time.perf_counter()
        try:
            self._options_used, tasks = self._prepare(context)
        except Exception as ex:
            self._report_error(ex)
            return {"CANCELLED"}
        running = process.Job(tasks, self._options_used, self.work).start()
        wm = context.window_manager
        self._timer = wm.event_timer_add(0.1, window=context.window)
        wm.progress_begin(0, 1000)
        wm.modal_handler_add(self)
        return {"RUNNING_MODAL"}

    def _stop(self, context):
        global running
        wm = context.window_manager
        wm.event_timer_remove(self._timer)
        wm.progress_end()
        if context.workspace:
            context.workspace.status_text_set(None)
        job, running = running, None
        _redraw(context)
        return job

    def modal(self, context, event):
        job = running
        if event.type == "ESC" and event.value == "PRESS":
            job.cancel()
            job.wait()
            self._stop(context)
            self.report({"WARNING"}, f"{self.title} cancelled: nothing was changed")
            return {"CANCELLED"}
        if event.type != "TIMER":
            return {"PASS_THROUGH"}
        if not job.done:
            context.window_manager.progress_update(int(1000 * job.progress))
            if context.workspace:
                context.workspace.status_text_set(
                    f"{self.title}: {100 * job.progress:.0f}%   Esc: cancel"
                )
            _redraw(context)
            return {"PASS_THROUGH"}
        self._stop(context)
        if job.error is not None:
            self._report_error(job.error)
            return {"CANCELLED"}
        try:
            self._finish(context, self._options_used, job.tasks, self._started)
        except Exception as ex:
            self._report_error(ex)
            return {"CANCELLED"}
        return {"FINISHED"}

    def cancel(self, context):
        # Blender ends the modal operator (the window closes, a file is loaded).
        if running is not None:
            running.cancel()
            running.wait()
            self._stop(context)


@props.operator_options
class OBJECT_OT_shape_diameter(WorkerRun, bpy.types.Operator):
    """Compute the Shape Diameter Function (local thickness) of the selected meshes into
    attributes and a color attribute"""

    bl_idname = "object.shape_diameter"
    bl_label = "Compute Shape Diameter"
    bl_options = {"REGISTER", "UNDO"}

    @staticmethod
    def work(tasks, options, progress=None, cancelled=None):
        return process.compute(tasks, options, progress, cancelled)

    def _options(self, context):
        values = props.option_values(self)
        values["engine"] = resolve_engine(context, values["engine"])
        return process.Options.from_keywords(**values)

    def _prepare(self, context):
        options = self._options(context)
        tasks, warnings = process.prepare(
            context.evaluated_depsgraph_get(),
            context.selected_objects,
            options,
            active=context.active_object,
        )
        for warning in warnings:
            self.report({"WARNING"}, warning)
        return options, tasks

    def _finish(self, context, options, tasks, started):
        process.write(bpy.data, tasks, options)
        for task in tasks:
            for warning in task.warnings:
                self.report({"WARNING"}, warning)
        text = _summary(tasks, time.perf_counter() - started)
        last_run.clear()
        last_run.update(text=text, options=options, objects=[t.object_name for t in tasks])
        self.report({"INFO"}, text)

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        layout.use_property_decorate = False
        for name in ("rays", "cone_angle", "sampling"):
            layout.prop(self, name)
        if self.sampling == "random":
            layout.prop(self, "seed")
        for name in ("points", "normalize", "engine"):
            layout.prop(self, name)
        for name in ("orientation", "accel"):
            if core.supports(name):
                layout.prop(self, name)
        if core.supports("smoothing"):
            draw_smoothing(layout, self)
        for name in ("attribute_name", "normalized_name", "color_name"):
            layout.prop(self, name)
        if core.has("smooth"):
            draw_bake(layout, self, context)
        for name in ("use_modifiers", "apply_scale"):
            layout.prop(self, name)


def draw_smoothing(layout, settings):
    """The smoothing options that apply to the chosen method (operator and panel)."""
    layout.prop(settings, "smoothing")
    if settings.smoothing == "kring":
        layout.prop(settings, "smoothing_rings")
    elif settings.smoothing == "projected":
        layout.prop(settings, "smoothing_iterations")
        layout.prop(settings, "smoothing_rule")
    elif settings.smoothing == "texture":
        layout.prop(settings, "texture_size")
        layout.prop(settings, "texture_radius")


def draw_bake(layout, settings, context):
    """The bake options (operator and panel); the UV map is searched on the active mesh."""
    layout.prop(settings, "bake_image")
    col = layout.column()
    col.active = settings.bake_image or settings.smoothing == "texture"
    ob = context.active_object
    if ob is not None and ob.type == "MESH":
        col.prop_search(settings, "uv_map", ob.data, "uv_layers", icon="GROUP_UVS")
    else:
        col.prop(settings, "uv_map", icon="GROUP_UVS")
    col = layout.column()
    col.active = settings.bake_image
    col.prop(settings, "image_name")
    col.prop(settings, "bake_depth")
    col.prop(settings, "bake_tiles")
    if settings.smoothing != "texture":
        col.prop(settings, "texture_size")


class VIEW3D_OT_shape_diameter_show(bpy.types.Operator):
    """Show the active color attribute in this 3D view (Solid shading, color "Attribute")"""

    bl_idname = "view3d.shape_diameter_show"
    bl_label = "Show SDF Colors"
    bl_options = {"REGISTER"}

    @classmethod
    def poll(cls, context):
        space = context.space_data
        if space is None or space.type != "VIEW_3D":
            cls.poll_message_set("Needs a 3D view")
            return False
        return True

    def execute(self, context):
        shading = context.space_data.shading
        shading.type = "SOLID"
        shading.color_type = "VERTEX"
        return {"FINISHED"}


classes = (OBJECT_OT_shape_diameter, VIEW3D_OT_shape_diameter_show)


def register():
    for cls in classes:
        bpy.utils.register_class(cls)


def unregister():
    if running is not None:
        running.cancel()
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
