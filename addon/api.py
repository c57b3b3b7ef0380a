# SPDX-License-Identifier: GPL-3.0-or-later
"""The Shape Diameter for scripts running inside Blender (including `blender -b`).

The add-on's modules live under `bl_ext.<repository>.shape_diameter`; installed from a file
(drag and drop, or `blender --command extension install-file -r user_default`), that is:

    from bl_ext.user_default.shape_diameter import api

    result = api.compute_object(bpy.data.objects["Suzanne"], rays=64, points="faces")
    result.values        # float32 per polygon (or vertex): the SDF, in world units
    result.attributes    # the attributes written: ["sdf", "sdf_normalized", "sdf_color"]

    parts = api.segment_object(bpy.data.objects["Suzanne"], clusters=5)
    parts.segment_count  # parts found; parts.labels: int32 per polygon
    parts.vertex_groups  # ["part_01", ...]; parts.armature: the armature object's name

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

from . import baking, core, operators, part_writing, process, segmenting

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
    image: str = ""  # name of the baked image in bpy.data.images (UDIM tile 1001), if any
    # Every baked tile's image: tile number -> name (1001: `image`; 1002: "<image>.1002", ...;
    # with bake_tiles='TILED', `image` for every tile: one tiled image).
    tile_images: dict = field(default_factory=dict)


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
    (smoothing_iterations=1, smoothing_rule='local' or 'paper') or 'texture'
    (texture_size=1024, an integer in [16, 16384]; texture_radius=0: automatic, or texels in
    [0, 1024]; needs a UV map), attribute_name='sdf',
    normalized_name='sdf_normalized', color_name='sdf_color' (empty: not written),
    bake_image=False, uv_map='' (the active one), image_name='{object}_sdf', bake_margin=4
    (texels around each UV island, an integer in [0, 16384]), bake_depth='16' (the packed
    OpenEXR's half floats; '32': 32-bit floats), bake_tiles='IMAGES' (UVs on UDIM tiles: an
    image per tile; 'TILED': one tiled image), use_modifiers=False,
    apply_scale=True; and any further keyword that
    shape_diameter.compute() accepts. write=False computes without writing, and so without
    baking (a bake makes images in the file): bake_image is then skipped with a
    RuntimeWarning, and its UV map is not needed. progress: called
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
    skipped = _bake_skipped(opts, write)
    if depsgraph is None:
        depsgraph = context.evaluated_depsgraph_get()
    # Warnings about the whole run (what was skipped, long or large texture work) are issued
    # before computing, as the operator reports them, and go into every result, so that a
    # caller that reads any result's warnings sees them.
    tasks, run_warnings = process.prepare(depsgraph, objects, opts, for_writing=write)
    run_warnings = [*skipped, *run_warnings]
    for warning in run_warnings:
        warnings.warn(warning, RuntimeWarning, stacklevel=2)
    _run_cancellable(process.compute, tasks, opts, progress)
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
            tile_images=baking.image_names(t.image_name, t.image or {}, opts) if write else {},
        )
        for t in tasks
    ]


def _bake_skipped(opts, write):
    """With write=False a bake would make images only to throw them away: it is turned off
    (the options are the caller's copy). Returns the warning saying so, if any."""
    if write or not opts.bake_image:
        return []
    opts.bake_image = False
    return ["bake_image is skipped with write=False: a bake makes images in the file, and "
            "write=False writes nothing"]  # fmt: skip


def _run_cancellable(compute, work, opts, progress):
    """compute(work, opts, ...) with the caller's `progress`, where a False from it stops the
    run: Cancelled, also when the last callback said so after which nothing checked."""
    stopped = []

    def report(fraction):
        if progress(fraction) is False:
            stopped.append(True)

    compute(work, opts, progress=report if progress else None, cancelled=lambda: bool(stopped))
    if stopped:
        raise Cancelled()


def compute_object(obj, *, depsgraph=None, write=True, **options):
    """compute_objects() on one mesh object; returns its ObjectResult."""
    if obj is None or obj.type != "MESH":
        what = "None" if obj is None else f"{obj.name} ({obj.type.lower()})"
        raise UserError(f"Not a mesh: {what}")
    return compute_objects([obj], depsgraph=depsgraph, write=write, **options)[0]


@dataclass
class PartsResult:
    """What one object got from segment_objects(). labels: int32 per polygon, its part in
    [0, segment_count) (a polygon split into triangles of several parts takes the one with
    the largest area); triangle_labels: per loop triangle (Blender's triangulation, the
    core's labels); vertex_labels: int32 per vertex (-1 for a vertex in no face);
    segmentation: the core's shape_diameter.Segmentation (boundaries, adjacency, weights);
    reused_values: the SDF attribute on the mesh was segmented (not computed again);
    attributes, vertex_groups, materials, armature: what was written (names)."""

    object_name: str
    segment_count: int
    labels: np.ndarray
    triangle_labels: np.ndarray
    vertex_labels: np.ndarray
    segmentation: object
    reused_values: bool
    timings: dict
    attributes: list = field(default_factory=list)
    vertex_groups: list = field(default_factory=list)
    materials: list = field(default_factory=list)
    armature: str = ""
    warnings: list = field(default_factory=list)


def segment_objects(objects, *, depsgraph=None, write=True, progress=None, **options):
    """Segments every mesh object in `objects` into parts by thickness and writes the
    outputs (all or none), as the operator object.shape_diameter_segment does. Options:
    clusters=5, smoothness=0.26, mode='auto' ('cgal'), min_part_area=0.0 (a minimum part
    size, a share of the mesh's area in [0, 1): smaller parts join the neighbour they share
    the longest boundary with; 0: off), segments=0 (the number of parts wanted: clusters
    and smoothness are searched for it; 0: the clusters decide), reuse_values=True (the SDF
    attribute Compute wrote per face with the same settings on the same geometry is
    segmented as it is), face_sets=True, label_name='segment',
    segment_color_name='segment_color' (empty: not written), vertex_groups=True,
    group_prefix='part_', soft_weights=True, materials=False, armature=True,
    armature_name='{object}_parts'; and compute_objects()' options for the SDF where it is
    computed (points is always 'faces'). Raises UserError (nothing written) for what the
    user can fix, Cancelled when `progress` returns False."""
    if progress is not None and not callable(progress):
        raise UserError("progress must be a callable taking the fraction done, or None")
    context = bpy.context
    if options.get("engine") in (None, "DEFAULT"):
        options["engine"] = operators.resolve_engine(context, "DEFAULT")
    opts = segmenting.SegmentOptions.from_keywords(**options)
    if depsgraph is None:
        depsgraph = context.evaluated_depsgraph_get()
    parts, run_warnings = segmenting.prepare(depsgraph, objects, opts)
    for warning in run_warnings:
        warnings.warn(warning, RuntimeWarning, stacklevel=2)
    _run_cancellable(segmenting.compute, parts, opts, progress)
    written = part_writing.write(context, parts, opts) if write else [None] * len(parts)
    return [_parts_result(part, out, run_warnings) for part, out in zip(parts, written)]


def _parts_result(part, out, run_warnings):
    seg = part.segmentation
    out = out or part_writing.Written()
    return PartsResult(
        object_name=part.object_name,
        segment_count=seg.segment_count,
        labels=part.polygon_labels,
        triangle_labels=seg.labels,
        vertex_labels=seg.vertex_labels,
        segmentation=seg,
        reused_values=part.reused,
        timings=part.timings,
        attributes=out.attributes,
        vertex_groups=out.vertex_groups,
        materials=out.materials,
        armature=out.armature,
        warnings=[*run_warnings, *part.warnings],
    )


def segment_object(obj, *, depsgraph=None, write=True, **options):
    """segment_objects() on one mesh object; returns its PartsResult."""
    if obj is None or obj.type != "MESH":
        what = "None" if obj is None else f"{obj.name} ({obj.type.lower()})"
        raise UserError(f"Not a mesh: {what}")
    return segment_objects([obj], depsgraph=depsgraph, write=write, **options)[0]
