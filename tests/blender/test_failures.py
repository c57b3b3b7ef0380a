# SPDX-License-Identifier: GPL-3.0-or-later
"""Every failure is reported (bpy.ops turns an ERROR report into RuntimeError) and leaves
every mesh in the file byte-identical: attribute names, types, domains and data, the active
and default color attributes."""

import os
import tempfile

import bpy
import pytest
from helpers import addon_module, import_obj, run, select_only, snapshot, snapshot_all


def sphere():
    bpy.ops.mesh.primitive_uv_sphere_add(segments=16, ring_count=8)
    return bpy.context.active_object


def suzanne_and_sphere():
    """Two good meshes, one with results of an earlier run that a failure must keep."""
    good = sphere()
    select_only(good)
    assert run(rays=4) == {"FINISHED"}
    return good, import_obj("suzanne.obj")


def nothing_selected():
    suzanne_and_sphere()
    select_only()
    return {}


def not_a_mesh():
    suzanne_and_sphere()
    empty = bpy.data.objects.new("empty", None)
    curve = bpy.data.objects.new("curve", bpy.data.curves.new("curve", "CURVE"))
    for ob in (empty, curve):
        bpy.context.scene.collection.objects.link(ob)
    select_only(empty, curve)
    return {}


def faceless_meshes():
    """Two meshes without faces, linked to the scene: an empty one and three lone vertices."""
    empty = bpy.data.objects.new("nothing", bpy.data.meshes.new("nothing"))
    me = bpy.data.meshes.new("points")
    me.from_pydata([(0, 0, 0), (1, 0, 0), (0, 1, 0)], [], [])
    points = bpy.data.objects.new("points", me)
    for ob in (empty, points):
        bpy.context.scene.collection.objects.link(ob)
    return empty, points


def only_faceless():
    select_only(*faceless_meshes())
    return {}


def edit_mode():
    good, suzanne = suzanne_and_sphere()
    select_only(suzanne, good)
    bpy.context.view_layer.objects.active = suzanne
    bpy.ops.object.mode_set(mode="EDIT")
    return {}


def linked_mesh():
    good, _ = suzanne_and_sphere()
    path = os.path.join(tempfile.mkdtemp(), "library.blend")
    me = bpy.data.meshes.new("library_mesh")
    me.from_pydata(
        [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)],
        [],
        [(0, 2, 1), (0, 1, 3), (1, 2, 3), (0, 3, 2)],
    )
    bpy.data.libraries.write(path, {me})
    bpy.data.meshes.remove(me)
    with bpy.data.libraries.load(path, link=True) as (_source, target):
        target.meshes = ["library_mesh"]
    ob = bpy.data.objects.new("linked", target.meshes[0])
    bpy.context.scene.collection.objects.link(ob)
    assert ob.data.library is not None
    select_only(good, ob)
    return {}


def attribute_of_another_type():
    good, suzanne = suzanne_and_sphere()
    suzanne.data.attributes.new("sdf", "INT", "FACE")
    select_only(good, suzanne)
    return {}


def attribute_on_another_domain():
    good, suzanne = suzanne_and_sphere()
    suzanne.data.attributes.new("sdf_normalized", "FLOAT", "POINT")
    select_only(good, suzanne)
    return {}


def color_of_another_type():
    good, suzanne = suzanne_and_sphere()
    suzanne.data.color_attributes.new("sdf_color", "FLOAT_COLOR", "POINT")
    select_only(good, suzanne)
    return {}


def vertices_over_the_users_attribute():
    # The sphere's FACE results are the add-on's own and could be replaced by POINT ones;
    # suzanne's FACE attribute of the same name is the user's, and is kept.
    good, suzanne = suzanne_and_sphere()
    suzanne.data.attributes.new("sdf", "FLOAT", "FACE")
    select_only(good, suzanne)
    return {"points": "vertices"}


def bad_coordinates():
    good, suzanne = suzanne_and_sphere()
    suzanne.data.vertices[10].co = (float("nan"), 0.0, 0.0)
    select_only(good, suzanne)
    return {}


def too_wide():
    good, suzanne = suzanne_and_sphere()
    suzanne.data.vertices[10].co = (1e31, 0.0, 0.0)
    select_only(good, suzanne)
    return {}


def modifiers_change_topology():
    good, suzanne = suzanne_and_sphere()
    suzanne.modifiers.new("subdivide", "SUBSURF")
    select_only(good, suzanne)
    return {"use_modifiers": True}


def same_names():
    suzanne_and_sphere()
    return {"normalized_name": "sdf"}


def empty_name():
    suzanne_and_sphere()
    return {"attribute_name": ""}


def internal_name():
    suzanne_and_sphere()
    return {"color_name": ".sdf"}


CASES = [
    (nothing_selected, "Nothing selected"),
    (not_a_mesh, "Not a mesh: empty \\(empty\\), curve \\(curve: convert it to a mesh first\\)"),
    (only_faceless, "nothing has no faces \\(nor have points\\)"),
    (edit_mode, "(suzanne|Sphere) is in Edit Mode"),
    (linked_mesh, "linked: its mesh 'library_mesh' is linked from"),
    (attribute_of_another_type, "attribute 'sdf' exists as INT on FACE"),
    (attribute_on_another_domain, "attribute 'sdf_normalized' exists as FLOAT on POINT"),
    (color_of_another_type, "attribute 'sdf_color' exists as FLOAT_COLOR on POINT"),
    (
        vertices_over_the_users_attribute,
        "suzanne: attribute 'sdf' exists as FLOAT on FACE; the result is FLOAT on POINT",
    ),
    (bad_coordinates, "suzanne has vertices whose coordinates are not finite"),
    (too_wide, "suzanne: the mesh spans 1e\\+31 units on an axis"),  # the core's, named
    (modifiers_change_topology, "The modifiers of suzanne change its topology"),
    (same_names, "names must differ"),
    (empty_name, "attribute name is empty"),
    (internal_name, "starting with '.'"),
]


def test_meshes_without_faces_are_skipped_beside_others():
    # A wire rig or a single-vertex placeholder in the selection stopped the whole run; it is
    # skipped with a warning, as what is not a mesh is, and left as it was.
    api = addon_module("api")
    good, _ = suzanne_and_sphere()
    empty, points = faceless_meshes()
    before = (snapshot(empty.data), snapshot(points.data))
    with pytest.warns(RuntimeWarning, match="Skipped meshes without faces: nothing, points"):
        results = api.compute_objects([good, empty, points], rays=4)
    assert [r.object_name for r in results] == [good.name]
    assert (snapshot(empty.data), snapshot(points.data)) == before


@pytest.mark.parametrize("setup, message", CASES, ids=[c[0].__name__ for c in CASES])
def test_failure_is_reported_and_changes_nothing(setup, message):
    options = setup()
    before = snapshot_all()
    with pytest.raises(RuntimeError, match=message):
        run(**options)
    assert snapshot_all() == before


def test_engine_failure_changes_nothing(monkeypatch):
    core = addon_module("core")
    suzanne_and_sphere()
    select_only(*[ob for ob in bpy.data.objects])

    def broken(*args, **kwargs):
        raise RuntimeError("device lost")

    monkeypatch.setattr(core, "compute", broken)
    before = snapshot_all()
    with pytest.raises(RuntimeError, match="Shape Diameter failed: RuntimeError: device lost"):
        run()
    assert snapshot_all() == before


def _fifth_write_fails(monkeypatch):
    """Makes the fifth attribute write raise MemoryError; returns the names written to."""
    mesh_data = addon_module("mesh_data")
    original = mesh_data.write_attribute
    calls = []

    def failing(attribute, data):
        calls.append(attribute.name)
        if len(calls) == 5:
            raise MemoryError("out of memory while writing")
        original(attribute, data)

    monkeypatch.setattr(mesh_data, "write_attribute", failing)
    return calls


def test_a_write_failing_half_way_is_rolled_back(monkeypatch):
    """The all-or-nothing write: the first mesh is fully written (replacing its earlier
    results) before writing the second fails; everything is put back."""
    good, suzanne = suzanne_and_sphere()
    select_only(good, suzanne)
    calls = _fifth_write_fails(monkeypatch)
    before = snapshot_all()
    with pytest.raises(RuntimeError, match="MemoryError"):
        run(rays=12)
    assert len(calls) > 5  # the rollback wrote the replaced values back
    assert snapshot_all() == before


def test_a_write_failing_after_replacing_a_domain_is_rolled_back(monkeypatch):
    """Switching Points removes the earlier run's attributes of the other domain; a failure
    later in the write puts them back, with their data. They come back at the end of their
    domain's list, so the comparison sorts them and leaves out the active attribute's index."""
    mesh_data = addon_module("mesh_data")
    good, suzanne = suzanne_and_sphere()
    select_only(good, suzanne)
    assert run(rays=4) == {"FINISHED"}
    _fifth_write_fails(monkeypatch)

    def state():
        return {
            name: {**shot, "attributes": sorted(shot["attributes"]), "active_attribute": 0}
            for name, shot in snapshot_all().items()
        }

    before = state()
    records = {me.name: me.get(mesh_data.OUTPUTS_PROPERTY) for me in bpy.data.meshes}
    with pytest.raises(RuntimeError, match="MemoryError"):
        run(rays=4, points="vertices")
    assert state() == before
    assert {me.name: me.get(mesh_data.OUTPUTS_PROPERTY) for me in bpy.data.meshes} == records


def test_core_that_cannot_load_is_reported(monkeypatch):
    core = addon_module("core")
    good, suzanne = suzanne_and_sphere()
    select_only(good, suzanne)

    def cannot_load():
        raise core.CoreUnavailable("The Shape Diameter core could not be loaded: test")

    monkeypatch.setattr(core, "load", cannot_load)
    before = snapshot_all()
    with pytest.raises(RuntimeError, match="core could not be loaded"):
        run()
    assert snapshot_all() == before


def bake_without_uvs():
    good, suzanne = suzanne_and_sphere()  # the sphere has a UV map, suzanne.obj none
    select_only(good, suzanne)
    return {"bake_image": True, "texture_size": 64}


def bake_with_a_missing_uv_map():
    good, _ = suzanne_and_sphere()
    spot = import_obj("spot.obj")
    select_only(good, spot)
    return {"bake_image": True, "texture_size": 64, "uv_map": "NoSuchMap"}


def texture_smoothing_without_uvs():
    good, suzanne = suzanne_and_sphere()
    select_only(suzanne, good)
    return {"smoothing": "texture", "texture_size": 64}


def one_image_for_two_objects():
    good, _ = suzanne_and_sphere()
    spot = import_obj("spot.obj")
    select_only(good, spot)
    return {"bake_image": True, "texture_size": 64, "image_name": "shared"}


BAKE_CASES = [
    (bake_without_uvs, "suzanne has no UV map, needed by the bake"),
    (bake_with_a_missing_uv_map, "Sphere has no UV map 'NoSuchMap', needed by the bake"),
    (texture_smoothing_without_uvs, "suzanne has no UV map, needed by texture smoothing"),
    (one_image_for_two_objects, "Several objects would bake into one image"),
]


@pytest.mark.parametrize("setup, message", BAKE_CASES, ids=[c[0].__name__ for c in BAKE_CASES])
def test_bake_failure_is_reported_and_changes_nothing(setup, message):
    options = setup()
    before = snapshot_all()
    images = sorted(bpy.data.images.keys())
    with pytest.raises(RuntimeError, match=message):
        run(**options)
    assert snapshot_all() == before
    assert sorted(bpy.data.images.keys()) == images


def test_an_image_failing_is_rolled_back_with_the_attributes(monkeypatch):
    # Failing once Blender made the image (its bytes packed): that image goes too.
    baking = addon_module("baking")
    good, _ = suzanne_and_sphere()
    spot = import_obj("spot.obj")
    select_only(good, spot)

    def failing(image):
        raise MemoryError("no memory for the image")

    monkeypatch.setattr(baking, "_settle", failing)
    before = snapshot_all()
    images = sorted(bpy.data.images.keys())
    with pytest.raises(RuntimeError, match="no memory for the image"):
        run(rays=8, bake_image=True, texture_size=64)
    assert snapshot_all() == before
    assert sorted(bpy.data.images.keys()) == images
