# SPDX-License-Identifier: GPL-3.0-or-later
"""One run of the Shape Diameter on Blender objects, in three steps shared by the operator and
the scripting API:

  prepare()  main thread: checks every object and option, reads each mesh into numpy
             (mesh_data); raises UserError and changes nothing when anything is wrong.
  compute()  any thread, no bpy: the core on each mesh's triangles, folded back to Blender's
             polygons. Job runs it on a worker thread for the interactive UI.
  write()    main thread: all attributes of all meshes, written together or not at all
             (a failure half-way restores what was written).
"""

import functools
import json
import os
import threading
import time
from dataclasses import dataclass, field, fields

import bpy
import numpy as np

from . import baking, core, mesh_data

# Attribute names: Blender 4.x refuses names over 67 bytes (its layer name buffer is 68
# bytes); names starting with "." are Blender's internal attributes.
MAX_NAME_BYTES = 63


class UserError(ValueError):
    """Something the user can fix; its message is reported as is."""


class Cancelled(Exception):
    """Raised in the progress callback when the user cancels."""

    def __init__(self, message="cancelled: nothing was written"):
        super().__init__(message)


SMOOTHING_METHODS = ("none", "kring", "projected", "texture")
# An object's share of the progress that its cast (and smoothing) takes when it is also
# baked; the bake takes the rest.
CAST_SHARE_WHEN_BAKING = 0.5
BAKE_DEPTHS = ("16", "32")  # bits of each float in the packed OpenEXR
BAKE_TILES = ("IMAGES", "TILED")  # UDIM tiles: an image each, or one tiled image

# What a vertex in no face gets in every output (values, normalised values; its colour is
# transparent black): it has no thickness. 0 is what the core gives every point where no ray
# anywhere found the other side (valid_rays 0 everywhere).
NOT_MEASURED = 0.0

# The texture's side and blur radius in texels, as the operator's properties bound them
# (props.py); the API checks the same bounds before any work (the core takes sizes from 1,
# and would refuse a bad one only in the bake, after the cast).
TEXTURE_SIZE_RANGE = (16, 16384)
TEXTURE_RADIUS_RANGE = (0.0, 1024.0)
BAKE_MARGIN_RANGE = (0, 16384)  # texels grown around each UV island (the core's bound)


@dataclass
class Options:
    """What a run computes and writes: shape_diameter.compute()'s keywords (COMPUTE_KEYS,
    OPTIONAL_COMPUTE_KEYS where the core has them, smoothing and its options), the outputs,
    the bake, and `extra`: further compute() keywords, checked against compute()'s
    signature."""

    rays: int = 30
    cone_angle: float = 120.0
    sampling: str = "fibonacci"
    seed: int = 0
    points: str = "faces"
    normalize: str = "linear"
    engine: str = "auto"
    accel: str = "bvh"
    orientation: str = "auto"
    smoothing: str = "none"
    smoothing_rings: int = 0  # kring: rings, 0 = chosen from the face count
    smoothing_iterations: int = 1  # projected
    smoothing_rule: str = "local"  # projected: 'local' or the paper's ('paper')
    texture_size: int = 1024  # texture smoothing and the bake, square
    texture_radius: float = 0.0  # texture smoothing: texels, 0 = 2 per 256 texels (paper)
    attribute_name: str = "sdf"
    normalized_name: str = "sdf_normalized"
    color_name: str = "sdf_color"
    bake_image: bool = False
    uv_map: str = ""  # empty: the active UV map
    image_name: str = "{object}_sdf"
    bake_margin: int = 4
    bake_depth: str = "16"  # the packed OpenEXR's floats: "16" (half) or "32"
    bake_tiles: str = "IMAGES"  # UDIM tiles: "IMAGES" (one per tile) or "TILED" (one image)
    use_modifiers: bool = False
    apply_scale: bool = True
    extra: dict = field(default_factory=dict)

    COMPUTE_KEYS = ("rays", "cone_angle", "sampling", "seed", "points", "normalize", "engine")
    # name: default (needs no support if default)
    OPTIONAL_COMPUTE_KEYS = {"accel": "bvh", "orientation": "auto"}

    @property
    def needs_uvs(self):
        return self.bake_image or self.smoothing == "texture"

    def smoothing_options(self):
        """shape_diameter.smooth() keywords for the chosen method."""
        if self.smoothing == "kring":
            return {"k": self.smoothing_rings or None}
        if self.smoothing == "projected":
            return {"iterations": self.smoothing_iterations, "rule": self.smoothing_rule}
        if self.smoothing == "texture":
            return {"texture_size": self.texture_size, "radius": self.texture_radius or None}
        return {}

    def bake_radius(self):
        """The bake's blur in texels: texture smoothing's (None: the core's default), else 0."""
        return self.smoothing_options()["radius"] if self.smoothing == "texture" else 0.0

    @classmethod
    def from_keywords(cls, **keywords):
        """Options from keyword arguments (the operator's property names); keywords that are
        not fields must be compute() keywords the core accepts."""
        known = {f.name for f in fields(cls)} - {"extra"}
        options = cls(**{k: v for k, v in keywords.items() if k in known})
        for key, value in keywords.items():
            if key not in known:
                if not core.supports(key):
                    raise TypeError(f"unknown option {key!r}; options: {', '.join(sorted(known))}")
                options.extra[key] = value
        return options

    def compute_options(self):
        options = {key: getattr(self, key) for key in self.COMPUTE_KEYS}
        for key, default in self.OPTIONAL_COMPUTE_KEYS.items():
            value = getattr(self, key)
            if core.supports(key):
                options[key] = value
            elif value != default:
                raise UserError(f"This build of the core has no {key!r} option")
        if self.smoothing != "none":
            options["smoothing"] = self.smoothing
            options["smoothing_options"] = self.smoothing_options()
        options.update(self.extra)
        return options

    # Options that do not change the values: which device casts, how the values are mapped
    # to [0, 1] and colours, the structure rays are traced through, threads.
    NOT_CHANGING_VALUES = ("engine", "normalize", "accel", "threads", "progress")

    def sdf_settings(self):
        """What the per-face values depend on, as JSON-able values: equal settings give the
        same values, so that segmenting may reuse values already on a mesh."""
        settings = {
            key: value
            for key, value in self.compute_options().items()
            if key not in self.NOT_CHANGING_VALUES
        }
        settings.update(apply_scale=self.apply_scale, use_modifiers=self.use_modifiers)
        return json.loads(json.dumps(settings, sort_keys=True, default=str))

    def outputs(self):
        """[(name, data_type, domain)] written by a run; empty names are not written."""
        on_vertices = self.points == "vertices"
        domain = "POINT" if on_vertices else "FACE"
        out = [(self.attribute_name, "FLOAT", domain)]
        if self.normalized_name:
            out.append((self.normalized_name, "FLOAT", domain))
        if self.color_name:
            out.append((self.color_name, "BYTE_COLOR", "POINT" if on_vertices else "CORNER"))
        return out

    def check_values(self):
        """The numbers the core sees only late (the bake runs after the cast), checked up
        front, for dry runs too. Raises UserError naming the option and its range."""
        lo, hi = TEXTURE_SIZE_RANGE
        size = self.texture_size
        integer = isinstance(size, (int, np.integer)) and not isinstance(size, bool)
        if not integer or not lo <= size <= hi:
            raise UserError(f"texture_size must be an integer in [{lo}, {hi}], got {size!r}")
        lo, hi = TEXTURE_RADIUS_RANGE
        radius = self.texture_radius
        number = isinstance(radius, (int, float, np.integer, np.floating))
        if not number or isinstance(radius, bool) or not lo <= radius <= hi:  # NaN fails too
            raise UserError(
                f"texture_radius must be a number in [{lo:g}, {hi:g}] texels (0: 2 per 256 "
                f"texels of the texture), got {radius!r}"
            )
        lo, hi = BAKE_MARGIN_RANGE
        margin = self.bake_margin
        integer = isinstance(margin, (int, np.integer)) and not isinstance(margin, bool)
        if not integer or not lo <= margin <= hi:
            raise UserError(
                f"bake_margin must be an integer in [{lo}, {hi}] texels, got {margin!r}"
            )

    def check(self):
        if self.points not in ("faces", "vertices"):
            raise UserError(f"points must be 'faces' or 'vertices', got {self.points!r}")
        if not self.attribute_name:
            raise UserError("The attribute name is empty")
        names = [name for name, _, _ in self.outputs()]
        for name in names:
            if name.startswith("."):
                raise UserError(f"Attribute names starting with '.' are Blender's own: {name!r}")
            if len(name.encode("utf-8")) > MAX_NAME_BYTES:
                raise UserError(f"Attribute name longer than {MAX_NAME_BYTES} bytes: {name!r}")
        if len(set(names)) != len(names):
            raise UserError(f"The output attribute names must differ: {', '.join(names)}")
        if self.smoothing not in SMOOTHING_METHODS:
            raise UserError(f"smoothing must be one of {SMOOTHING_METHODS}, got {self.smoothing!r}")
        if self.bake_image and not self.image_name.strip():  # "{object}" alone is a name
            raise UserError("The image name is empty")
        if self.smoothing != "none" and not core.supports("smoothing"):
            raise UserError("This build of the core has no smoothing")
        if self.bake_depth not in BAKE_DEPTHS:
            raise UserError(f"bake_depth must be one of {BAKE_DEPTHS}, got {self.bake_depth!r}")
        if self.bake_tiles not in BAKE_TILES:
            raise UserError(f"bake_tiles must be one of {BAKE_TILES}, got {self.bake_tiles!r}")
        if self.bake_image and not core.has("smooth"):
            raise UserError("This build of the core cannot bake (no shape_diameter.smooth)")


@dataclass
class Task:
    """One mesh to compute: found again by session uid when writing (the user may delete or
    edit objects while a job runs in the UI)."""

    object_name: str
    object_uid: int
    mesh_uid: int
    topology: mesh_data.Topology
    mesh: mesh_data.Triangulation
    shared_by: list = field(default_factory=list)  # other objects using the same mesh
    linear: list = None  # the 3x3 transform applied (apply_scale), row by row, or None
    # Filled by compute():
    values: np.ndarray = None  # float32 per polygon (or vertex): the SDF
    normalized: np.ndarray = None  # float32 per polygon (or vertex), in [0, 1]
    valid_rays: np.ndarray = None  # int32 per triangle (or vertex): rays kept
    colors: np.ndarray = None  # float32 (k, 4) sRGB, per polygon (or vertex)
    corner_uvs: np.ndarray = None  # float32 (m, 3, 2) per triangle corner, when needed
    image_name: str = ""
    # Per UDIM tile (1001 always): the bytes of its one-channel OpenEXR file (exr.py).
    image: dict = None
    uv_layout: object = None  # shape_diameter.UvLayout of corner_uvs, where they are needed
    engine: str = ""
    timings: dict = None
    warnings: list = field(default_factory=list)


def _editable_problem(ob):
    me = ob.data
    for thing, what in ((ob, "object"), (me, "mesh")):
        if thing.library is not None:
            return (
                f"{ob.name}: its {what} {thing.name!r} is linked from {thing.library.filepath!r} "
                "and cannot be changed (make it local first)"
            )
        if not getattr(thing, "is_editable", True):
            return f"{ob.name}: its {what} {thing.name!r} is not editable (a linked override?)"
    return None


def _mode_problem(ob):
    if ob.mode == "EDIT" or ob.data.is_editmode:
        return f"{ob.name} is in Edit Mode: switch to Object Mode first"
    if ob.mode == "SCULPT" and getattr(ob, "use_dynamic_topology_sculpting", False):
        return f"{ob.name} uses Dynamic Topology in Sculpt Mode: switch to Object Mode first"
    return None


def _attribute_problem(ob, options):
    for name, data_type, domain in options.outputs():
        # Blender keeps vertex group names apart from attributes and refuses an attribute
        # of a group's name: checked here, since it failed only after the computation.
        if ob.vertex_groups.get(name) is not None:
            return (
                f"{ob.name}: a vertex group is named {name!r}; rename it, or choose another "
                "name for the result"
            )
        existing = ob.data.attributes.get(name)
        if (
            existing is not None
            and (existing.data_type, existing.domain) != (data_type, domain)
            and not mesh_data.is_written_output(ob.data, existing)
        ):
            return (
                f"{ob.name}: attribute {name!r} exists as {existing.data_type} on "
                f"{existing.domain}; the result is {data_type} on {domain}: rename or remove "
                "it, or choose another name"
            )
    return None


def _not_a_mesh(ob):
    """How a run names an object it cannot measure, with what would make it a mesh where
    Blender has a way (a collection instance read just 'Inst (empty)')."""
    if ob.type == "EMPTY" and ob.instance_type == "COLLECTION":
        return f"{ob.name} (a collection instance: Make Instances Real first)"
    if ob.type in ("CURVE", "SURFACE", "FONT", "META"):
        return f"{ob.name} ({ob.type.lower()}: convert it to a mesh first)"
    return f"{ob.name} ({ob.type.lower()})"


# Modifiers that leave the surface where it is (normals, UVs, weights, splitting into
# triangles or along edges): a run without Use Modifiers loses nothing of the shape to them.
_SHAPE_KEEPING_MODIFIERS = {
    "WEIGHTED_NORMAL",
    "NORMAL_EDIT",
    "UV_PROJECT",
    "UV_WARP",
    "VERTEX_WEIGHT_EDIT",
    "VERTEX_WEIGHT_MIX",
    "VERTEX_WEIGHT_PROXIMITY",
    "DATA_TRANSFER",
    "TRIANGULATE",
    "EDGE_SPLIT",
}
# Blender's Shade Auto Smooth adds a geometry-nodes modifier of this node group (4.1 on), which
# sets sharp edges alone: it must not be named as changing the shape on every run.
_SHAPE_KEEPING_NODE_GROUPS = ("Smooth by Angle",)


def _keeps_shape(modifier) -> bool:
    if modifier.type in _SHAPE_KEEPING_MODIFIERS:
        return True
    group = getattr(modifier, "node_group", None) if modifier.type == "NODES" else None
    return group is not None and group.name.startswith(_SHAPE_KEEPING_NODE_GROUPS)


def _counted(count: int, one: str, many: str) -> str:
    return f"{count} {one if count == 1 else many}"


def _shape_changes(ob):
    """What changes `ob`'s shape in the viewport beyond its base mesh ('modifiers (Mirror)',
    'shape keys', both), or '': a run without Use Modifiers measured a half of a mirrored
    model, or a cube a shape key flattens, without a word."""
    found = []
    modifiers = [m.name for m in ob.modifiers if m.show_viewport and not _keeps_shape(m)]
    if modifiers:
        found.append(f"its modifiers ({', '.join(modifiers)})")
    keys = ob.data.shape_keys
    if (
        keys is not None
        and len(keys.key_blocks) > 1
        and (
            not keys.use_relative
            or (ob.show_only_shape_key and ob.active_shape_key_index > 0)
            or any(k.value != 0.0 and not k.mute for k in keys.key_blocks[1:])
        )
    ):
        found.append("its shape keys")
    return " and ".join(found)


def prepare(depsgraph, objects, options, for_writing=True, active=None):
    """Tasks for the mesh objects among `objects`, plus the warnings about the whole run
    (objects skipped as not meshes, long or large texture work), to report before computing;
    a warning about one object (its mesh shared with others) goes into its task's warnings.
    A mesh several objects share is computed once, from `active` when it is one of them (the
    operator's active object: its transform is the one the user looks at), else from the
    first of them in `objects`. Raises UserError, having changed nothing, when the run cannot
    go ahead (texture work too large for this machine's memory included). for_writing=False
    (a dry run of the scripting API) skips the checks of the attributes to be written."""
    options.check_values()
    if for_writing:
        options.check()
    objects = list(objects)
    meshes, notices = _meshes_to_compute(objects)
    source = _sources(meshes, active)
    tasks = {}
    for ob in meshes:
        problem = _mode_problem(ob)
        if for_writing:
            problem = problem or _editable_problem(ob) or _attribute_problem(ob, options)
        if problem:
            raise UserError(problem)
        uid = ob.data.session_uid
        if uid in tasks:
            if ob is not source[uid]:  # (the source joined its task when it was made)
                tasks[uid].shared_by.append(ob.name)
            continue
        # Computed from the mesh's source object, in this object's place of the order.
        tasks[uid] = _task(depsgraph, source[uid], options)
        if source[uid] is not ob:
            tasks[uid].shared_by.append(ob.name)
    images = [t.image_name for t in tasks.values() if t.image_name]
    if len(set(images)) != len(images):
        raise UserError("Several objects would bake into one image: put {object} in the image name")
    notice = _texture_work_notice(list(tasks.values()), options)
    if notice:
        notices.append(notice)
    notices.extend(_find_uv_layouts(tasks.values(), options))
    _sharing_warnings(tasks, objects if for_writing else None)
    return list(tasks.values()), notices


def _meshes_to_compute(objects):
    """(the mesh objects with faces, notices of what was skipped); UserError when none is."""
    if not objects:
        raise UserError("Nothing selected: select one or more mesh objects")
    meshes = [ob for ob in objects if ob.type == "MESH"]
    notices = []
    others = [_not_a_mesh(ob) for ob in objects if ob.type != "MESH"]
    if not meshes:
        raise UserError(f"Not a mesh: {', '.join(others)}")
    if others:
        notices.append(f"Skipped what is not a mesh: {', '.join(others)}")
    # A mesh without faces (a wire rig, a single-vertex placeholder) has no thickness: skipped as
    # what is not a mesh is, unless nothing else is left (one such mesh stopped the whole run).
    faceless = [ob for ob in meshes if len(ob.data.polygons) == 0]
    if len(faceless) == len(meshes):
        more = ", ".join(ob.name for ob in faceless[1:])
        raise UserError(
            f"{faceless[0].name} has no faces" + (f" (nor have {more})" if more else "")
        )
    if faceless:
        notices.append(f"Skipped meshes without faces: {', '.join(ob.name for ob in faceless)}")
        meshes = [ob for ob in meshes if len(ob.data.polygons) > 0]
    return meshes, notices


def _sources(meshes, active):
    """The object each mesh is computed from (by the mesh's session_uid): the active one
    where it shares the mesh, else the first."""
    source = {}
    for ob in meshes:
        source.setdefault(ob.data.session_uid, ob)
    if active is not None and active.type == "MESH" and active in meshes:
        source[active.data.session_uid] = active
    return source


def _task(depsgraph, ob, options):
    """The task computing `ob`'s mesh, its triangles and UVs read now. UserError (naming the
    object) for what would stop it."""
    me = ob.data
    matrix = ob.matrix_world if options.apply_scale else None
    original = mesh_data.topology(me)
    triangles, uvs = _geometry(depsgraph, ob, original, matrix, options)
    # Checked here, before any object is computed, so that the message names the object
    # (the core's own check would come after the earlier objects' work).
    if not np.isfinite(triangles.vertices).all():
        raise UserError(
            f"{ob.name} has vertices whose coordinates are not finite (NaN or infinite"
            f"{' after its modifiers' if options.use_modifiers else ''}): fix them, e.g. "
            "by deleting those vertices in Edit Mode"
        )
    task = Task(ob.name, ob.session_uid, me.session_uid, original, triangles, corner_uvs=uvs)
    if matrix is not None:
        task.linear = [list(row) for row in matrix.to_3x3()]
    if not options.use_modifiers:
        left_out = _shape_changes(ob)
        if left_out:
            task.warnings.append(
                f"{ob.name}: {left_out} change its shape in the viewport and are left out "
                "(Use Modifiers is off): the values are those of its base mesh"
            )
    if options.bake_image:
        task.image_name = options.image_name.replace("{object}", ob.name)
        problem = _image_problem(bpy.data, task.image_name)
        if problem:
            raise UserError(problem)
    return task


def _geometry(depsgraph, ob, original, matrix, options):
    """(triangulation, corner UVs) of the base mesh, or with Use Modifiers of the evaluated
    one, which must keep the base mesh's topology (the values are written back onto it)."""
    me = ob.data
    if not options.use_modifiers:
        triangles = mesh_data.triangulation(me, matrix)
        return triangles, _corner_uvs(ob, me, options, triangles.flipped)
    evaluated = ob.evaluated_get(depsgraph)
    if not evaluated.is_evaluated:  # its base mesh would be computed without a word
        raise UserError(
            f"{ob.name} is not evaluated in this view layer (its collection is excluded "
            "or disabled, it is disabled in viewports, or it is in no scene), so Use "
            "Modifiers cannot apply its modifiers and shape keys: include it, or turn "
            "off Use Modifiers"
        )
    temp = evaluated.to_mesh()
    try:
        if not mesh_data.topology(temp).matches(original):
            raise UserError(
                f"The modifiers of {ob.name} change its topology "
                f"({_counted(len(me.vertices), 'vertex', 'vertices')}, "
                f"{_counted(len(me.polygons), 'face', 'faces')} become "
                f"{len(temp.vertices)}, {len(temp.polygons)}): the result could not be "
                "written back. Turn off Use Modifiers, or apply or disable the "
                "modifiers that add or remove geometry"
            )
        triangles = mesh_data.triangulation(temp, matrix)
        return triangles, _corner_uvs(ob, temp, options, triangles.flipped)
    finally:
        evaluated.to_mesh_clear()


def _sharing_warnings(tasks, chosen):
    """Each task's warnings about its mesh's other users: the selected ones it was computed
    for, and (with `chosen`, the objects of a run that writes) the unselected ones that show
    its values too, measured with the computing object's transform (computing a scaled copy
    rescaled the original's values without a word)."""
    unselected = {}
    if chosen is not None:
        names = {ob.name for ob in chosen}
        for ob in bpy.data.objects:
            if ob.type == "MESH" and ob.name not in names and ob.data.session_uid in tasks:
                unselected.setdefault(ob.data.session_uid, []).append(ob.name)
    for uid, task in tasks.items():
        if task.shared_by:
            task.warnings.append(
                f"{task.object_name} shares its mesh with {', '.join(task.shared_by)}: "
                f"computed once, from {task.object_name}"
            )
        if uid in unselected:
            task.warnings.append(
                f"{task.object_name}'s mesh is also used by {', '.join(unselected[uid])}, not "
                f"computed: they show these values too, measured with {task.object_name}'s "
                "transform"
            )


# Texture work (texture smoothing, the bake) grows with the texels, and the blur with the
# radius too: a 2048^2 bake with texture smoothing at a radius of 1024 texels ran for half a
# minute on 2 cores without a word. It is estimated before computing, from the core's figures
# (shape_diameter.smoothing.texture_cost: the blur's reads, the buffers) and the add-on's
# own, measured on a 2-core AMD EPYC with bpy 4.5 on Spot (TextureCost.cpu_seconds is the
# core's side):
# The image's side of a bake: its one-channel half-float OpenEXR encoded (worker thread;
# bench/blender_bake.py: 0.131 s at 2048^2, 0.045 s at 1024^2), Blender's part being 0.1 ms;
# 32-bit floats took twice as long (0.262 s at 2048^2).
SECONDS_PER_BAKED_TEXEL = {"16": 4.5e-8, "32": 9.0e-8}


# A bake's memory, from what the code holds (not measured): while one image is encoded, its
# float32 values, their copy at the file's depth and the compressed file (at most as large);
# every image baked is then held, compressed, until all are written.
def baked_bytes_per_texel(depth):
    """(while encoding, held after): bytes a texel of one baked image."""
    value = 2 if depth == "16" else 4
    return 4 + 2 * value, value


# Past WARN_SECONDS or WARN_MEMORY of the machine's memory the
# run says so before it starts (the interface's Esc still cancels it); past REFUSE_MEMORY it
# is refused: swapping, or the kernel's out-of-memory killer ending Blender and its unsaved
# work. Time alone never refuses: an OpenCL GPU blurs far faster than the estimate's CPU.
WARN_SECONDS = 10.0
WARN_MEMORY = 0.25
REFUSE_MEMORY = 0.8


def physical_memory():
    """Bytes of memory of this machine, or None where the system does not say."""
    try:
        return os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (AttributeError, ValueError, OSError):
        return None


def texture_work(tasks, options):
    """(seconds, bytes, threads): the estimated time of a run's texture work on the CPU
    threads and its peak memory; (0.0, 0, threads) without texture work."""
    threads = max(1, int(options.extra.get("threads") or core.cpu_threads()))
    seconds, peak, baked, largest = 0.0, 0, 0, 0
    if not options.needs_uvs:
        return seconds, peak, threads
    passes = []  # (radius, baked): one texture pass each
    if options.smoothing == "texture":
        passes.append((options.smoothing_options()["radius"], False))
    if options.bake_image:
        passes.append((options.bake_radius(), True))
    for task in tasks:
        for radius, bake in passes:
            cost = core.texture_cost(options.texture_size, radius, task.corner_uvs)
            seconds += cost.cpu_seconds(threads)
            peak = max(peak, cost.bytes)
            if bake:
                seconds += cost.texels * SECONDS_PER_BAKED_TEXEL[options.bake_depth]
                baked += cost.texels
                largest = max(largest, cost.texels)
    encoding, held = baked_bytes_per_texel(options.bake_depth)
    return seconds, max(peak, largest * encoding) + baked * held, threads


def _size(count):
    return f"{count / 2**30:.1f} GiB" if count >= 2**30 else f"{count / 2**20:.0f} MiB"


def _texture_work_notice(tasks, options):
    """A warning (or None) for texture work estimated to be long or large; raises UserError
    for work that cannot fit in this machine's memory."""
    if not options.needs_uvs:
        return None
    seconds, peak, threads = texture_work(tasks, options)
    size = options.texture_size
    parts = (["texture smoothing"] if options.smoothing == "texture" else []) + (
        ["the bake"] if options.bake_image else []
    )
    what = (
        f"{' and '.join(parts)} of {len(tasks)} object{'s' if len(tasks) != 1 else ''} at "
        f"{size} x {size} texels"
    )
    if options.smoothing == "texture" and options.texture_radius:
        what += (
            f" with a blur radius of {options.texture_radius:g} texels (default "
            f"{core.default_radius(size):g})"
        )
    memory = physical_memory()
    if memory and peak > REFUSE_MEMORY * memory:
        raise UserError(
            f"Too large: {what} would need about {_size(peak)} of memory, more than "
            f"{REFUSE_MEMORY:.0%} of this machine's {_size(memory)}; lower the resolution"
            f"{' or bake fewer objects at once' if options.bake_image and len(tasks) > 1 else ''}"
        )
    if seconds > WARN_SECONDS or (memory and peak > WARN_MEMORY * memory):
        return (
            f"Long or large texture work ahead: {what}: about {seconds:.0f} s on {threads} CPU "
            f"thread{'s' if threads != 1 else ''} and {_size(peak)} of memory (an estimate; a "
            "GPU blurs faster). A smaller radius or resolution costs less"
        )
    return None


def _find_uv_layouts(tasks, options):
    """Each task's UV layout (UDIM tiles, overlapping shells) for texture smoothing and the
    bake, found now, so that what it says is reported before the work (and found once: the
    work takes it). Returns those words, each naming its object."""
    if not options.needs_uvs or not core.has("uv_layout"):
        return []
    notices = []
    for task in tasks:
        mesh = task.mesh
        task.uv_layout = core.uv_layout(
            mesh.vertices, mesh.triangles, task.corner_uvs, options.points, options.bake_image
        )
        notices.extend(f"{task.object_name}: {message}" for message in task.uv_layout.warnings)
    return notices


def _corner_uvs(ob, me, options, flipped):
    """The chosen UV map per triangle corner, when the run needs one (after triangulation())."""
    if not options.needs_uvs:
        return None
    what = "the bake" if options.bake_image else "texture smoothing"
    if options.uv_map:
        if me.uv_layers.get(options.uv_map) is None:
            raise UserError(f"{ob.name} has no UV map {options.uv_map!r}, needed by {what}")
        name = options.uv_map
    elif me.uv_layers.active is not None:
        name = me.uv_layers.active.name
    else:
        raise UserError(f"{ob.name} has no UV map, needed by {what}")
    uvs = mesh_data.corner_uvs(me, name, flipped)
    # Checked before any work, naming the map: the core's own check came after the cast, as
    # an unnamed 'ValueError: uvs must be finite'.
    if not np.isfinite(uvs).all():
        raise UserError(
            f"{ob.name}'s UV map {name!r} has coordinates that are not finite (NaN "
            f"or infinite), needed by {what}: fix or unwrap it again"
        )
    return uvs


def polygon_means(triangle_values, mesh):
    """Each polygon's area-weighted mean of its triangles' values (the plain mean where all
    of a polygon's triangles have zero area)."""
    v = mesh.vertices
    t = mesh.triangles
    area = 0.5 * np.linalg.norm(np.cross(v[t[:, 1]] - v[t[:, 0]], v[t[:, 2]] - v[t[:, 0]]), axis=1)
    polys = mesh.triangle_polygons
    n = int(polys.max()) + 1 if len(polys) else 0
    values = np.asarray(triangle_values, dtype=np.float64)
    weight = np.bincount(polys, weights=area, minlength=n)
    weighted = np.bincount(polys, weights=area * values, minlength=n)
    count = np.bincount(polys, minlength=n)
    plain = np.bincount(polys, weights=values, minlength=n) / np.maximum(count, 1)
    safe = np.where(weight > 0.0, weight, 1.0)
    return np.where(weight > 0.0, weighted / safe, plain).astype(np.float32)


def _bake(task, options, step):
    """The normalised field through the UV map, blurred in texture space when that is the
    smoothing chosen (the paper's texture-space smoothing, 4.4), into task.image; `step`
    reports the bake's progress (0 to 1) and raises to cancel."""
    started = time.perf_counter()
    normalized = task.normalized
    per_point = normalized[task.mesh.triangle_polygons] if options.points == "faces" else normalized
    with core.collect_warnings() as caught:  # e.g. a device's failure
        baking.bake(task, options, per_point, step)
    task.warnings.extend(f"{task.object_name} (bake): {message}" for message in caught)
    task.timings["bake"] = time.perf_counter() - started


def _with_layout(compute_options, task):
    """compute()'s options with the task's UV layout, for texture smoothing (found before)."""
    if task.uv_layout is None or compute_options.get("smoothing") != "texture":
        return compute_options
    smoothing = {**compute_options["smoothing_options"], "uv_layout": task.uv_layout}
    return {**compute_options, "smoothing_options": smoothing}


def compute(tasks, options, progress=None, cancelled=None):
    """Runs the core on every task (no bpy: safe on a worker thread). `progress(fraction)` is
    called now and then; when `cancelled()` turns true, Cancelled is raised."""
    total = float(sum(len(t.mesh.triangles) for t in tasks)) or 1.0
    done = 0.0
    compute_options = options.compute_options()
    for task in tasks:
        share = len(task.mesh.triangles) / total

        # The cast (and smoothing) and the bake each have their part of the object's share,
        # one after the other: progress only moves forward.
        cast_share = share * (CAST_SHARE_WHEN_BAKING if options.bake_image else 1.0)

        def step(fraction, start=done, width=cast_share):
            if cancelled is not None and cancelled():
                raise Cancelled()
            if progress is not None:
                progress(start + width * fraction)

        step(0.0)
        computing = time.perf_counter()
        mesh = task.mesh
        loose = None  # vertex values: the vertices in no face
        # Smoothing, when chosen, is the core's too: compute() casts, then smooths
        # (Result.values; Result.raw keeps the values as cast).
        # The core's warnings (few rays kept, parts the near-hit cutoff reaches, no value
        # anywhere, ...) are the object's, each said once: kept, not also printed.
        try:
            with core.collect_warnings() as caught:
                result = core.compute(
                    mesh.vertices, mesh.triangles, _with_layout(compute_options, task), step,
                    task.corner_uvs,
                )  # fmt: skip
        except ValueError as ex:  # the core refused this mesh: say which object it was
            raise UserError(f"{task.object_name}: {ex}") from ex
        task.warnings.extend(f"{task.object_name}: {message}" for message in caught)
        if options.points == "faces":
            task.values = polygon_means(result.values, mesh)
            task.normalized = core.normalize(task.values, options.normalize)
        else:
            task.values = np.asarray(result.values, dtype=np.float32)
            task.normalized = np.asarray(result.normalized, dtype=np.float32)
            # A vertex in no face has no thickness to measure: the core casts no ray from it
            # and fills it, as any point without a kept ray, with a value from its neighbours
            # (valid_rays 0), here the median of the mesh, so that normalising and smoothing
            # the others are unchanged. Written as it is, it read as measured; it is written
            # as NOT_MEASURED instead, with no colour (below).
            loose = task.topology.loose_vertices()
            if loose.any():
                task.values[loose] = NOT_MEASURED
                task.normalized[loose] = NOT_MEASURED
                task.warnings.append(
                    f"{task.object_name}: "
                    f"{_counted(int(loose.sum()), 'vertex', 'vertices')} in no face (loose "
                    "vertices, wire edges) have no thickness: their values are 0 and their "
                    "colour transparent black"
                )
        task.timings = dict(result.timings)
        if options.bake_image:
            _bake(task, options, functools.partial(step, start=done + cast_share,
                                                   width=share - cast_share))  # fmt: skip
        task.valid_rays = result.valid_rays
        task.colors = core.colors(task.normalized) if options.color_name else None
        if loose is not None and task.colors is not None:
            task.colors[loose] = 0.0  # transparent black: a colour the map never gives
        task.engine = result.engine
        if result.flipped_faces:  # measured right, but its normals still point in
            # Polygons, as Blender counts faces (the core counts triangles).
            flipped = len(np.unique(mesh.triangle_polygons[result.reversed_faces]))
            faces = _counted(flipped, "face points", "faces point")
            task.warnings.append(
                f"{task.object_name}: {faces} inward (inside out) and "
                f"{'was' if flipped == 1 else 'were'} measured turned outward; the mesh is "
                "unchanged (Mesh > Normals > Recalculate Outside turns it in Blender)"
            )
        task.timings["total"] = time.perf_counter() - computing
        done += share
    if progress is not None:
        progress(1.0)
    return tasks


def _find_object(bpy_data, uid):
    for ob in bpy_data.objects:
        if ob.session_uid == uid:
            return ob
    return None


def write(bpy_data, tasks, options):
    """Writes every task's attributes, all or none. Returns the objects written."""
    targets = []
    for task in tasks:
        ob = _find_object(bpy_data, task.object_uid)
        if ob is None or ob.type != "MESH":
            raise UserError(f"{task.object_name} was deleted while computing; nothing was written")
        if ob.data.session_uid != task.mesh_uid or not mesh_data.topology(ob.data).matches(
            task.topology
        ):
            raise UserError(f"{ob.name}'s mesh changed while computing; nothing was written")
        problem = _mode_problem(ob) or _editable_problem(ob) or _attribute_problem(ob, options)
        if task.image_name:
            problem = problem or _image_problem(bpy_data, task.image_name)
        if problem:
            raise UserError(problem + "; nothing was written")
        targets.append((ob, task))

    undo = []  # functions taking back each change, most recent last
    new_images = []  # (image, the name it takes once everything is written)
    try:
        for ob, task in targets:
            me = ob.data
            undo.append(_record_restorer(me))
            undo.append(_record_restorer(me, mesh_data.SDF_SETTINGS_PROPERTY))
            if options.points == "faces":
                colors = (
                    mesh_data.polygon_loop_expand(task.colors, task.topology.loop_totals)
                    if task.colors is not None
                    else None
                )
            else:
                colors = task.colors
            # Restored last on failure: Blender 5.x keeps the names of removed attributes.
            undo.append(_colors_restorer(me))
            default_before = me.color_attributes.default_color_name
            data = {options.attribute_name: task.values}
            if options.normalized_name:
                data[options.normalized_name] = task.normalized
            if options.color_name:
                data[options.color_name] = colors
            for name, data_type, domain in options.outputs():
                put_attribute(me, name, data_type, domain, data[name], undo)
            if options.color_name:
                me.color_attributes.active_color = me.color_attributes[options.color_name]
                # The render colour too, where it was ours or none: replacing our attribute
                # of the other domain left bpy 4.5 rendering no colour.
                if default_before in ("", options.color_name):
                    me.color_attributes.default_color_name = options.color_name
            mesh_data.record_outputs(me, options.outputs())
            if options.points == "faces":  # what segmenting may reuse
                mesh_data.record_sdf_settings(
                    me, options.attribute_name, options.sdf_settings(), task.linear
                )
            me.update()
        # Images are made under a temporary name and replace the old ones (same name) only
        # when everything else is written: users of an old image (materials) get the new one.
        for _, task in targets:
            new_images.extend(baking.make_images(bpy_data, task, options))
    except BaseException:
        for image, _ in new_images:
            bpy_data.images.remove(image)
        for take_back in reversed(undo):
            take_back()
        raise
    for image, name in new_images:
        old = bpy_data.images.get((name, None))
        if old is not None:
            old.user_remap(image)
            bpy_data.images.remove(old)
        image.name = name
    return [ob for ob, _ in targets]


def put_attribute(me, name, data_type, domain, data, undo):
    """Writes `data` into the attribute `name` of this type and domain, made (or remade, when
    an earlier run's is on another domain or of another type: checked before) as needed;
    appends to `undo` what takes it back."""
    attribute = me.attributes.get(name)
    if attribute is not None and (attribute.data_type, attribute.domain) != (data_type, domain):
        undo.append(_recreator(me, attribute))
        me.attributes.remove(attribute)
        attribute = None
    if attribute is None:
        attribute = me.attributes.new(name, data_type, domain)
        if attribute is None or attribute.name != name:
            if attribute is not None:
                me.attributes.remove(attribute)
            raise RuntimeError(f"Blender could not create attribute {name!r}")
        undo.append(_remover(me, name))
    else:
        undo.append(_rewriter(me, attribute))
    mesh_data.write_attribute(attribute, data)


def _remover(me, name):
    def take_back():
        me.attributes.remove(me.attributes[name])
        me.update()

    return take_back


def _rewriter(me, attribute):
    name, before = attribute.name, mesh_data.read_attribute(attribute)

    def take_back():
        mesh_data.write_attribute(me.attributes[name], before)
        me.update()

    return take_back


def _recreator(me, attribute):
    """Puts back an attribute about to be removed (at the end of its domain's list)."""
    name, data_type, domain = attribute.name, attribute.data_type, attribute.domain
    before = mesh_data.read_attribute(attribute)

    def take_back():
        mesh_data.write_attribute(me.attributes.new(name, data_type, domain), before)
        me.update()

    return take_back


def _colors_restorer(me):
    colors = me.color_attributes
    before = (colors.active_color_name, colors.default_color_name)

    def take_back():
        colors.active_color_name, colors.default_color_name = before

    return take_back


def _record_restorer(me, name=mesh_data.OUTPUTS_PROPERTY):
    """Puts back (or removes) the custom property `name` as it is now."""
    before = me.get(name)

    def take_back():
        if before is None:
            me.pop(name, None)
        else:
            me[name] = before

    return take_back


def _image_problem(bpy_data, name):
    if len(name.encode("utf-8")) > MAX_NAME_BYTES:
        return f"Image name longer than {MAX_NAME_BYTES} bytes: {name!r}"
    linked = [im for im in bpy_data.images if im.name == name and im.library is not None]
    local = bpy_data.images.get((name, None))
    if linked and local is None:
        return f"Image {name!r} is linked from a library and cannot be replaced"
    return None


class Job:
    """compute() (or `work`, which takes the same arguments) on a worker thread, for a modal
    operator to poll from the main thread."""

    def __init__(self, tasks, options, work=None):
        self.tasks = tasks
        self.options = options
        self._work = work or compute
        self.progress = 0.0
        self.error = None
        self._cancel = threading.Event()
        self._done = threading.Event()
        self._thread = threading.Thread(target=self._run, name="shape_diameter", daemon=True)

    def start(self):
        self._thread.start()
        return self

    def _run(self):
        try:
            self._work(self.tasks, self.options, self._set_progress, self._cancel.is_set)
        except BaseException as ex:  # reported on the main thread
            self.error = ex
        finally:
            self._done.set()

    def _set_progress(self, fraction):
        self.progress = max(self.progress, fraction)  # never backwards, whatever reports it

    @property
    def done(self):
        return self._done.is_set()

    def cancel(self):
        self._cancel.set()

    def wait(self, timeout=None):
        """Waits for the thread to end; True when it has."""
        self._thread.join(timeout)
        return self.done
