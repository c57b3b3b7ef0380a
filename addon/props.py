# SPDX-License-Identifier: GPL-3.0-or-later
"""The run options as Blender properties, defined once and used by the operator and by the
panel's per-scene settings (which the panel's button copies into the operator).

Options that depend on the core (accel, smoothing: compute() keywords; the bake:
shape_diameter.smooth) are drawn only where the core has them (core.supports, core.has).
"""

import inspect
import math

import bpy
from bpy.props import BoolProperty, EnumProperty, FloatProperty, IntProperty, StringProperty

from . import core, process

# Blender keeps only pointers to the strings of dynamic enum items: the lists must stay alive
# (docs.blender.org/api/current/bpy.props.html#bpy.props.EnumProperty, "items" warning).
_engine_items = {}


def engine_choices(with_default):
    """[(key, enum item)] for the engines shape_diameter.engines() lists here, after 'auto'
    (and 'DEFAULT', the preferences' choice, on the operator and the panel); with OpenCL
    devices, 'opencl' (the best of them, whichever machine this is), 'opencl:all' where that
    shares the work between two devices or more, and each device, labelled by its name. Item
    identifiers are what shape_diameter.compute(engine=...) takes, so scripts pass the same
    strings. `key` is what a saved setting keeps: the identifier, but for a device its name
    ('opencl:<device name>', '... #2' for a second device of that name), because a device's
    index changes with the drivers and the devices installed, and 'OPENCL_ALL' for
    'opencl:all'."""
    choices = []  # (key, (identifier, label, description))
    if with_default:
        choices.append(
            ("DEFAULT", ("DEFAULT", "Default", "The engine chosen in the add-on's preferences"))
        )
    choices.append(
        ("auto", ("auto", "Automatic", "The best OpenCL GPU if there is one, else the CPU"))
    )
    engines = core.engines()
    devices = [e for e in engines if str(e["name"]).startswith("opencl:")]
    has_opencl = bool(devices)
    # 'opencl:all' takes every GPU, or every OpenCL device where there is no GPU.
    gpus = sum(1 for e in devices if e.get("type") == "GPU")
    sharing = gpus or len(devices)
    same_name = {}
    for engine in engines:
        name = str(engine["name"])
        if name.startswith("opencl:"):
            device = str(engine.get("device") or name)
            same_name[device] = same_name.get(device, 0) + 1
            label = device if same_name[device] == 1 else f"{device} #{same_name[device]}"
            description = f"OpenCL: {engine.get('description') or device}; engine='{name}'"
            choices.append(("opencl:" + label, (name, label, description)))
            continue
        description = str(engine.get("description") or name)
        if name == "cpu":
            choices.append(("cpu", ("cpu", "CPU", f"The CPU engine, {description}")))
        else:  # an engine a later core adds
            choices.append((name, (name, name, description)))
        if name == "cpu" and has_opencl:
            best = "The fastest OpenCL device here, a GPU before a CPU device; engine='opencl'"
            choices.append(("opencl", ("opencl", "Best OpenCL Device", best)))
            if sharing >= 2:  # 'opencl:all' would use more than one device
                label = "All GPUs" if gpus else "All OpenCL Devices"
                # Its key is no "opencl:<label>": a device named "all" keeps its own.
                shared = (
                    f"{label} at once, sharing the points (the same values as one device); "
                    "engine='opencl:all'"
                )
                choices.append(("OPENCL_ALL", ("opencl:all", label, shared)))
    items = [item for _, item in choices]
    items = _engine_items.setdefault((with_default, tuple(items)), items)
    return [(key, item) for (key, _), item in zip(choices, items)]


def engine_items(with_default):
    """The enum items of engine_choices()."""
    return [item for _, item in engine_choices(with_default)]


def _operator_engine_items(self, context):
    return engine_items(True)


def _plain_engine_items(self, context):
    return engine_items(False)


SAMPLING_ITEMS = (
    (
        "fibonacci",
        "Fibonacci",
        (
            "Spherical Fibonacci directions in the cone, the same set at "
            "every point (paper 4.2); deterministic"
        ),
    ),
    ("random", "Random", "Uniform in the cone, different at each point; reproducible with Seed"),
    (
        "cgal",
        "CGAL",
        "CGAL sdf_values' rules: Vogel disk, equal weights, median absolute deviation outliers",
    ),
)
POINTS_ITEMS = (
    (
        "faces",
        "Faces",
        (
            "One value per face (quads and n-gons: the area-weighted mean of their "
            "triangles); FACE attributes and a CORNER color attribute"
        ),
    ),
    ("vertices", "Vertices", "One value per vertex; POINT attributes"),
)
ORIENTATION_ITEMS = (
    ("auto", "Auto", "Turn inside-out parts and stray reversed faces outward for computing"),
    ("as_is", "As Is", "Trust the faces' winding"),
    ("flip", "Flip", "Reverse every face for computing"),
)
ACCEL_ITEMS = (
    ("bvh", "BVH", "Binned-SAH bounding volume hierarchy"),
    ("octree", "Octree", "The paper's octree (section 4.2)"),
)
SMOOTHING_ITEMS = (
    ("none", "None", "The values as cast"),
    ("kring", "K-Ring", "Gaussian over the rings of neighbouring faces on the mesh"),
    (
        "projected",
        "Projected Points",
        "Points moved inward by half their value, averaged in an octree (paper 4.4)",
    ),
    ("texture", "Texture Space", "Blurred in the UV layout, islands kept apart; needs a UV map"),
)
NORMALIZE_ITEMS = (
    ("linear", "Linear", "(x - min) / (max - min)"),
    (
        "log",
        "Logarithmic",
        "log(4x + 1) / log 5 of the linear value (Shapira et al.), spreads the thin end",
    ),
)


def options():
    """Fresh property definitions of every run option, by name (the scripting names)."""
    return {
        "rays": IntProperty(
            name="Rays",
            description="Rays cast per point (paper: 30)",
            default=30,
            min=1,
            max=1024,
            soft_max=256,
        ),
        "cone_angle": FloatProperty(
            name="Cone Angle",
            description="Full apex angle of the cone of rays (paper: 120°)",
            default=math.radians(120.0),
            min=math.radians(1.0),
            max=math.radians(179.0),
            subtype="ANGLE",
        ),
        "sampling": EnumProperty(
            name="Sampling",
            description="How the rays are spread in the cone",
            items=SAMPLING_ITEMS,
            default="fibonacci",
        ),
        "seed": IntProperty(
            name="Seed",
            description="Seed of the random sampling",
            default=0,
            min=0,
        ),
        "points": EnumProperty(
            name="Points",
            description="Where values are computed",
            items=POINTS_ITEMS,
            default="faces",
        ),
        "normalize": EnumProperty(
            name="Normalize",
            description="How the normalised attribute and the colours map values to [0, 1]",
            items=NORMALIZE_ITEMS,
            default="linear",
        ),
        "orientation": EnumProperty(
            name="Orientation",
            description="Which way faces point for computing (the mesh itself is not changed)",
            items=ORIENTATION_ITEMS,
            default="auto",
        ),
        "accel": EnumProperty(
            name="Acceleration",
            description="The structure rays are traced through",
            items=ACCEL_ITEMS,
            default="bvh",
        ),
        "smoothing": EnumProperty(
            name="Smoothing",
            description="Smoothing of the values after casting (paper 4.4)",
            items=SMOOTHING_ITEMS,
            default="none",
        ),
        "smoothing_rings": IntProperty(
            name="Rings",
            description="K-ring: rings of neighbours averaged (0: chosen from the face count)",
            default=0,
            min=0,
            max=255,
        ),
        "smoothing_iterations": IntProperty(
            name="Iterations",
            description="Projected points: smoothing passes",
            default=1,
            min=1,
            max=100,
        ),
        "smoothing_rule": EnumProperty(
            name="Rule",
            description="Projected points: how far each point gathers",
            items=(
                (
                    "local",
                    "Local",
                    "A sphere of a twentieth of each value over fine cells: "
                    "keeps a clean field, removes some noise",
                ),
                (
                    "paper",
                    "Paper",
                    "The paper's sphere of the whole value: smooths more, "
                    "and moves values across parts of other thicknesses",
                ),
            ),
            default="local",
        ),
        "texture_size": IntProperty(
            name="Resolution",
            description="Size in texels of the texture used by texture smoothing and the bake "
            "(square)",
            default=1024,
            min=process.TEXTURE_SIZE_RANGE[0],
            max=process.TEXTURE_SIZE_RANGE[1],
            soft_max=8192,
        ),
        "texture_radius": FloatProperty(
            name="Radius",
            description="Texture smoothing: blur reach in texels (0: 2 per 256 texels, paper)",
            default=0.0,
            min=process.TEXTURE_RADIUS_RANGE[0],
            max=process.TEXTURE_RADIUS_RANGE[1],
        ),
        "bake_image": BoolProperty(
            name="Bake Image",
            description="Also bake the normalised values into an image through a UV map "
            "(packed into the .blend, replacing an image of the same name)",
            default=False,
        ),
        "uv_map": StringProperty(
            name="UV Map",
            description="The UV map to bake through, and for texture smoothing (empty: the "
            "active UV map)",
            default="",
        ),
        "image_name": StringProperty(
            name="Image",
            description="Name of the baked image; {object} is replaced by the object's name",
            default="{object}_sdf",
        ),
        "bake_depth": EnumProperty(
            name="Floats",
            description="Precision of the baked image, packed as a one-channel OpenEXR file",
            items=[
                ("16", "Half (16-bit)", "Half floats: 3 significant digits, half the size"),
                ("32", "Full (32-bit)", "32-bit floats: the values as computed"),
            ],
            default="16",
        ),
        "bake_tiles": EnumProperty(
            name="UDIM Tiles",
            description="What a bake of UVs on several UDIM tiles makes",
            items=[
                ("IMAGES", "Image per Tile", "One image per tile: NAME, NAME.1002, ..."),
                ("TILED", "Tiled Image", "One UDIM tiled image NAME holding every tile"),
            ],
            default="IMAGES",
        ),
        "attribute_name": StringProperty(
            name="Attribute",
            description="FLOAT attribute for the values, in mesh (or world) units",
            default="sdf",
        ),
        "normalized_name": StringProperty(
            name="Normalized",
            description="FLOAT attribute for the normalised values in [0, 1], each object "
            "to its own range (empty: not written)",
            default="sdf_normalized",
        ),
        "color_name": StringProperty(
            name="Color",
            description="Color attribute from a perceptual colour map of the "
            "normalised values, made active (empty: not written)",
            default="sdf_color",
        ),
        "use_modifiers": BoolProperty(
            name="Use Modifiers",
            description="Compute on the mesh as the modifiers and shape "
            "keys leave it; written back only when they keep its topology (deforming modifiers)",
            default=False,
        ),
        "apply_scale": BoolProperty(
            name="Apply Object Scale",
            description="Values in world units: the object's scale "
            "and rotation are applied before computing",
            default=True,
        ),
    }


SEGMENT_MODE_ITEMS = (
    (
        "auto",
        "Auto",
        "Graph cut run until no move lowers its energy (a lower energy than CGAL's)",
    ),
    ("cgal", "CGAL", "CGAL's segmentation_from_sdf_values exactly (its graph cut's first move)"),
)


def segment_options():
    """Fresh property definitions of the segmentation options, by name (the scripting names,
    segmenting.SegmentOptions' fields)."""
    return {
        "clusters": IntProperty(
            name="Clusters",
            description="Levels of thickness the faces are grouped into (CGAL: 5); each "
            "connected piece of a level is a part",
            default=5,
            min=1,
            max=256,
            soft_max=16,
        ),
        "smoothness": FloatProperty(
            name="Smoothness",
            description="How dear it is to cut between faces (CGAL's lambda, 0.26): higher "
            "gives fewer, rounder parts cut along creases",
            default=0.26,
            min=0.0,
            soft_max=2.0,
        ),
        "segments": IntProperty(
            name="Number of Parts",
            description="The parts wanted: clusters 2-9 and the smoothness are searched for "
            "that many, the nearest count kept (0: the clusters decide)",
            default=0,
            min=0,
            max=4096,
            soft_max=32,
        ),
        "mode": EnumProperty(
            name="Mode", description="The graph cut", items=SEGMENT_MODE_ITEMS, default="auto"
        ),
        "min_part_area": FloatProperty(
            name="Minimum Part Size",
            description="Parts smaller than this share of the mesh's area join the neighbour "
            "they share the longest boundary with (0: off); a separate piece of the mesh stays "
            "a part of its own",
            default=0.0,
            min=0.0,
            max=0.99,
            soft_max=0.1,
            step=0.1,
            precision=3,
            subtype="FACTOR",
        ),
        "reuse_values": BoolProperty(
            name="Reuse SDF Values",
            description="Segment the SDF attribute already on a mesh when Compute wrote it per "
            "face with these settings on this geometry, instead of computing it again",
            default=True,
        ),
        "face_sets": BoolProperty(
            name="Face Sets",
            description="Sculpt Mode's face sets, one per part (ids from 1)",
            default=True,
        ),
        "label_name": StringProperty(
            name="Part Attribute",
            description="INT face attribute with each polygon's part, from 0 (empty: not written)",
            default="segment",
        ),
        "segment_color_name": StringProperty(
            name="Part Colors",
            description="Color attribute with one colour per part, made active (empty: not "
            "written)",
            default="segment_color",
        ),
        "vertex_groups": BoolProperty(
            name="Vertex Groups",
            description="One vertex group per part (the armature needs them)",
            default=True,
        ),
        "group_prefix": StringProperty(
            name="Prefix",
            description="Vertex groups, bones and materials are named prefix + number: "
            "part_01, part_02, ...",
            default="part_",
        ),
        "soft_weights": BoolProperty(
            name="Soft Weights",
            description="Weights that fall off smoothly across the boundaries between parts "
            "(else 1 inside each part)",
            default=True,
        ),
        "materials": BoolProperty(
            name="Material Slots",
            description="Replace the mesh's material slots by one material per part",
            default=False,
        ),
        "armature": BoolProperty(
            name="Proto-Skeleton",
            description="An armature parented to the mesh, one bone per part along its main "
            "axis, joined where parts meet, deforming the mesh through the vertex groups",
            default=True,
        ),
        "armature_name": StringProperty(
            name="Armature",
            description="Name of the armature object; {object} is replaced by the mesh "
            "object's name",
            default="{object}_parts",
        ),
    }


def with_segment_options(cls):
    """Class decorator: adds the segmentation options to the class's annotations."""
    annotations = dict(inspect.get_annotations(cls))
    annotations.update(segment_options())
    cls.__annotations__ = annotations
    return cls


def segment_operator_options(cls):
    """An operator's SDF and segmentation options, starting from the defaults at every call."""
    operator_options(cls)
    with_segment_options(cls)
    cls.__annotations__ = {
        name: _skip_save(prop) if name in segment_options() else prop
        for name, prop in cls.__annotations__.items()
    }
    return cls


def copy_segment_options(source, target):
    copy_options(source, target)
    for name in segment_options():
        setattr(target, name, getattr(source, name))


def segment_option_values(holder):
    values = option_values(holder)
    values.update({name: getattr(holder, name) for name in segment_options()})
    return values


def engine_property():
    return EnumProperty(
        name="Engine",
        description="What casts the rays",
        items=_operator_engine_items,
    )


def stored_engine_property(store, with_default, description):
    """An engine enum kept by key (engine_choices) in the string property `store`: a dynamic
    enum saves an index, which would point at another engine on a machine with other
    devices, and so would a device's 'opencl:<index>'. A device found again under another
    index reads as that index; an engine that is not available here reads as the first item
    (Default, or Automatic), never as another device."""

    def items(self, context):
        return engine_items(with_default)

    def get(self):
        stored = getattr(self, store)
        choices = engine_choices(with_default)
        for index, (key, _) in enumerate(choices):
            if key == stored:
                return index
        return 0

    def set(self, value):
        setattr(self, store, engine_choices(with_default)[value][0])

    return EnumProperty(name="Engine", description=description, items=items, get=get, set=set)


def _skip_save(prop):
    """The same property definition with SKIP_SAVE: an operator then starts from the defaults
    every time instead of the previous call's values (a script's bpy.ops call that left out
    orientation='flip' still flipped). The panel passes every option."""
    keywords = dict(prop.keywords)
    keywords["options"] = set(keywords.get("options", set())) | {"SKIP_SAVE"}
    return prop.function(**keywords)


def with_options(cls, engine=None):
    """Class decorator: adds every option (and the engine) to the class's annotations."""
    annotations = dict(inspect.get_annotations(cls))
    annotations.update(options())
    annotations["engine"] = engine or engine_property()
    cls.__annotations__ = annotations
    return cls


def operator_options(cls):
    """with_options for an operator: its options start from the defaults at every call."""
    with_options(cls)
    cls.__annotations__ = {
        name: _skip_save(prop) if name in (*options(), "engine") else prop
        for name, prop in cls.__annotations__.items()
    }
    return cls


def copy_options(source, target):
    """Copies every option from one property holder to another (the panel's settings into
    the operator it runs)."""
    for name in (*options(), "engine"):
        setattr(target, name, getattr(source, name))


def option_values(holder):
    """{name: value} of the options on a property holder; the cone angle in degrees, as
    shape_diameter.compute wants it."""
    values = {name: getattr(holder, name) for name in options()}
    values["cone_angle"] = math.degrees(values["cone_angle"])
    values["engine"] = holder.engine
    return values


class ShapeDiameterSettings(bpy.types.PropertyGroup):
    """The panel's settings, per scene (saved with the .blend)."""

    engine_name: StringProperty(default="DEFAULT", options={"HIDDEN"})


with_options(
    ShapeDiameterSettings,
    engine=stored_engine_property("engine_name", True, "What casts the rays"),
)
with_segment_options(ShapeDiameterSettings)


classes = (ShapeDiameterSettings,)


def register():
    for cls in classes:
        bpy.utils.register_class(cls)
    bpy.types.Scene.shape_diameter = bpy.props.PointerProperty(type=ShapeDiameterSettings)


def unregister():
    del bpy.types.Scene.shape_diameter
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
