# SPDX-License-Identifier: GPL-3.0-or-later
"""One segmentation run on Blender objects, in the three steps of process.py:

prepare()  main thread: process.prepare's checks and mesh reading, the outputs' names
           checked against what is on each object, SDF values already on a mesh taken
           when they were computed with the same settings on the same geometry.
compute()  any thread, no bpy: the SDF where needed, shape_diameter.segment, labels per
           polygon, colours, the proto-skeleton (shape_diameter.rigging).
write()    main thread: every output of every object, all or none.
"""

import re
import time
from dataclasses import dataclass, field, fields

import bpy
import numpy as np

from . import armature, core, mesh_data, part_outputs, process

UserError = process.UserError
Cancelled = process.Cancelled
MODES = ("auto", "cgal")
# Each mesh's share of the progress: the SDF (where it is computed), then the segmentation
# (which polls for a cancel as it goes), then the parts' outputs.
SDF_END, SEGMENT_END = 0.8, 0.95


@dataclass
class SegmentOptions:
    """What a segmentation run does: segment()'s options, the outputs (an empty name or
    False: not written), and the SDF's options (process.Options, faces) for meshes without
    reusable values."""

    clusters: int = 5
    smoothness: float = 0.26
    mode: str = "auto"
    min_part_area: float = 0.0
    segments: int = 0  # the parts wanted; 0: the clusters decide
    reuse_values: bool = True
    face_sets: bool = True
    label_name: str = "segment"
    segment_color_name: str = "segment_color"
    vertex_groups: bool = True
    group_prefix: str = "part_"
    soft_weights: bool = True
    materials: bool = False
    armature: bool = True
    armature_name: str = "{object}_parts"
    sdf: process.Options = field(default_factory=process.Options)

    @classmethod
    def from_keywords(cls, **keywords):
        """Segmentation keywords (the fields) and any SDF option (process.Options')."""
        own = {f.name for f in fields(cls)} - {"sdf"}
        sdf = process.Options.from_keywords(**{k: v for k, v in keywords.items() if k not in own})
        sdf.points = "faces"
        return cls(**{k: v for k, v in keywords.items() if k in own}, sdf=sdf)

    def segment_options(self):
        """segment()'s keywords. CGAL's bilateral filter (postprocess) is part of segmenting
        values as cast; values the SDF's own smoothing already smoothed are taken as they
        are."""
        return {
            "clusters": self.clusters,
            "smoothness": self.smoothness,
            "mode": self.mode,
            "min_part_area": self.min_part_area,
            "segments": self.segments or None,
            "postprocess": self.sdf.smoothing == "none",
        }

    def attribute_outputs(self):
        """[(name, data_type, domain)] of the attributes written."""
        out = [(part_outputs.FACE_SETS, "INT", "FACE")] if self.face_sets else []
        if self.label_name:
            out.append((self.label_name, "INT", "FACE"))
        if self.segment_color_name:
            out.append((self.segment_color_name, "FLOAT_COLOR", "CORNER"))
        return out

    def check(self):
        count = self.clusters
        if isinstance(count, bool) or not isinstance(count, (int, np.integer)) or count < 1:
            raise UserError(f"clusters must be an integer >= 1, got {count!r}")
        if not isinstance(self.smoothness, (int, float)) or not self.smoothness >= 0.0:
            raise UserError(f"smoothness must be a number >= 0, got {self.smoothness!r}")
        if self.mode not in MODES:
            raise UserError(f"mode must be one of {MODES}, got {self.mode!r}")
        share = self.min_part_area
        if isinstance(share, bool) or not isinstance(share, (int, float)) or not 0 <= share < 1:
            raise UserError(f"min_part_area must be a share in [0, 1) (0.01: 1%), got {share!r}")
        wanted = self.segments
        integer = not isinstance(wanted, bool) and isinstance(wanted, (int, np.integer))
        if not integer or not 0 <= wanted <= 4096:
            raise UserError(f"segments must be an integer in [0, 4096] (0: off), got {wanted!r}")
        names = [name for name, _, _ in self.attribute_outputs()]
        for name in names[1:] if self.face_sets else names:
            if name.startswith("."):
                raise UserError(f"Attribute names starting with '.' are Blender's own: {name!r}")
        for name in names:
            if len(name.encode("utf-8")) > process.MAX_NAME_BYTES:
                raise UserError(f"Name longer than {process.MAX_NAME_BYTES} bytes: {name!r}")
        if len(set(names)) != len(names):
            raise UserError(f"The output attribute names must differ: {', '.join(names)}")
        if (self.vertex_groups or self.armature) and not self.group_prefix.strip():
            raise UserError("The vertex group prefix is empty")
        if self.armature and not self.armature_name.strip():
            raise UserError("The armature name is empty")
        if not (names or self.vertex_groups or self.materials or self.armature):
            raise UserError("No output chosen: nothing would be written")

    @property
    def writes_groups(self):
        """The armature deforms through the groups: it needs them."""
        return self.vertex_groups or self.armature


@dataclass
class PartsTask:
    """One mesh to segment: process.Task (its triangles, found again by uid) and the results."""

    task: process.Task
    values: np.ndarray = None  # float64 per triangle, when taken from the mesh
    reused: bool = False
    segmentation: object = None  # shape_diameter.Segmentation
    polygon_labels: np.ndarray = None  # int32 per polygon
    polygon_colors: np.ndarray = None  # float32 (polygons, 4) sRGB
    skeleton: object = None  # shape_diameter.rigging.Skeleton, mesh coordinates
    timings: dict = field(default_factory=dict)

    @property
    def object_name(self):
        return self.task.object_name

    @property
    def warnings(self):
        return self.task.warnings


def _group_pattern(prefix):
    return re.compile(re.escape(prefix) + r"[0-9]{2,}$")


def names_problem(ob, options, count=None):
    """Why the outputs cannot be written on `ob`, or None: an attribute, vertex group,
    material or object of an output's name that this add-on did not write. Before computing,
    groups are checked by pattern (prefix and digits); after, by the exact names."""
    me = ob.data
    record = part_outputs.object_record(ob)
    for name, _, _ in options.attribute_outputs():
        existing = me.attributes.get(name)
        if existing is not None and not mesh_data.is_written_output(me, existing):
            what = "face sets" if name == part_outputs.FACE_SETS else f"attribute {name!r}"
            return (
                f"{ob.name}: its mesh has {what} ({existing.data_type} on {existing.domain}) "
                "not written by Shape Diameter: rename or remove it, or choose another output"
            )
        if ob.vertex_groups.get(name) is not None:
            return f"{ob.name}: a vertex group is named {name!r}, as an output attribute"
    ours = set(record.get("groups", []))
    if options.writes_groups:
        if count is None:
            pattern = _group_pattern(options.group_prefix)
            taken = [g.name for g in ob.vertex_groups if pattern.match(g.name)]
        else:
            taken = [
                n
                for n in part_outputs.part_names(options.group_prefix, count)
                if ob.vertex_groups.get(n) is not None or me.attributes.get(n) is not None
            ]
        foreign = [name for name in taken if name not in ours]
        if foreign:
            return (
                f"{ob.name}: vertex groups {', '.join(map(repr, foreign[:5]))} were not written "
                "by Shape Diameter: rename them, or choose another group prefix"
            )
    if options.armature:
        name = options.armature_name.replace("{object}", ob.name)
        existing = bpy.data.objects.get((name, None))
        if existing is not None and not (
            existing.get(armature.MARK) and record.get("armature") == name
        ):
            return (
                f"{ob.name}: an object is named {name!r} and was not made by Shape Diameter "
                "for it: rename it, or choose another armature name"
            )
    if options.materials and count is not None:
        for name in part_outputs.part_names(options.group_prefix, count):
            material = bpy.data.materials.get((name, None))
            if material is not None and not material.get(part_outputs.MATERIAL_MARK):
                return (
                    f"{ob.name}: material {name!r} was not made by Shape Diameter: rename it, "
                    "or choose another group prefix"
                )
    return None


def _reusable_values(ob, task, options):
    """float64 per triangle: the SDF attribute on the mesh, where the record says it was
    computed per face with these settings, this transform and this geometry; else None."""
    me = ob.data
    record = mesh_data.recorded_sdf(me)
    if record is None or record["settings"] != options.sdf.sdf_settings():
        return None
    if record["linear"] is None:
        if task.linear is not None:
            return None
    elif task.linear is None or not np.allclose(record["linear"], task.linear, rtol=1e-6):
        return None
    attribute = me.attributes.get(record["attribute"])
    if attribute is None or (attribute.data_type, attribute.domain) != ("FLOAT", "FACE"):
        return None
    if not mesh_data.is_written_output(me, attribute):
        return None
    if record["geometry"] != mesh_data.geometry_digest(me):
        return None
    per_polygon = mesh_data.read_attribute(attribute).astype(np.float64)
    return per_polygon[task.mesh.triangle_polygons]


def prepare(depsgraph, objects, options, active=None):
    """PartsTasks for the mesh objects among `objects`, and the warnings about the run.
    Raises UserError, having changed nothing, when the run cannot go ahead."""
    options.check()
    options.sdf.check_values()
    tasks, notices = process.prepare(
        depsgraph, objects, options.sdf, for_writing=False, active=active
    )
    parts = []
    for task in tasks:
        ob = process._find_object(bpy.data, task.object_uid)
        problem = process._editable_problem(ob) or names_problem(ob, options)
        if problem:
            raise UserError(problem)
        values = _reusable_values(ob, task, options) if options.reuse_values else None
        parts.append(PartsTask(task, values=values, reused=values is not None))
    return parts, notices


def compute(parts, options, progress=None, cancelled=None):
    """The SDF (where not reused) and the segmentation of every task; no bpy."""
    total = float(sum(len(p.task.mesh.triangles) for p in parts)) or 1.0
    done = 0.0
    rig = core.rigging()
    for part in parts:
        mesh = part.task.mesh
        share = len(mesh.triangles) / total

        def step(fraction, done=done, share=share):
            if cancelled is not None and cancelled():
                raise Cancelled()
            if progress is not None:
                progress(done + share * fraction)

        step(0.0)
        started = time.perf_counter()
        values = part.values
        segment_start = 0.0 if values is not None else SDF_END
        if values is None:
            try:
                with core.collect_warnings() as caught:
                    result = core.compute(
                        mesh.vertices,
                        mesh.triangles,
                        options.sdf.compute_options(),
                        lambda f: step(SDF_END * f),
                    )
            except ValueError as ex:
                raise UserError(f"{part.object_name}: {ex}") from ex
            part.warnings.extend(f"{part.object_name}: {m}" for m in caught)
            values = result.values
            part.timings["sdf"] = time.perf_counter() - started
        step(segment_start)
        with core.collect_warnings() as caught:
            seg = core.segment(
                mesh.vertices,
                mesh.triangles,
                values,
                options.segment_options(),
                lambda f, start=segment_start: step(start + (SEGMENT_END - start) * f),
            )
        part.warnings.extend(f"{part.object_name}: {m}" for m in caught)
        step(SEGMENT_END)
        part.segmentation = seg
        areas = rig.triangle_areas(mesh.vertices, mesh.triangles)
        part.polygon_labels = rig.polygon_labels(
            seg.labels, mesh.triangle_polygons, areas, part.task.topology.polygon_count
        )
        part.polygon_colors = core.segment_colors(part.polygon_labels)
        if options.armature:
            part.skeleton = _local_skeleton(rig, mesh, seg, part.task.linear)
        part.timings.update({f"segment_{k}": v for k, v in seg.timings.items()})
        part.timings["total"] = time.perf_counter() - started
        done += share
    if progress is not None:
        progress(1.0)
    return parts


def _local_skeleton(rig, mesh, seg, linear):
    """The proto-skeleton in the mesh's own coordinates (the segmentation ran on vertices
    through the object's 3x3 transform; a bone in the mesh's space follows the object)."""
    skeleton = rig.proto_skeleton(
        mesh.vertices,
        mesh.triangles,
        seg.labels,
        seg.segment_count,
        seg.boundaries,
        seg.segment_area,
    )
    if linear is not None:
        inverse = np.linalg.inv(np.asarray(linear, dtype=np.float64)).T
        skeleton.head = skeleton.head @ inverse
        skeleton.tail = skeleton.tail @ inverse
    return skeleton
