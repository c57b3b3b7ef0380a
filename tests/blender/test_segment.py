# SPDX-License-Identifier: GPL-3.0-or-later
"""Segment by Thickness inside real Blender: face sets, the part attribute and colours, vertex
groups and the proto-skeleton on a dumbbell of quads and on a human from the Princeton
Segmentation Benchmark (tests/data/psb/1.off), checked against shape_diameter.segment on
Blender's own triangles; the armature deforms the mesh; failures and undo change nothing."""

import bpy
import numpy as np
import pytest
import shape_diameter
import shape_diameter.colormap
from helpers import DATA, addon_module, select_only, snapshot_all, world_triangles
from modal_stand_in import defaults, event, stand_in

BALL, NECK, CENTRE = 1.0, 0.25, 1.6  # ball radius, neck radius, ball centres at x = +-CENTRE


def dumbbell(name="dumbbell", sides=32, rings=80):
    """Two balls of radius 1 joined by a neck of radius 0.25 around the x axis: quads between
    rings, triangle fans at the poles (a mesh of quads and triangles, as modellers make)."""
    x = np.linspace(-CENTRE - BALL + 0.02, CENTRE + BALL - 0.02, rings)
    radius = np.maximum(np.sqrt(np.clip(BALL**2 - (np.abs(x) - CENTRE) ** 2, 0, None)), NECK)
    theta = np.linspace(0.0, 2 * np.pi, sides, endpoint=False)
    ring = np.stack(
        [
            np.repeat(x, sides),
            np.outer(radius, np.cos(theta)).ravel(),
            np.outer(radius, np.sin(theta)).ravel(),
        ],
        axis=1,
    )
    vertices = np.vstack([[-CENTRE - BALL, 0, 0], ring, [CENTRE + BALL, 0, 0]])
    last = len(vertices) - 1
    faces = []
    for j in range(sides):
        jn = (j + 1) % sides
        faces.append((0, 1 + jn, 1 + j))
        for i in range(rings - 1):
            a, b = 1 + i * sides + j, 1 + i * sides + jn
            faces.append((a, b, b + sides, a + sides))
        base = 1 + (rings - 1) * sides
        faces.append((last, base + j, base + jn))
    return new_object(name, vertices, faces)


def new_object(name, vertices, faces):
    me = bpy.data.meshes.new(name)
    me.from_pydata([tuple(v) for v in vertices], [], [tuple(f) for f in faces])
    me.update()
    ob = bpy.data.objects.new(name, me)
    bpy.context.scene.collection.objects.link(ob)
    select_only(ob)
    return ob


def character():
    """The human of the Princeton Segmentation Benchmark (mesh 1), 15k triangles."""
    words = (DATA / "psb" / "1.off").read_text().split()
    n, m = int(words[1]), int(words[2])
    vertices = np.array(words[4 : 4 + 3 * n], dtype=float).reshape(n, 3)
    faces = np.array(words[4 + 3 * n : 4 + 3 * n + 4 * m], dtype=int).reshape(m, 4)[:, 1:]
    return new_object("human", vertices, faces)


def reference(ob, **options):
    """(labels per polygon, segmentation) from the package directly: the SDF and segment()
    on Blender's triangles, each polygon the label of its largest area (written here with a
    loop, apart from the add-on's numpy)."""
    v, t, p = world_triangles(ob)
    values = shape_diameter.compute(v, t).values
    seg = shape_diameter.segment(v, t, values, postprocess=True, **options)
    area = 0.5 * np.linalg.norm(np.cross(v[t[:, 1]] - v[t[:, 0]], v[t[:, 2]] - v[t[:, 0]]), axis=1)
    best = {}
    for polygon, label, a in zip(p.tolist(), seg.labels.tolist(), area.tolist()):
        sums = best.setdefault(polygon, {})
        sums[label] = sums.get(label, 0.0) + a
    labels = np.array([min(best[i], key=lambda k: (-best[i][k], k)) for i in range(len(best))])
    return labels, seg


def face_ints(me, name):
    out = np.empty(len(me.polygons), dtype=np.int32)
    me.attributes[name].data.foreach_get("value", out)
    return out


def group_weights(ob):
    """{group name: {vertex: weight}} (a loop: test meshes are small)."""
    names = {g.index: g.name for g in ob.vertex_groups}
    out = {name: {} for name in names.values()}
    for v in ob.data.vertices:
        for g in v.groups:
            out[names[g.group]][v.index] = g.weight
    return out


def state():
    """Every mesh byte for byte, and the objects, groups, modifiers and materials."""
    objects = {
        ob.name: (
            ob.type,
            [g.name for g in ob.vertex_groups],
            [m.name for m in ob.modifiers],
            ob.parent.name if ob.parent else None,
        )
        for ob in bpy.data.objects
    }
    weights = {ob.name: group_weights(ob) for ob in bpy.data.objects if ob.type == "MESH"}
    return (
        snapshot_all(),
        objects,
        weights,
        sorted(bpy.data.materials.keys()),
        len(bpy.data.armatures),
    )


def check_outputs(ob, result, labels, seg):
    me = ob.data
    count = seg.segment_count
    names = [f"part_{i + 1:02d}" for i in range(count)]
    assert result.segment_count == count
    np.testing.assert_array_equal(result.labels, labels)
    np.testing.assert_array_equal(face_ints(me, ".sculpt_face_set"), labels + 1)
    np.testing.assert_array_equal(face_ints(me, "segment"), labels)
    colors = me.attributes["segment_color"]
    assert (colors.data_type, colors.domain) == ("FLOAT_COLOR", "CORNER")
    assert me.color_attributes.active_color_name == "segment_color"
    rgba = np.empty(len(me.loops) * 4, dtype=np.float32)
    colors.data.foreach_get("color_srgb", rgba)  # Blender's own conversion from linear
    per_corner = rgba.reshape(-1, 4)
    first_corner = np.empty(len(me.polygons), dtype=np.int32)
    me.polygons.foreach_get("loop_start", first_corner)
    palette = shape_diameter.colormap.segment_colors(np.arange(count)) / 255.0
    np.testing.assert_allclose(per_corner[first_corner], palette[labels], atol=1 / 255)
    assert [g.name for g in ob.vertex_groups] == names
    arm = bpy.data.objects[f"{ob.name}_parts"]
    assert arm.type == "ARMATURE" and arm.parent == ob and result.armature == arm.name
    assert sorted(b.name for b in arm.data.bones) == names
    modifier = [m for m in ob.modifiers if m.type == "ARMATURE"]
    assert len(modifier) == 1 and modifier[0].object == arm


def test_dumbbell_gives_three_parts_everywhere():
    api = addon_module("api")
    ob = dumbbell()
    labels, seg = reference(ob, clusters=2)
    assert seg.segment_count == 3  # two balls and the neck
    result = api.segment_object(ob, clusters=2)
    check_outputs(ob, result, labels, seg)
    # The neck (the thinnest: part_01) joins both balls: a chain of three bones.
    bones = bpy.data.objects["dumbbell_parts"].data.bones
    roots = [b for b in bones if b.parent is None]
    assert len(roots) == 1 and roots[0].name != "part_01"
    assert bones["part_01"].parent == roots[0]
    # Joints at the necks: x = +-(CENTRE - sqrt(BALL^2 - NECK^2)), on the axis.
    neck_x = CENTRE - np.sqrt(BALL**2 - NECK**2)
    head = np.array(bones["part_01"].head_local)
    assert abs(abs(head[0]) - neck_x) < 0.1 and np.hypot(head[1], head[2]) < 0.02
    # Hard weights: each vertex in the group of its part, weight 1.
    api.segment_object(ob, clusters=2, soft_weights=False)
    weights = group_weights(ob)
    members = sum(len(w) for w in weights.values())
    assert members == len(ob.data.vertices)
    assert all(value == 1.0 for w in weights.values() for value in w.values())


def test_character_parts_match_the_core():
    api = addon_module("api")
    ob = character()
    labels, seg = reference(ob)
    assert seg.segment_count >= 5  # torso, limbs
    result = api.segment_object(ob, materials=True)
    check_outputs(ob, result, labels, seg)
    arm = bpy.data.objects["human_parts"]
    assert len([b for b in arm.data.bones if b.parent is None]) == 1  # one connected body
    # Soft weights sum to 1 at every vertex; material slots follow the parts.
    weights = group_weights(ob)
    total = np.zeros(len(ob.data.vertices))
    for w in weights.values():
        for vertex, value in w.items():
            total[vertex] += value
    np.testing.assert_allclose(total, 1.0, atol=seg.segment_count / 1024)
    assert [m.name for m in ob.data.materials] == [g.name for g in ob.vertex_groups]
    indices = np.empty(len(ob.data.polygons), dtype=np.int32)
    ob.data.polygons.foreach_get("material_index", indices)
    np.testing.assert_array_equal(indices, labels)


def evaluated_positions(ob):
    evaluated = ob.evaluated_get(bpy.context.evaluated_depsgraph_get())
    me = evaluated.to_mesh()
    co = np.empty(len(me.vertices) * 3, dtype=np.float32)
    me.vertices.foreach_get("co", co)
    evaluated.to_mesh_clear()
    return co.reshape(-1, 3)


def test_posing_a_bone_moves_its_part_only():
    api = addon_module("api")
    ob = dumbbell()
    result = api.segment_object(ob, clusters=2)
    arm = bpy.data.objects[result.armature]
    bones = arm.data.bones
    leaf = next(b.name for b in bones if not b.children)
    root = next(b.name for b in bones if b.parent is None)
    rest = evaluated_positions(ob)
    np.testing.assert_allclose(rest, np.array([v.co for v in ob.data.vertices]), atol=1e-5)
    # A quarter turn about the joint (the bone is connected: it turns, it cannot move).
    pose = arm.pose.bones[leaf]
    pose.rotation_mode = "XYZ"
    pose.rotation_euler = (np.pi / 2, 0.0, 0.0)
    bpy.context.view_layer.update()
    moved = np.linalg.norm(evaluated_positions(ob) - rest, axis=1)
    labels = result.vertex_labels
    index = {name: i for i, name in enumerate(result.vertex_groups)}
    x = rest[:, 0]
    leaf_side = np.sign(np.median(x[labels == index[leaf]]))
    deep_leaf = (labels == index[leaf]) & (np.abs(x) > CENTRE) & (np.sign(x) == leaf_side)
    far = (labels == index[root]) & (np.abs(x) > CENTRE)
    assert deep_leaf.sum() > 100 and far.sum() > 100
    # The ball's vertices are 0.65 to 2.6 from the joint: a quarter turn moves them by
    # sqrt(2) times their distance from the bone's axis, at least a few tenths.
    assert moved[deep_leaf].min() > 0.2
    assert moved[far].max() < 1e-6
    # The bone goes from the joint through the ball: its tail on the far side of it.
    tail = np.array(bones[leaf].tail_local)
    assert abs(tail[0]) > CENTRE + 0.5 * BALL and np.hypot(tail[1], tail[2]) < 0.1


def test_values_on_the_mesh_are_reused():
    api = addon_module("api")
    ob = dumbbell()
    assert not api.segment_object(ob, clusters=2).reused_values  # nothing there yet
    api.compute_object(ob)
    again = api.segment_object(ob, clusters=2)
    assert again.reused_values and again.segment_count == 3
    assert not api.segment_object(ob, clusters=2, rays=12).reused_values  # other settings
    ob.data.vertices[0].co.x -= 0.01
    assert not api.segment_object(ob, clusters=2).reused_values  # other geometry


def test_minimum_part_size_joins_the_neck_to_a_ball():
    """The neck is 7% of the dumbbell's area: a minimum part size of 10% joins it to a ball,
    as the package does on the same triangles."""
    api = addon_module("api")
    ob = dumbbell()
    result = api.segment_object(ob, clusters=2, min_part_area=0.1)
    labels, seg = reference(ob, clusters=2, min_part_area=0.1)
    assert result.segment_count == seg.segment_count == 2
    np.testing.assert_array_equal(result.labels, labels)
    assert [g.name for g in ob.vertex_groups] == ["part_01", "part_02"]
    assert bpy.ops.object.shape_diameter_segment(clusters=2, min_part_area=0.1) == {"FINISHED"}
    np.testing.assert_array_equal(face_ints(ob.data, "segment"), labels)
    before = state()
    with pytest.raises(api.UserError, match=r"min_part_area must be a share in \[0, 1\)"):
        api.segment_object(ob, min_part_area=1.0)
    assert state() == before


def test_number_of_parts_searches_for_that_many():
    """Number of Parts: the package's segment(segments=N) on the same triangles, through the
    API and the operator; a bad count is refused with nothing written."""
    api = addon_module("api")
    ob = dumbbell()
    result = api.segment_object(ob, segments=3)
    labels, seg = reference(ob, segments=3)
    assert result.segment_count == seg.segment_count == 3
    np.testing.assert_array_equal(result.labels, labels)
    assert bpy.ops.object.shape_diameter_segment(segments=3, clusters=8) == {"FINISHED"}
    np.testing.assert_array_equal(
        face_ints(ob.data, "segment"), reference(ob, segments=3, clusters=8)[0]
    )
    before = state()
    with pytest.raises(api.UserError, match=r"segments must be an integer in \[0, 4096\]"):
        api.segment_object(ob, segments=-2)
    assert state() == before


def test_a_second_run_replaces_its_own_outputs():
    api = addon_module("api")
    ob = dumbbell()
    api.segment_object(ob, clusters=2)
    result = api.segment_object(ob, clusters=1, smoothness=0.0)
    assert [g.name for g in ob.vertex_groups] == result.vertex_groups
    armatures = [o for o in bpy.data.objects if o.type == "ARMATURE"]
    assert [o.name for o in armatures] == ["dumbbell_parts"]
    assert len(armatures[0].data.bones) == result.segment_count
    assert len([m for m in ob.modifiers if m.type == "ARMATURE"]) == 1


def edit_mode(ob):
    bpy.ops.object.mode_set(mode="EDIT")


def users_group(ob):
    ob.vertex_groups.new(name="part_01")


def users_face_sets(ob):
    ob.data.attributes.new(".sculpt_face_set", "INT", "FACE")


def users_object(ob):
    bpy.data.objects.new("dumbbell_parts", None)


def users_attribute(ob):
    ob.data.attributes.new("segment", "FLOAT", "POINT")


FAILURES = [
    (edit_mode, "dumbbell is in Edit Mode"),
    (users_group, "vertex groups 'part_01' were not written by Shape Diameter"),
    (users_face_sets, "has face sets .* not written by Shape Diameter"),
    (users_object, "an object is named 'dumbbell_parts'"),
    (users_attribute, "attribute 'segment' .* not written by Shape Diameter"),
]


@pytest.mark.parametrize("setup, message", FAILURES, ids=[f[0].__name__ for f in FAILURES])
def test_failure_is_reported_and_changes_nothing(setup, message):
    ob = dumbbell()
    setup(ob)
    before = state()
    with pytest.raises(RuntimeError, match=message):
        bpy.ops.object.shape_diameter_segment("EXEC_DEFAULT", True, clusters=2)
    assert state() == before


def test_linked_mesh_and_non_mesh_change_nothing(tmp_path):
    path = str(tmp_path / "library.blend")
    source = dumbbell("library")
    bpy.data.libraries.write(path, {source.data})
    bpy.data.objects.remove(source)
    with bpy.data.libraries.load(path, link=True) as (_, target):
        target.meshes = ["library"]
    linked = bpy.data.objects.new("linked", target.meshes[0])
    bpy.context.scene.collection.objects.link(linked)
    select_only(linked)
    before = state()
    with pytest.raises(RuntimeError, match="linked: its mesh 'library' is linked from"):
        bpy.ops.object.shape_diameter_segment("EXEC_DEFAULT", True)
    empty = bpy.data.objects.new("empty", None)
    bpy.context.scene.collection.objects.link(empty)
    select_only(empty)
    with pytest.raises(RuntimeError, match="Not a mesh: empty"):
        bpy.ops.object.shape_diameter_segment("EXEC_DEFAULT", True)
    bpy.data.objects.remove(empty)
    bpy.context.view_layer.update()
    assert state() == before


def test_a_write_failing_half_way_is_rolled_back(monkeypatch):
    armature = addon_module("armature")
    ob = dumbbell()
    before = state()

    def failing(*args):
        raise RuntimeError("out of memory")

    monkeypatch.setattr(armature, "attach", failing)
    with pytest.raises(RuntimeError, match="out of memory"):
        bpy.ops.object.shape_diameter_segment("EXEC_DEFAULT", True, clusters=2)
    assert state() == before
    assert ob.name in bpy.data.objects


def test_undo_restores_the_mesh_and_removes_the_armature():
    ob = dumbbell()
    name = ob.name
    before = state()
    bpy.ops.ed.undo_push(message="before Segment")
    assert bpy.ops.object.shape_diameter_segment("EXEC_DEFAULT", True, clusters=2) == {"FINISHED"}
    assert "dumbbell_parts" in bpy.data.objects
    assert bpy.ops.ed.undo() == {"FINISHED"}
    assert "dumbbell_parts" not in bpy.data.objects
    assert name in bpy.data.objects
    assert state() == before


def modal_segment(monkeypatch, **values):
    """The Segment operator's invoke() and modal() on a stand-in (modal_stand_in.py), as
    test_worker drives Compute's."""
    process, segmenting = addon_module("process"), addon_module("segmenting")
    cls = addon_module("segment_operator").OBJECT_OT_shape_diameter_segment
    methods = ("_prepare", "_finish", "_report_error", "_stop", "invoke", "modal")
    options = {
        **defaults(process.Options),
        **defaults(segmenting.SegmentOptions, leave_out=("sdf",)),
    }
    return stand_in(monkeypatch, cls, methods, options, values, scene=bpy.context.scene,
                    view_layer=bpy.context.view_layer)  # fmt: skip


def test_modal_segment_runs_on_the_worker_and_writes_at_the_end(monkeypatch):
    import time

    operators = addon_module("operators")
    ob = dumbbell()
    op, context, reports = modal_segment(monkeypatch, clusters=2)
    assert op.invoke(context, event("LEFTMOUSE")) == {"RUNNING_MODAL"}
    assert operators.running is not None and not bpy.ops.object.shape_diameter_segment.poll()
    while (result := op.modal(context, event("TIMER"))) == {"PASS_THROUGH"}:
        assert not ob.vertex_groups  # nothing is written before the end
        time.sleep(0.01)
    assert result == {"FINISHED"} and operators.running is None
    assert [g.name for g in ob.vertex_groups] == ["part_01", "part_02", "part_03"]
    assert reports[-1][0] == {"INFO"} and "dumbbell: 3 parts" in reports[-1][1]


def test_modal_segment_cancels_on_escape(monkeypatch):
    operators = addon_module("operators")
    ob = dumbbell()
    before = state()
    op, context, reports = modal_segment(monkeypatch, rays=256)
    assert op.invoke(context, event("LEFTMOUSE")) == {"RUNNING_MODAL"}
    assert op.modal(context, event("ESC", "PRESS")) == {"CANCELLED"}
    assert operators.running is None
    assert state() == before and ob.name in bpy.data.objects
    assert reports == [({"WARNING"}, "Segment cancelled: nothing was changed")]


def test_invoke_runs_synchronously_in_background():
    ob = dumbbell()
    assert bpy.app.background
    assert bpy.ops.object.shape_diameter_segment("INVOKE_DEFAULT", clusters=2) == {"FINISHED"}
    assert len(ob.vertex_groups) == 3


def test_segment_panel_and_operator_draw():
    import types

    from test_extension import FakeLayout, draw

    dumbbell()
    panel = bpy.types.VIEW3D_PT_shape_diameter_segment
    assert panel.poll(bpy.context)
    drawn = draw(panel, bpy.context)
    assert ("operator", "object.shape_diameter_segment") in drawn
    for name in (
        "clusters",
        "smoothness",
        "mode",
        "min_part_area",
        "face_sets",
        "group_prefix",
        "armature",
    ):
        assert ("prop", name) in drawn, name
    operator = addon_module("segment_operator").OBJECT_OT_shape_diameter_segment
    names = bpy.ops.object.shape_diameter_segment.get_rna_type().properties.keys()
    fake = types.SimpleNamespace(layout=FakeLayout([]), **{n: 0 for n in names if n != "rna_type"})
    operator.draw(fake, bpy.context)


def test_unregister_removes_the_segment_operator_and_panel():
    import addon_utils

    addon_utils.disable("bl_ext.user_default.shape_diameter", default_set=True)
    try:
        assert not hasattr(bpy.types, "OBJECT_OT_shape_diameter_segment")
        assert not hasattr(bpy.types, "VIEW3D_PT_shape_diameter_segment")
    finally:
        addon_utils.enable("bl_ext.user_default.shape_diameter", default_set=True)
    assert bpy.types.OBJECT_OT_shape_diameter_segment.is_registered


def segment_spy(monkeypatch):
    """What each call of the core's segment() did ('returned', or the exception's name), and
    the fractions it reported of its own work."""
    core = addon_module("core")
    original = core.segment
    outcomes, fractions = [], []

    def spy(vertices, triangles, values, options, progress=None):
        def told(fraction):
            fractions.append(fraction)
            progress(fraction)

        try:
            result = original(vertices, triangles, values, options, told)
        except BaseException as ex:
            outcomes.append(type(ex).__name__)
            raise
        outcomes.append("returned")
        return result

    monkeypatch.setattr(core, "segment", spy)
    return outcomes, fractions


def big_dumbbell_with_values():
    """200k triangles with the SDF already on them: a run that is all segmentation, long
    enough to be stopped half way."""
    api = addon_module("api")
    ob = dumbbell(sides=256, rings=400)
    api.compute_object(ob, rays=8)
    return ob


def test_a_stop_from_progress_stops_the_segmentation_itself(monkeypatch):
    api = addon_module("api")
    ob = big_dumbbell_with_values()
    before = state()
    outcomes, fractions = segment_spy(monkeypatch)

    def progress(fraction):
        return not (fractions and fractions[-1] >= 0.3)

    with pytest.raises(api.Cancelled):
        api.segment_object(ob, rays=8, progress=progress)
    assert outcomes == ["Cancelled"]  # raised inside the core's segment(), not after it
    assert 0.3 <= fractions[-1] < 0.9  # the graph cut's second move
    assert state() == before


def test_escape_during_the_segmentation_stops_it_and_changes_nothing(monkeypatch):
    import time

    operators = addon_module("operators")
    ob = big_dumbbell_with_values()
    before = state()
    outcomes, fractions = segment_spy(monkeypatch)
    op, context, reports = modal_segment(monkeypatch, rays=8)
    assert op.invoke(context, event("LEFTMOUSE")) == {"RUNNING_MODAL"}
    job = operators.running
    while not (fractions and fractions[-1] >= 0.3) and not job.done:
        time.sleep(0.001)
    assert not job.done
    assert op.modal(context, event("ESC", "PRESS")) == {"CANCELLED"}
    assert outcomes == ["Cancelled"] and fractions[-1] < 0.9
    assert job.tasks[0].segmentation is None
    assert state() == before and ob.name in bpy.data.objects
    assert reports == [({"WARNING"}, "Segment cancelled: nothing was changed")]
