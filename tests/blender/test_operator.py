# SPDX-License-Identifier: GPL-3.0-or-later
"""object.shape_diameter on real meshes: what it writes, against the Python package on the
same triangles and against the analytic sphere."""

import bmesh
import bpy
import numpy as np
import pytest
import shape_diameter
from helpers import (
    addon_module,
    attribute_array,
    import_obj,
    loop_totals,
    reference_face_values,
    run,
    select_only,
    snapshot,
    suzanne_with_ngons,
    world_triangles,
)
from mathutils import Matrix


def uv_sphere(radius=1.0, segments=64, rings=32):
    bpy.ops.mesh.primitive_uv_sphere_add(segments=segments, ring_count=rings, radius=radius)
    ob = bpy.context.active_object
    select_only(ob)
    return ob


def analytic_sphere_sdf(radius, rays=30, cone_angle=120.0):
    """The exact SDF of a sphere: a ray at angle a to the inward normal crosses a chord of
    length 2 r cos(a); reduced by the core's own rule over the directions it casts."""
    _, angles = shape_diameter.cone_rays([0.0, 0.0, 1.0], rays, cone_angle)
    return shape_diameter.reduce_lengths(2.0 * radius * np.cos(angles), angles)


def test_uv_sphere_matches_the_api_and_the_analytic_sphere():
    ob = uv_sphere(radius=1.0)
    assert run() == {"FINISHED"}
    values = attribute_array(ob.data, "sdf")
    np.testing.assert_allclose(values, reference_face_values(ob), rtol=1e-5)
    relative = values / analytic_sphere_sdf(1.0) - 1.0
    # A 64 x 32 UV sphere: faces lie inside the sphere, thin triangles at the poles.
    assert abs(np.median(relative)) < 0.01, np.median(relative)
    assert np.abs(relative).max() < 0.03, np.abs(relative).max()


def test_uv_sphere_vertices_match_the_analytic_sphere():
    ob = uv_sphere(radius=0.5)
    assert run(points="vertices") == {"FINISHED"}
    values = attribute_array(ob.data, "sdf")
    assert len(values) == len(ob.data.vertices)
    relative = values / analytic_sphere_sdf(0.5) - 1.0
    assert abs(np.median(relative)) < 0.01
    assert np.abs(relative).max() < 0.03


def test_switching_points_replaces_the_earlier_runs_attributes():
    # Faces then Vertices failed on the first run's own FACE attributes, which
    # had to be removed by hand. The add-on records what it wrote and replaces those.
    ob = uv_sphere(radius=0.5, segments=16, rings=8)
    me = ob.data
    values = {}
    for points, domain, color_domain, count in [
        ("faces", "FACE", "CORNER", len(me.polygons)),
        ("vertices", "POINT", "POINT", len(me.vertices)),
        ("faces", "FACE", "CORNER", len(me.polygons)),
    ]:
        assert run(points=points, rays=8, color_name="sdf_color") == {"FINISHED"}
        assert (me.attributes["sdf"].domain, me.attributes["sdf_color"].domain) == (
            domain,
            color_domain,
        )
        assert len(attribute_array(me, "sdf")) == count
        assert me.color_attributes.active_color_name == "sdf_color"
        # And the render colour: bpy 4.5 lost it when the other domain's was replaced.
        assert me.color_attributes.default_color_name == "sdf_color"
        values.setdefault(points, []).append(attribute_array(me, "sdf"))
    names = [a.name for a in me.attributes]
    assert len(names) == len(set(names))
    np.testing.assert_array_equal(*values["faces"])  # the same run's values, rewritten


def test_an_inside_out_mesh_is_measured_outward_unless_told_otherwise():
    ob = uv_sphere(radius=1.0, segments=32, rings=16)
    assert run() == {"FINISHED"}
    outward = attribute_array(ob.data, "sdf")
    ob.data.flip_normals()  # the mesh itself is inside out now
    corners = np.empty(len(ob.data.loops), dtype=np.int32)
    ob.data.loops.foreach_get("vertex_index", corners)
    assert run() == {"FINISHED"}  # orientation="auto"
    np.testing.assert_allclose(attribute_array(ob.data, "sdf"), outward, rtol=1e-5)
    # Said, since the artist's normals still point in (orientation turned them without a word).
    said = addon_module("api").compute_object(ob, rays=4).warnings
    assert said == [
        f"{ob.name}: {len(ob.data.polygons)} faces point inward (inside out) and were "
        "measured turned outward; the mesh is unchanged (Mesh > Normals > "
        "Recalculate Outside turns it in Blender)"
    ]
    # Every ray left through the skin: zeros, and it says so once (the core's warning, kept
    # for the object, not also printed: warnings are errors here).
    result = addon_module("api").compute_object(ob, orientation="as_is")
    assert len(result.warnings) == 1 and "no ray of any point" in result.warnings[0]
    assert np.allclose(attribute_array(ob.data, "sdf"), 0.0)
    # The computation reversed its own copy: the mesh's winding is untouched.
    after = np.empty_like(corners)
    ob.data.loops.foreach_get("vertex_index", after)
    np.testing.assert_array_equal(after, corners)


@pytest.mark.parametrize(
    "scale, apply_scale, factor",
    [((2.0, 2.0, 2.0), True, 2.0), ((2.0, 2.0, 2.0), False, 1.0), ((-1.0, 1.0, 1.0), True, 1.0)],
    ids=["world-units", "mesh-units", "mirrored"],
)
def test_object_scale(scale, apply_scale, factor):
    ob = uv_sphere(radius=1.0, segments=32, rings=16)
    assert run() == {"FINISHED"}
    plain = attribute_array(ob.data, "sdf")
    ob.scale = scale
    bpy.context.view_layer.update()
    assert run(apply_scale=apply_scale) == {"FINISHED"}
    scaled = attribute_array(ob.data, "sdf")
    np.testing.assert_allclose(scaled, reference_face_values(ob, apply_scale), rtol=1e-5)
    if scale[0] > 0:
        np.testing.assert_allclose(scaled, factor * plain, rtol=2e-3)
    else:
        # A mirroring scale turns the faces inside out; the add-on reverses the winding with
        # it. The cone's rays are not mirrored with the mesh, so values move a little.
        ratio = scaled / plain
        assert abs(np.median(ratio) - 1.0) < 0.005 and np.abs(ratio - 1.0).max() < 0.04


def test_the_operator_runs_on_the_best_opencl_device_or_a_chosen_one():
    # The engine menu refused 'opencl' (the best device), which shape_diameter.compute()
    # takes. An OpenCL device is needed: CI installs PoCL (scripts/setup.sh), as for
    # tests/python/test_opencl.py, so none is a failure.
    operators = addon_module("operators")
    devices = [e["name"] for e in shape_diameter.engines() if e["name"].startswith("opencl:")]
    assert devices, "no OpenCL device here: install pocl-opencl-icd"
    ob = uv_sphere(radius=1.0, segments=32, rings=16)
    # Fibonacci sampling: every OpenCL device computes the CPU engine's bits (docs/python.md).
    expected = reference_face_values(ob, rays=16, engine="cpu")
    for engine in ("opencl", devices[-1]):
        assert run(engine=engine, rays=16) == {"FINISHED"}
        assert ", opencl:" in operators.last_run["text"], operators.last_run["text"]
        np.testing.assert_allclose(attribute_array(ob.data, "sdf"), expected, rtol=1e-6)


def test_suzanne_with_quads_and_ngons():
    ob = suzanne_with_ngons()
    me = ob.data
    sizes = loop_totals(me)
    assert (sizes == 3).any() and (sizes == 4).any() and (sizes > 4).any()
    assert run() == {"FINISHED"}

    kinds = {a.name: (a.data_type, a.domain, len(a.data)) for a in me.attributes}
    assert kinds["sdf"] == ("FLOAT", "FACE", len(me.polygons))
    assert kinds["sdf_normalized"] == ("FLOAT", "FACE", len(me.polygons))
    assert kinds["sdf_color"] == ("BYTE_COLOR", "CORNER", len(me.loops))
    assert me.color_attributes.active_color_name == "sdf_color"

    values = attribute_array(me, "sdf")
    np.testing.assert_allclose(values, reference_face_values(ob), rtol=1e-5)
    normalized = attribute_array(me, "sdf_normalized")
    np.testing.assert_allclose(normalized, shape_diameter.normalize(values, "linear"), atol=1e-6)
    assert normalized.min() == 0.0 and normalized.max() == 1.0
    # Each corner carries its polygon's colour: the package's colour map, byte for byte.
    expected = np.repeat(shape_diameter.colormap.colormap(normalized), sizes, axis=0)
    colors = np.rint(attribute_array(me, "sdf_color") * 255).astype(np.uint8)
    np.testing.assert_array_equal(colors, expected)


def test_suzanne_vertices():
    ob = import_obj("suzanne.obj")
    me = ob.data
    assert run(points="vertices", normalize="log", rays=16) == {"FINISHED"}
    for name, data_type in (
        ("sdf", "FLOAT"),
        ("sdf_normalized", "FLOAT"),
        ("sdf_color", "BYTE_COLOR"),
    ):
        a = me.attributes[name]
        assert (a.data_type, a.domain, len(a.data)) == (data_type, "POINT", len(me.vertices))
    v, t, _ = world_triangles(ob)
    ref = shape_diameter.compute(v, t, points="vertices", normalize="log", rays=16)
    np.testing.assert_allclose(attribute_array(me, "sdf"), ref.values, rtol=1e-6)
    np.testing.assert_allclose(attribute_array(me, "sdf_normalized"), ref.normalized, atol=1e-6)
    assert me.color_attributes.active_color_name == "sdf_color"


def test_loose_vertices_are_left_unmeasured():
    # A vertex of no face (a lone point, a wire edge's ends) casts no ray: the core fills it
    # with the median of the values (valid_rays 0), which the add-on wrote and coloured as
    # if measured.
    api = addon_module("api")
    ob = uv_sphere(radius=1.0, segments=32, rings=16)
    me = ob.data
    n = len(me.vertices)
    me.vertices.add(3)
    for i, co in enumerate([(0.1, 0.2, 0.3), (2.0, 0.0, 0.0), (3.0, 0.0, 0.0)]):
        me.vertices[n + i].co = co
    me.edges.add(1)
    me.edges[-1].vertices = (n + 1, n + 2)  # a wire edge
    me.update()
    loose = [n, n + 1, n + 2]
    measured = np.arange(n)

    result = api.compute_object(ob, points="vertices", rays=16)
    values = attribute_array(me, "sdf")
    normalized = attribute_array(me, "sdf_normalized")
    colors = attribute_array(me, "sdf_color")
    assert (values[loose] == 0).all() and (result.values[loose] == 0).all()
    assert (normalized[loose] == 0).all() and (result.valid_rays[loose] == 0).all()
    assert (colors[loose] == 0).all()  # transparent black: no colour of the map
    assert (colors[measured, 3] == 1).all()
    assert any("3 vertices in no face" in w for w in result.warnings), result.warnings
    # The other vertices are as the package gives them: the loose ones change nothing there.
    v, t, _ = world_triangles(ob)
    ref = shape_diameter.compute(v, t, points="vertices", rays=16)
    np.testing.assert_allclose(values[measured], ref.values[measured], rtol=1e-6)
    np.testing.assert_allclose(normalized[measured], ref.normalized[measured], atol=1e-6)
    # Per face, loose vertices have no value at all: nothing to say.
    assert not api.compute_object(
        ob, attribute_name="per_face", normalized_name="", color_name=""
    ).warnings


def test_undo_restores_the_mesh():
    ob = suzanne_with_ngons()
    name = ob.data.name
    before = snapshot(ob.data)
    bpy.ops.ed.undo_push(message="before Shape Diameter")
    assert run() == {"FINISHED"}
    assert "sdf" in bpy.data.meshes[name].attributes
    assert bpy.ops.ed.undo() == {"FINISHED"}
    assert snapshot(bpy.data.meshes[name]) == before
    assert bpy.ops.ed.redo() == {"FINISHED"}
    assert "sdf" in bpy.data.meshes[name].attributes


def test_a_second_run_replaces_the_values():
    ob = import_obj("suzanne.obj")
    assert run(rays=8) == {"FINISHED"}
    names = [a.name for a in ob.data.attributes]
    assert run(rays=40) == {"FINISHED"}
    assert [a.name for a in ob.data.attributes] == names
    np.testing.assert_allclose(
        attribute_array(ob.data, "sdf"), reference_face_values(ob, rays=40), rtol=1e-5
    )


def test_custom_names_and_optional_outputs():
    ob = import_obj("suzanne.obj")
    assert run(attribute_name="thickness", normalized_name="", color_name="") == {"FINISHED"}
    names = {a.name for a in ob.data.attributes}
    assert "thickness" in names and not names & {"sdf", "sdf_normalized", "sdf_color"}
    assert len(ob.data.color_attributes) == 0


def test_use_modifiers_computes_on_the_deformed_mesh():
    ob = import_obj("suzanne.obj")
    modifier = ob.modifiers.new("deform", "SIMPLE_DEFORM")
    modifier.deform_method = "TAPER"
    modifier.factor = 1.5
    assert run(use_modifiers=False) == {"FINISHED"}
    plain = attribute_array(ob.data, "sdf")
    assert run(use_modifiers=True) == {"FINISHED"}
    deformed = attribute_array(ob.data, "sdf")
    assert not np.allclose(plain, deformed, rtol=0.05)

    evaluated = ob.evaluated_get(bpy.context.evaluated_depsgraph_get())
    temp = bpy.data.meshes.new_from_object(evaluated)
    try:
        proxy = bpy.data.objects.new("proxy", temp)
        proxy.matrix_world = ob.matrix_world
        np.testing.assert_allclose(deformed, reference_face_values(proxy), rtol=1e-5)
    finally:
        bpy.data.objects.remove(proxy)
        bpy.data.meshes.remove(temp)


def test_use_modifiers_refuses_an_object_the_view_layer_does_not_evaluate():
    # In an excluded collection its base mesh was computed without a word, even
    # under a Subdivision Surface modifier that the topology check refuses.
    api = addon_module("api")
    ob = import_obj("suzanne.obj")
    ob.modifiers.new("deform", "SIMPLE_DEFORM").factor = 1.5
    hidden = bpy.data.collections.new("hidden")
    bpy.context.scene.collection.children.link(hidden)
    hidden.objects.link(ob)
    bpy.context.scene.collection.objects.unlink(ob)
    bpy.context.view_layer.layer_collection.children["hidden"].exclude = True
    before = snapshot(ob.data)
    with pytest.raises(api.UserError, match="suzanne is not evaluated in this view layer"):
        api.compute_object(ob, rays=4, use_modifiers=True)
    assert snapshot(ob.data) == before
    assert api.compute_object(ob, rays=4).object_name == "suzanne"  # its base mesh, as asked


def test_modifiers_and_shape_keys_left_out_are_named_in_a_warning():
    # A mirror-modelled half and a cube flattened by a shape key were measured as
    # their base meshes with no word that the viewport shows something else.
    api = addon_module("api")
    half = import_obj("suzanne.obj")
    half.modifiers.new("Mirror", "MIRROR")
    half.modifiers.new("Normals", "WEIGHTED_NORMAL")  # keeps the shape: not named
    half.modifiers.new("Split", "EDGE_SPLIT")  # the same (it was named, falsely)
    # Shade Auto Smooth's modifier (4.1 on): geometry nodes of a 'Smooth by Angle' group.
    smooth = half.modifiers.new("Smooth by Angle", "NODES")
    smooth.node_group = bpy.data.node_groups.new("Smooth by Angle", "GeometryNodeTree")
    keyed = uv_sphere(segments=16, rings=8)
    keyed.shape_key_add(name="Basis")
    keyed.shape_key_add(name="Flat").value = 0.0
    plain = uv_sphere(segments=16, rings=8)
    results = api.compute_objects([half, keyed, plain], rays=4)
    assert [w for w in results[0].warnings if "left out" in w] == [
        "suzanne: its modifiers (Mirror) change its shape in the viewport and are left out "
        "(Use Modifiers is off): the values are those of its base mesh"
    ]
    assert not any("left out" in w for r in results[1:] for w in r.warnings)  # key at 0
    keyed.data.shape_keys.key_blocks["Flat"].value = 0.5
    result = api.compute_object(keyed, rays=4)
    assert any("its shape keys change its shape" in w for w in result.warnings)
    modified = api.compute_object(keyed, rays=4, use_modifiers=True)
    assert not any("left out" in w for w in modified.warnings)


def test_a_thin_part_far_from_the_rest_is_warned_of():
    # The core's warning, as the add-on words it: a 1 mm plate and a ball 60 m away in one
    # object; hits nearer than 2e-5 of the object's size (1.2 mm) are ignored.
    api = addon_module("api")
    me = bpy.data.meshes.new("scene")
    bm = bmesh.new()
    bmesh.ops.create_cube(bm, size=1.0)
    bmesh.ops.subdivide_edges(bm, edges=bm.edges[:], cuts=7, use_grid_fill=True)
    bmesh.ops.scale(bm, vec=(1.0, 1.0, 0.001), verts=bm.verts[:])
    bmesh.ops.create_icosphere(
        bm, subdivisions=2, radius=0.25, matrix=Matrix.Translation((60.0, 0.0, 0.0))
    )
    bm.to_mesh(me)
    bm.free()
    ob = bpy.data.objects.new("scene", me)
    bpy.context.scene.collection.objects.link(ob)
    result = api.compute_object(ob)  # the core's warning, not also printed
    near = [w for w in result.warnings if "near-hit cutoff" in w]
    assert len(near) == 1 and near[0].startswith("scene: 1 of the mesh's 2 parts")


def test_every_selected_mesh_and_a_shared_mesh():
    sphere = uv_sphere(segments=32, rings=16)
    suzanne = import_obj("suzanne.obj")
    twin = bpy.data.objects.new("twin", suzanne.data)  # a linked duplicate: same mesh
    bpy.context.scene.collection.objects.link(twin)
    camera = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
    bpy.context.scene.collection.objects.link(camera)
    select_only(sphere, suzanne, twin, camera)
    assert run() == {"FINISHED"}  # the camera is skipped with a warning
    np.testing.assert_allclose(
        attribute_array(sphere.data, "sdf"), reference_face_values(sphere), rtol=1e-5
    )
    np.testing.assert_allclose(
        attribute_array(suzanne.data, "sdf"), reference_face_values(suzanne), rtol=1e-5
    )


def test_scripting_api():
    api = addon_module("api")
    ob = import_obj("suzanne.obj")
    result = api.compute_object(ob, rays=12, cone_angle=90.0)
    assert result.domain == "FACE" and result.attributes == ["sdf", "sdf_normalized", "sdf_color"]
    assert result.engine.startswith("cpu")
    np.testing.assert_array_equal(attribute_array(ob.data, "sdf"), result.values)
    np.testing.assert_allclose(
        result.values, reference_face_values(ob, rays=12, cone_angle=90.0), rtol=1e-5
    )

    before = snapshot(ob.data)
    dry = api.compute_object(ob, write=False, points="vertices", attribute_name="other")
    assert dry.domain == "POINT" and len(dry.values) == len(ob.data.vertices)
    assert snapshot(ob.data) == before

    with pytest.raises(TypeError, match="unknown option 'no_such_option'"):
        api.compute_object(ob, no_such_option=1)
    with pytest.raises(ValueError, match="rays"):
        api.compute_object(ob, rays=0)
    with pytest.raises(api.UserError, match="Not a mesh"):
        api.compute_object(bpy.data.objects.new("empty", None))
    assert snapshot(ob.data) == before
    assert [e["name"] for e in api.engines()][0] == shape_diameter.engines()[0]["name"]


def test_the_api_says_what_it_skipped_as_the_operator_does():
    # compute_objects() left out what is not a mesh without a word; the operator reports it.
    api = addon_module("api")
    sphere = uv_sphere(segments=16, rings=8)
    suzanne = import_obj("suzanne.obj")
    twin = bpy.data.objects.new("twin", suzanne.data)  # a linked duplicate: same mesh
    camera = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
    for ob in (twin, camera):
        bpy.context.scene.collection.objects.link(ob)
    with pytest.warns(RuntimeWarning, match=r"Skipped what is not a mesh: camera \(camera\)"):
        results = api.compute_objects([sphere, camera, suzanne, twin], rays=4)
    assert [r.object_name for r in results] == ["Sphere", "suzanne"]
    # About the whole run: in every result, first.
    assert all(r.warnings[0] == "Skipped what is not a mesh: camera (camera)" for r in results)
    # About one object: in its own result only.
    shared = "suzanne shares its mesh with twin: computed once, from suzanne"
    assert results[1].warnings == [results[0].warnings[0], shared]
    assert results[0].warnings == [results[0].warnings[0]]
    assert results[1].shared_by == ["twin"]


def test_what_is_not_a_mesh_is_named_with_how_to_make_it_one():
    api = addon_module("api")
    instance = bpy.data.objects.new("Inst", None)
    instance.instance_type = "COLLECTION"
    instance.instance_collection = bpy.data.collections.new("kit")
    curve = bpy.data.objects.new("Path", bpy.data.curves.new("Path", "CURVE"))
    with pytest.raises(api.UserError) as caught:
        api.compute_objects([instance, curve])
    assert str(caught.value) == (
        "Not a mesh: Inst (a collection instance: Make Instances Real "
        "first), Path (curve: convert it to a mesh first)"
    )


def test_a_shared_mesh_is_computed_from_the_active_object():
    # A linked duplicate at 10 times the scale, made active: the operator computed the mesh
    # from whichever object came first in the selection, not the one looked at.
    api = addon_module("api")
    suzanne = import_obj("suzanne.obj")
    big = bpy.data.objects.new("big", suzanne.data)
    bpy.context.scene.collection.objects.link(big)
    big.scale = (10.0, 10.0, 10.0)
    bpy.context.view_layer.update()
    for ob in (suzanne, big):
        ob.select_set(True)
    bpy.context.view_layer.objects.active = big
    assert run(rays=8) == {"FINISHED"}
    expected = api.compute_object(big, rays=8, write=False).values
    # (the operator's cone angle goes through radians: the last bit may differ)
    np.testing.assert_allclose(attribute_array(suzanne.data, "sdf"), expected, rtol=1e-6)
    # The API keeps the order it is given.
    results = api.compute_objects([suzanne, big], rays=8, write=False)
    assert results[0].object_name == "suzanne" and results[0].shared_by == ["big"]


def test_an_inside_out_mesh_trusted_as_wound_warns_that_few_rays_were_kept():
    api = addon_module("api")
    spot = import_obj("spot.obj")
    result = api.compute_object(spot, rays=8, orientation="flip", write=False)
    assert any(w.startswith("spot: only ") and "orientation='flip'" in w for w in result.warnings)
    assert not any("only " in w for w in api.compute_object(spot, rays=8, write=False).warnings)


def test_a_vertex_group_of_the_results_name_is_refused_first():
    # Blender cannot make an attribute of a vertex group's name: this failed only after the
    # computation, with Blender's own error.
    api = addon_module("api")
    bpy.ops.mesh.primitive_cube_add()
    ob = bpy.context.active_object
    ob.vertex_groups.new(name="sdf")
    before = snapshot(ob.data)
    with pytest.raises(api.UserError, match="a vertex group is named 'sdf'"):
        api.compute_object(ob)
    assert snapshot(ob.data) == before
    assert (api.compute_object(ob, attribute_name="thickness").values > 0).all()


def test_the_operator_starts_from_its_defaults_at_every_call():
    # Called with undo (as the UI does), the operator once reused the previous call's options
    # for those a call left out (orientation='flip' stuck: every value 0).
    bpy.ops.mesh.primitive_uv_sphere_add()
    ob = bpy.context.active_object
    done = bpy.ops.object.shape_diameter("EXEC_DEFAULT", True, attribute_name="first", rays=4)
    assert done == {"FINISHED"} and "first" in ob.data.attributes
    assert bpy.ops.object.shape_diameter("EXEC_DEFAULT", True) == {"FINISHED"}
    assert "sdf" in ob.data.attributes  # the default name, not the previous call's
    np.testing.assert_allclose(  # and the default 30 rays, not 4
        attribute_array(ob.data, "sdf"), reference_face_values(ob), rtol=1e-5
    )


def test_the_api_reports_progress_and_stops_when_asked():
    # progress= once collided with the keyword the API passes on (TypeError).
    api = addon_module("api")
    ob = import_obj("spot.obj")
    seen = []
    api.compute_object(ob, rays=8, progress=seen.append)
    assert seen and seen[-1] == 1.0 and all(0.0 <= f <= 1.0 for f in seen)
    before = snapshot(ob.data)
    with pytest.raises(api.Cancelled):
        api.compute_object(ob, rays=8, attribute_name="other", progress=lambda f: False)
    assert snapshot(ob.data) == before
    with pytest.raises(api.Cancelled):  # a stop at the very last call writes nothing either
        api.compute_object(ob, rays=8, attribute_name="other", progress=lambda f: f < 1.0)
    assert snapshot(ob.data) == before
    with pytest.raises(api.UserError, match="progress must be a callable"):
        api.compute_object(ob, progress=3)


def test_an_open_sheet_gives_zeros_and_a_warning():
    api = addon_module("api")
    bpy.ops.mesh.primitive_plane_add()
    ob = bpy.context.active_object
    result = api.compute_object(ob)
    assert result.warnings == [
        "Plane: no ray of any point found the other side of the mesh (is it open, flat or "
        "inside out?); every value is 0 and valid_rays is 0 everywhere"
    ]
    assert (attribute_array(ob.data, "sdf") == 0).all()


def test_a_double_sided_mesh_measures_the_same_on_both_sides():
    # Shift+D and Flip in Edit Mode: every face again, reversed, on vertices of its own. The
    # copies' values came out 0.08-2.7x the thickness, and a bake was overwritten by them.
    import bmesh

    api = addon_module("api")
    spot = import_obj("spot.obj")
    single = api.compute_object(spot, rays=8, write=False).values
    bm = bmesh.new()
    bm.from_mesh(spot.data)
    copied = bmesh.ops.duplicate(bm, geom=bm.verts[:] + bm.edges[:] + bm.faces[:])
    faces = [g for g in copied["geom"] if isinstance(g, bmesh.types.BMFace)]
    bmesh.ops.reverse_faces(bm, faces=faces)
    bm.to_mesh(spot.data)
    bm.free()
    result = api.compute_object(spot, rays=8)
    n = len(single)
    assert len(result.values) == 2 * n
    np.testing.assert_allclose(result.values[:n], single, rtol=1e-6)
    np.testing.assert_allclose(result.values[n:], single, rtol=1e-6)


def test_users_of_the_mesh_not_computed_are_named():
    # Computing a scaled linked duplicate rescaled the original's values (they
    # share the mesh, and so its attribute) without a word.
    api = addon_module("api")
    original = uv_sphere(segments=16, rings=8)
    copy = original.copy()
    bpy.context.scene.collection.objects.link(copy)
    copy.scale = (3.0, 3.0, 3.0)
    result = api.compute_objects([copy], rays=4)[0]
    assert [w for w in result.warnings if "also used by" in w] == [
        f"{copy.name}'s mesh is also used by {original.name}, not computed: they show these "
        f"values too, measured with {copy.name}'s transform"
    ]
    assert not any(
        "also used by" in w for w in api.compute_objects([copy, original], rays=4)[0].warnings
    )


def test_uvs_that_are_not_finite_are_refused_before_any_work():
    # A NaN UV failed the bake after the cast, as an unnamed 'ValueError'.
    api = addon_module("api")
    bpy.ops.mesh.primitive_cube_add()
    cube = bpy.context.active_object
    uv = np.zeros(len(cube.data.loops) * 2, dtype=np.float32)
    cube.data.uv_layers.active.data.foreach_get("uv", uv)
    uv[0] = np.nan
    cube.data.uv_layers.active.data.foreach_set("uv", uv)
    with pytest.raises(
        api.UserError,
        match=r"^Cube's UV map 'UVMap' has coordinates that are "
        r"not finite .*needed by the bake",
    ):
        api.compute_object(
            cube,
            bake_image=True,
            texture_size=64,
            progress=lambda f: pytest.fail("it computed first"),
        )
