# SPDX-License-Identifier: GPL-3.0-or-later
"""Writing a segmentation's outputs into Blender, for a mesh of about a million polygons, with
the extension's writers (numpy foreach_set, vertex groups one vg.add per group and weight
level) against the per-element Python loop they replace, in one run, in real Blender (bpy from
PyPI):

    scripts/build_extension.sh
    .venv-bpy45/bin/python bench/blender_segment_outputs.py [dist/shape_diameter-...zip]
        [--rings 1000] [--sides 1000] [--balls 5] [--rounds 3]

The mesh is a chain of balls joined by necks, revolved around the x axis: rings x sides quads
(1M by default) and two triangle fans. Its SDF is known without casting a ray (twice the
radius of revolution at each face), so the segmentation (shape_diameter.segment, 2 balls +
necks ...) comes from those values and only the writing is timed. Prints a table: output,
best seconds of `rounds` (each run replaces the previous one's outputs, as a second click
does), and for the vertex groups and the face sets the per-element loop's seconds, measured
on a slice and scaled to the whole mesh (a full loop takes minutes).
"""

import argparse
import sys
import time

from blender_addon import install, newest_zip  # before bpy: it gives bpy a user folder

# isort: split
import bpy
import numpy as np


def arguments():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("zip", nargs="?", default=newest_zip())
    parser.add_argument("--rings", type=int, default=1000)
    parser.add_argument("--sides", type=int, default=1000)
    parser.add_argument("--balls", type=int, default=5)
    parser.add_argument("--rounds", type=int, default=3)
    return parser.parse_args()


def chain(rings, sides, balls):
    """(vertices, quads and fans as one polygon list, per-triangle values are made later):
    radius r(x) = max(ball, neck) around the x axis, balls of radius 1 every 3 units."""
    length = 3.0 * balls - 1.0
    x = np.linspace(0.01, length - 0.01, rings)
    centres = 1.0 + 3.0 * np.arange(balls)
    nearest = np.min(np.abs(x[:, None] - centres[None, :]), axis=1)
    radius = np.maximum(np.sqrt(np.clip(1.0 - nearest**2, 0.0, None)), 0.25)
    theta = np.linspace(0.0, 2 * np.pi, sides, endpoint=False)
    ring = np.stack(
        [
            np.repeat(x, sides),
            np.outer(radius, np.cos(theta)).ravel(),
            np.outer(radius, np.sin(theta)).ravel(),
        ],
        axis=1,
    )
    vertices = np.vstack([[0.0, 0.0, 0.0], ring, [length, 0.0, 0.0]])
    i = np.arange(rings - 1)[:, None]
    j = np.arange(sides)[None, :]
    a = 1 + i * sides + j
    b = 1 + i * sides + (j + 1) % sides
    quads = np.stack([a, b, b + sides, a + sides], axis=-1).reshape(-1, 4)
    last = len(vertices) - 1
    base = 1 + (rings - 1) * sides
    js = np.arange(sides)
    first_fan = np.stack([np.zeros(sides, int), 1 + (js + 1) % sides, 1 + js], 1)
    last_fan = np.stack([np.full(sides, last), base + js, base + (js + 1) % sides], 1)
    return vertices, quads, np.vstack([first_fan, last_fan])


def new_mesh(vertices, quads, fans):
    """A Blender mesh from numpy with foreach_set (from_pydata on a million faces takes long)."""
    me = bpy.data.meshes.new("chain")
    me.vertices.add(len(vertices))
    me.vertices.foreach_set("co", vertices.astype(np.float32).ravel())
    corners = np.concatenate([quads.ravel(), fans.ravel()]).astype(np.int32)
    sizes = np.concatenate([np.full(len(quads), 4), np.full(len(fans), 3)]).astype(np.int32)
    me.loops.add(len(corners))
    me.loops.foreach_set("vertex_index", corners)
    me.polygons.add(len(sizes))
    starts = np.concatenate([[0], np.cumsum(sizes)[:-1]]).astype(np.int32)
    me.polygons.foreach_set("loop_start", starts)
    me.update(calc_edges=True)
    ob = bpy.data.objects.new("chain", me)
    bpy.context.scene.collection.objects.link(ob)
    bpy.context.view_layer.objects.active = ob
    ob.select_set(True)
    return ob


def segmented(modules, ob):
    """The object's PartsTask, segmented from its exact SDF (twice the radius of revolution)."""
    segmenting = modules["segmenting"]
    # The values are exact: they need no filtering, which segment() skips for values the SDF's
    # own smoothing made (any smoothing option says so; no SDF is computed here).
    options = segmenting.SegmentOptions.from_keywords(clusters=2, smoothing="kring")
    (part,), _ = segmenting.prepare(bpy.context.evaluated_depsgraph_get(), [ob], options)
    mesh = part.task.mesh
    centre = mesh.vertices[mesh.triangles].mean(axis=1)
    part.values = 2.0 * np.hypot(centre[:, 1], centre[:, 2])
    started = time.perf_counter()
    segmenting.compute([part], options)
    return part, time.perf_counter() - started


# Outputs written alone, then all together: the keywords of SegmentOptions.
NONE = dict(
    face_sets=False,
    label_name="",
    segment_color_name="",
    vertex_groups=False,
    materials=False,
    armature=False,
)
CASES = [
    ("face sets", dict(NONE, face_sets=True)),
    ("part attribute (INT per face)", dict(NONE, label_name="segment")),
    ("part colours (per corner)", dict(NONE, segment_color_name="segment_color")),
    ("vertex groups, hard", dict(NONE, vertex_groups=True, soft_weights=False)),
    ("vertex groups, soft", dict(NONE, vertex_groups=True)),
    ("material slots", dict(NONE, materials=True)),
    ("proto-skeleton (+ groups)", dict(NONE, armature=True)),
    ("everything (defaults + materials)", dict(materials=True)),
]


def time_writes(modules, part, rounds):
    segmenting, part_writing = modules["segmenting"], modules["part_writing"]
    rows = []
    for label, keywords in CASES:
        options = segmenting.SegmentOptions.from_keywords(clusters=2, **keywords)
        best = float("inf")
        for _ in range(rounds):
            started = time.perf_counter()
            part_writing.write(bpy.context, [part], options)
            best = min(best, time.perf_counter() - started)
        rows.append((label, best))
    return rows


def loop_groups(ob, weights, vertices):
    """The per-vertex loop: one vg.add per vertex and segment, on vertices [0, vertices)."""
    groups = [
        ob.vertex_groups.new(name=f"loop_{i}") for i in range(int(weights.segments.max()) + 1)
    ]
    started = time.perf_counter()
    for v in range(vertices):
        for k in range(weights.offsets[v], weights.offsets[v + 1]):
            groups[weights.segments[k]].add([v], float(weights.weights[k]), "REPLACE")
    seconds = time.perf_counter() - started
    for group in groups:
        ob.vertex_groups.remove(group)
    return seconds


def loop_face_sets(me, labels, polygons):
    """The per-polygon loop: attribute.data[i].value = ..., on polygons [0, polygons)."""
    attribute = me.attributes.new("loop_face_sets", "INT", "FACE")
    data = attribute.data
    started = time.perf_counter()
    for i in range(polygons):
        data[i].value = int(labels[i]) + 1
    seconds = time.perf_counter() - started
    me.attributes.remove(me.attributes["loop_face_sets"])
    return seconds


def main():
    args = arguments()
    if not args.zip:
        sys.exit("no extension zip: run scripts/build_extension.sh first")
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    modules = install(args.zip, ("segmenting", "part_writing", "process"))
    started = time.perf_counter()
    ob = new_mesh(*chain(args.rings, args.sides, args.balls))
    made = time.perf_counter() - started
    me = ob.data
    part, segmenting_seconds = segmented(modules, ob)
    seg = part.segmentation
    print(
        f"bpy {bpy.app.version_string}; mesh: {len(me.polygons)} polygons, {len(me.vertices)} "
        f"vertices, {len(part.task.mesh.triangles)} triangles (made in {made:.2f} s); "
        f"{seg.segment_count} parts (segment() from the exact SDF: {segmenting_seconds:.2f} s)"
    )
    rows = time_writes(modules, part, args.rounds)
    slice_vertices = min(len(me.vertices), 50_000)
    slice_polygons = min(len(me.polygons), 100_000)
    loop_g = loop_groups(ob, seg.vertex_weights, slice_vertices) * len(me.vertices) / slice_vertices
    loop_f = (
        loop_face_sets(me, part.polygon_labels, slice_polygons) * len(me.polygons) / slice_polygons
    )
    baseline = {"vertex groups, soft": loop_g, "face sets": loop_f}
    print(f"\n{'output':36s} {'seconds':>8s} {'loop s':>8s} {'ratio':>7s}")
    for label, seconds in rows:
        loop = baseline.get(label)
        extra = f" {loop:8.2f} {loop / seconds:6.0f}x" if loop else ""
        print(f"{label:36s} {seconds:8.3f}{extra}")
    print(
        f"\nloop s: per-element Python loop, measured on {slice_vertices} vertices / "
        f"{slice_polygons} polygons and scaled to the whole mesh. Target: everything < 1 s."
    )


if __name__ == "__main__":
    main()
