# SPDX-License-Identifier: GPL-3.0-or-later
"""The Shape Diameter for scripts running inside Blender (including `blender -b`).

The add-on's modules live under `bl_ext.<repository>.shape_diameter`; installed from a file
(drag and drop, or `blender --command extension install-file -r user_default`), that is:

    from bl_ext.user_default.shape_diameter import api

    result = api.compute_object(bpy.data.objects["Suzanne"], rays=64, points="faces")
    result.values        # float32 per polygon (or vertex): the SDF, in world units
    result.attributes    # the attributes written: ["sdf", "sdf_normalized", "sdf_color"]

It does what the operator object.shape_diameter does, synchronously, and raises instead of
reporting: ValueError (process.UserError, a subclass) for anything the user can fix, with the
message the operator would report; nothing is written then; Cancelled when a `progress`
callback returns False. The native package itself is `import shape_diameter` (numpy in,
numpy out).
"""

import warnings
from dataclasses import dataclass, field

import bpy
import numpy as np

from . import core, operators, process

UserError = process.UserError
Cancelled = process.Cancelled  # a progress callback returned False
CoreUnavailable = core.CoreUnavailable


@dataclass
class ObjectResult:
    """What one object got. Arrays have one entry per polygon (domain 'FACE') or per vertex
    (domain 'POINT'), except valid_rays: per triangle (or vertex). A vertex in no face has no
    thickness: values and normalized 0, colors (0, 0, 0, 0), valid_rays 0. warnings: what the
    operator reports, first those about the whole run (objects skipped as not meshes, long or
    large texture work; the same in every result), then this object's own. timings: seconds
    of the core's stages (shape_diameter.Result.timings), 'bake' where an image was baked, and
    'total': the object's whole computation, bake included."""

    object_name: str
    domain: str
    values: np.ndarray
    normalized: np.ndarray
    valid_rays: np.ndarray
    colors: np.ndarray
    engine: str
    timings: dict
    attributes: list
    shared_by: list = field(default_factory=list)
    warnings: list = field(default_factory=list)
    image: str = ""  # name of the baked image in bpy.data.images, if any


def engines():
    """The engines the core offers here: shape_diameter.engines()."""
    return core.engines()


def compute_objects(objects, *, depsgraph=None, write=True, progress=None, **options):
    """Computes every mesh object in `objects` together and writes their attributes (all or
    none). Options, with the operator's names: rays=30, cone_angle=120.0 (degrees),
    sampling='fibonacci', seed=0, points='faces', normalize='linear', engine=None (the
    preferences' default engine; or 'auto', 'opencl' (the best OpenCL device), or a name
    from engines()), orientation='auto' ('as_is', 'flip'), accel='bvh' or 'octree',
    smoothing='none', 'kring' (smoothing_rings=0: automatic), 'projected'
    (smoothing_iterations=1) or 'texture' (texture_size=1024, an integer in [16, 16384];
    texture_radius=0: automatic, or texels in [0, 1024]; needs a UV map), attribute_name='sdf',
    normalized_name='sdf_normalized', color_name='sdf_color' (empty: not written),
    bake_image=False, uv_map='' (the active one), image_name='{object}_sdf', bake_margin=4
    (texels around each UV island, an integer in [0, 16384]), use_modifiers=False,
    apply_scale=True; and any further keyword that
    shape_diameter.compute() accepts. write=False computes without writing. progress: called
    now and then with the fraction done (0 to 1); returning False stops the run, which raises
    Cancelled having written nothing. A mesh that several objects share is computed once,
    from the first of them in `objects` (the operator: from the active object, where it is
    one of them). The baked image is ObjectResult.image:
    bpy.data.images[result.image]. Warnings about the whole run are also issued
    (RuntimeWarning) before computing. Texture work estimated to need more than 80% of this
    machine's memory raises UserError, nothing computed."""
    if progress is not None and not callable(progress):
        raise UserError("progress must be a callable taking the fraction done, or None")
    context = bpy.context
    if options.get("engine") in (None, "DEFAULT"):
        options["engine"] = operators.resolve_engine(context, "DEFAULT")
    opts = process.Options.from_keywords(**options)
    if depsgraph is None:
        depsgraph = context.evaluated_depsgraph_get()
    # Warnings about the whole run (what was skipped, long or large texture work) are issued
    # before computing, as the operator reports them, and go into every result, so that a
    # caller that reads any result's warnings sees them.
    tasks, run_warnings = process.prepare(depsgraph, objects, opts, for_writing=write)
    for warning in run_warnings:
        warnings.warn(warning, RuntimeWarning, stacklevel=2)
    stopped = []

    def report(fraction):
        if progress(fraction) is False:
            stopped.append(True)

    process.compute(
        tasks, opts, progress=report if progress else None, cancelled=lambda: bool(stopped)
    )
    if stopped:  # a False from the last callback, after which nothing checked
        raise Cancelled()
    if write:
        process.write(bpy.data, tasks, opts)
    domain = "POINT" if opts.points == "vertices" else "FACE"
    written = [name for name, _, _ in opts.outputs()] if write else []
    return [
        ObjectResult(
            object_name=t.object_name,
            domain=domain,
            values=t.values,
            normalized=t.normalized,
            valid_rays=t.valid_rays,
            colors=t.colors,
            engine=t.engine,
            timings=t.timings,
            attributes=written,
            shared_by=list(t.shared_by),
            warnings=[*run_warnings, *t.warnings],
            image=t.image_name if write else "",
        )
        for t in tasks
    ]


def compute_object(obj, *, depsgraph=None, write=True, **options):
    """compute_objects() on one mesh object; returns its ObjectResult."""
    if obj is None or obj.type != "MESH":
        what = "None" if obj is None else f"{obj.name} ({obj.type.lower()})"
        raise UserError(f"Not a mesh: {what}")
    return compute_objects([obj], depsgraph=depsgraph, write=write, **options)[0]
