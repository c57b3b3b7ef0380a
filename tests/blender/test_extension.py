# SPDX-License-Identifier: GPL-3.0-or-later
"""The installed extension: where Blender put it, what it registers, that its panels and
preferences draw, that unregister leaves nothing behind, and that a core which cannot load
does not stop it from registering."""

import functools
import os
import subprocess
import sys
import textwrap
import types

import addon_utils
import bpy
import pytest
import tomllib
from helpers import ADDON, ROOT, addon_module, import_obj, select_only

OPERATORS = ("OBJECT_OT_shape_diameter", "VIEW3D_OT_shape_diameter_show")
PANELS = (
    "VIEW3D_PT_shape_diameter",
    "VIEW3D_PT_shape_diameter_rays",
    "VIEW3D_PT_shape_diameter_mesh",
    "VIEW3D_PT_shape_diameter_smoothing",
    "VIEW3D_PT_shape_diameter_output",
    "VIEW3D_PT_shape_diameter_bake",
    "VIEW3D_PT_shape_diameter_engine",
    "VIEW3D_PT_shape_diameter_result",
)
ICONS = {
    item.identifier
    for item in bpy.types.UILayout.bl_rna.functions["label"].parameters["icon"].enum_items
}


def test_installed_from_the_zip_into_the_isolated_user_directory():
    user = os.environ["BLENDER_USER_RESOURCES"]
    module = addon_module()
    assert module.__file__.startswith(
        os.path.join(user, "extensions", "user_default", "shape_diameter")
    )
    import shape_diameter

    site = os.path.join(
        user,
        "extensions",
        ".local",
        "lib",
        f"python{sys.version_info[0]}.{sys.version_info[1]}",
        "site-packages",
    )
    assert shape_diameter.__file__.startswith(site), shape_diameter.__file__
    with open(os.path.join(os.path.dirname(module.__file__), "blender_manifest.toml"), "rb") as f:
        manifest = tomllib.load(f)
    assert shape_diameter.__version__ == manifest["version"]
    ext = ".cpython-{}{}-x86_64-linux-gnu.so".format(*sys.version_info[:2])
    assert shape_diameter._core.__file__.endswith(ext)


def test_everything_is_registered():
    for name in (*OPERATORS, *PANELS):
        assert getattr(bpy.types, name).is_registered, name
    assert isinstance(
        bpy.types.Scene.bl_rna.properties["shape_diameter"], bpy.types.PointerProperty
    )
    prefs = bpy.context.preferences.addons[ADDON].preferences
    assert type(prefs).__name__ == "ShapeDiameterPreferences"
    import shape_diameter

    # Dynamic enums list no items through RNA outside drawing: ask the add-on's callback.
    props = addon_module("props")
    names = [e["name"] for e in shape_diameter.engines()]
    assert names[0] == "cpu"
    best = ["opencl"] if len(names) > 1 else []  # any OpenCL device, when there is one
    assert [item[0] for item in props.engine_items(False)] == ["auto", "cpu", *best, *names[1:]]
    assert [item[0] for item in props.engine_items(True)] == [
        "DEFAULT",
        "auto",
        "cpu",
        *best,
        *names[1:],
    ]
    operator = bpy.ops.object.shape_diameter.get_rna_type()
    assert {
        "rays",
        "cone_angle",
        "sampling",
        "points",
        "engine",
        "normalize",
        "use_modifiers",
        "apply_scale",
        "attribute_name",
        "normalized_name",
        "color_name",
        "accel",
        "smoothing",
        "smoothing_rings",
        "smoothing_iterations",
        "smoothing_rule",
        "texture_size",
        "texture_radius",
        "bake_image",
        "uv_map",
        "image_name",
    } <= set(operator.properties.keys())
    panel = bpy.types.VIEW3D_PT_shape_diameter
    assert (panel.bl_space_type, panel.bl_region_type, panel.bl_category) == (
        "VIEW_3D",
        "UI",
        "SDF",
    )
    for name in PANELS[1:]:
        assert getattr(bpy.types, name).bl_parent_id == "VIEW3D_PT_shape_diameter"


class FakeLayout:
    """Stands in for UILayout, which exists only while Blender draws a region: checks what
    real drawing would check (properties and operators exist, icons are valid) and records
    what was drawn."""

    def __init__(self, log):
        object.__setattr__(self, "log", log)

    def __setattr__(self, name, value):  # use_property_split, scale_y, enabled, ...
        assert name in bpy.types.UILayout.bl_rna.properties, name

    def _sub(self, *args, **kwargs):
        return FakeLayout(self.log)

    row = column = box = split = column_flow = grid_flow = _sub

    def _icon(self, kwargs):
        assert kwargs.get("icon", "NONE") in ICONS, kwargs.get("icon")

    def label(self, text="", **kwargs):
        self._icon(kwargs)
        self.log.append(("label", text))

    def progress(self, factor=0.0, text="", **kwargs):
        self.log.append(("progress", text))

    def prop(self, data, name, **kwargs):
        self._icon(kwargs)
        rna = getattr(data, "bl_rna", None)
        assert (name in rna.properties) if rna is not None else hasattr(data, name), name
        getattr(data, name)
        self.log.append(("prop", name))

    def prop_search(self, data, name, search_data, search_name, **kwargs):
        self.prop(data, name, **kwargs)
        assert search_name in search_data.bl_rna.properties, search_name
        self.log.append(("prop_search", name))

    def operator(self, idname, **kwargs):
        self._icon(kwargs)
        category, name = idname.split(".")
        rna = getattr(getattr(bpy.ops, category), name).get_rna_type()
        self.log.append(("operator", idname))
        return OperatorProperties(rna)


class OperatorProperties:
    def __init__(self, rna):
        object.__setattr__(self, "rna", rna)

    def __setattr__(self, name, value):
        prop = self.rna.properties[name]  # KeyError: no such property
        if prop.type == "ENUM" and len(prop.enum_items):  # dynamic enums list none here
            assert value in [i.identifier for i in prop.enum_items], value


def draw(cls, context, target=None):
    """Calls cls.draw as Blender would, with a FakeLayout; returns what was drawn."""
    log = []
    layout = FakeLayout(log)
    self = types.SimpleNamespace(layout=layout)
    for name in ("draw_settings",):
        if hasattr(cls, name):
            setattr(self, name, functools.partial(getattr(cls, name), self))
    if target is not None:  # draw(self) reads the preferences' properties from self
        self = types.SimpleNamespace(
            layout=layout,
            bl_rna=target.bl_rna,
            **{
                name: getattr(target, name)
                for name in target.bl_rna.properties.keys()  # noqa: SIM118 (a bpy collection)
                if name != "rna_type"
            },
        )
    cls.draw(self, context)
    return log


def test_panels_and_preferences_draw():
    for selected in (False, True):
        bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
        if selected:
            ob = import_obj("suzanne.obj")
            assert bpy.ops.object.shape_diameter() == {"FINISHED"}
            select_only(ob)
        settings = bpy.context.scene.shape_diameter
        for smoothing in ("none", "kring", "projected", "texture"):
            settings.smoothing = smoothing
            settings.bake_image = smoothing != "none"
            for name in PANELS:
                cls = getattr(bpy.types, name)
                if hasattr(cls, "poll"):
                    assert cls.poll(bpy.context), name
                assert draw(cls, bpy.context), name
        smoothing = draw(bpy.types.VIEW3D_PT_shape_diameter_smoothing, bpy.context)
        assert ("prop", "texture_radius") in smoothing
        bake = draw(bpy.types.VIEW3D_PT_shape_diameter_bake, bpy.context)
        assert ("prop_search" if selected else "prop", "uv_map") in bake
        main = draw(bpy.types.VIEW3D_PT_shape_diameter, bpy.context)
        assert ("operator", "object.shape_diameter") in main
        result = draw(bpy.types.VIEW3D_PT_shape_diameter_result, bpy.context)
        if selected:
            assert ("label", "sdf: FLOAT on FACE") in result
            assert ("label", "sdf_color: BYTE_COLOR on CORNER") in result
    prefs = bpy.context.preferences.addons[ADDON].preferences
    log = draw(type(prefs), bpy.context, target=prefs)
    assert ("prop", "default_engine") in log
    assert any(kind == "label" and text.startswith("shape_diameter ") for kind, text in log)

    operator = addon_module("operators").OBJECT_OT_shape_diameter
    names = bpy.ops.object.shape_diameter.get_rna_type().properties.keys()
    for smoothing in ("none", "kring", "projected", "texture"):
        fake = types.SimpleNamespace(
            layout=FakeLayout([]),
            sampling="random",
            smoothing=smoothing,
            **{n: 0 for n in names if n not in ("rna_type", "sampling", "smoothing")},
        )
        operator.draw(fake, bpy.context)


def test_default_engine_preference():
    prefs = bpy.context.preferences.addons[ADDON].preferences
    operators = addon_module("operators")
    assert prefs.default_engine == "auto"
    prefs.default_engine = "cpu"
    try:
        assert prefs.default_engine_name == "cpu"
        assert operators.resolve_engine(bpy.context, "DEFAULT") == "cpu"
        prefs.default_engine_name = "an-engine-that-is-gone"
        assert prefs.default_engine == "auto"
    finally:
        prefs.default_engine = "auto"


def fake_engines(*devices):
    """shape_diameter.engines() as a machine with these OpenCL devices ((name, type) pairs, in
    the drivers' order) lists them."""
    found = [{"name": "cpu", "type": "CPU", "threads": 2, "description": "2 threads"}]
    for index, (device, kind) in enumerate(devices):
        found.append(
            {
                "name": f"opencl:{index}",
                "index": index,
                "device": device,
                "type": kind,
                "platform": "Test",
                "memory": 8 << 30,
                "description": f"{device} (Test, 8192 MiB)",
            }
        )
    return found


def test_the_engine_menu_offers_the_best_opencl_device_and_each_by_name(monkeypatch):
    # The menu listed devices as 'opencl:0', 'opencl:1' (their indices for labels) and had no
    # 'opencl', the best device, which shape_diameter.compute() takes.
    core, props = addon_module("core"), addon_module("props")
    monkeypatch.setattr(
        core,
        "engines",
        lambda refresh=False: fake_engines(("GPU A", "GPU"), ("GPU B", "GPU"), ("GPU B", "GPU")),
    )
    items = props.engine_items(False)
    assert [item[0] for item in items] == [
        "auto",
        "cpu",
        "opencl",
        "opencl:all",
        "opencl:0",
        "opencl:1",
        "opencl:2",
    ]
    labels = {item[0]: item[1] for item in items}
    # Two devices of one name (two GPUs of a model) are told apart.
    assert [labels[f"opencl:{i}"] for i in range(3)] == ["GPU A", "GPU B", "GPU B #2"]
    assert "engine='opencl:1'" in {item[0]: item[2] for item in items}["opencl:1"]
    assert [item[0] for item in props.engine_items(True)][:2] == ["DEFAULT", "auto"]
    monkeypatch.setattr(core, "engines", lambda refresh=False: fake_engines())
    assert [item[0] for item in props.engine_items(False)] == ["auto", "cpu"]  # no OpenCL


def test_the_engine_menu_offers_every_device_at_once_where_that_is_two_or_more(monkeypatch):
    # compute(engine='opencl:all') shares the points between every GPU (every OpenCL device
    # where there is none); the menu offered no way to ask for it.
    core, props = addon_module("core"), addon_module("props")

    def menu(*devices):
        monkeypatch.setattr(core, "engines", lambda refresh=False: fake_engines(*devices))
        return {item[0]: item[1] for item in props.engine_items(False)}

    assert menu(("GPU A", "GPU"), ("GPU B", "GPU"))["opencl:all"] == "All GPUs"
    assert "opencl:all" not in menu(("GPU A", "GPU"), ("PoCL", "CPU"))  # one GPU: the same
    assert "opencl:all" not in menu(
        ("PoCL", "CPU"),
    )
    assert menu(("PoCL", "CPU"), ("Intel CPU", "CPU"))["opencl:all"] == "All OpenCL Devices"
    # A device named "all" keeps a key of its own: a saved choice of it reads back as it.
    menu(("all", "GPU"), ("GPU B", "GPU"))
    keys = [key for key, _ in props.engine_choices(False)]
    assert len(set(keys)) == len(keys)
    assert dict(props.engine_choices(False))["opencl:all"][0] == "opencl:0"


def test_a_chosen_device_is_kept_by_name_when_the_devices_change(monkeypatch):
    # An engine is stored as a name, not the enum's index; a device was stored as
    # 'opencl:<index>', which named another device once the drivers listed them otherwise.
    core, operators = addon_module("core"), addon_module("operators")
    prefs = bpy.context.preferences.addons[ADDON].preferences
    settings = bpy.context.scene.shape_diameter
    devices = [("GPU A", "GPU"), ("GPU B", "GPU")]
    monkeypatch.setattr(core, "engines", lambda refresh=False: fake_engines(*devices))
    try:
        prefs.default_engine = "opencl:1"
        settings.engine = "opencl:1"
        assert (prefs.default_engine, settings.engine) == ("opencl:1", "opencl:1")
        devices.reverse()  # a driver update, another GPU: GPU B is listed first now
        assert (prefs.default_engine, settings.engine) == ("opencl:0", "opencl:0")
        assert operators.resolve_engine(bpy.context, "DEFAULT") == "opencl:0"
        del devices[0]  # GPU B is gone: the first item again, not whatever took its place
        assert (prefs.default_engine, settings.engine) == ("auto", "DEFAULT")
        prefs.default_engine = "opencl"  # any device, whichever is best here
        devices[:] = [("GPU C", "GPU")]
        assert prefs.default_engine == "opencl"
    finally:
        prefs.default_engine = "auto"


def test_unregister_leaves_nothing_behind():
    module = addon_module()
    classes = [*module.operators.classes, *module.ui.classes, *module.props.classes]
    addon_utils.disable(ADDON, default_set=True)
    try:
        assert ADDON not in bpy.context.preferences.addons
        for cls in classes:
            assert not cls.is_registered, cls
        for name in (*OPERATORS, *PANELS, "ShapeDiameterSettings", "ShapeDiameterPreferences"):
            assert not hasattr(bpy.types, name), name
        assert "shape_diameter" not in bpy.types.Scene.bl_rna.properties
        with pytest.raises((AttributeError, KeyError)):
            bpy.ops.object.shape_diameter.get_rna_type()
    finally:
        addon_utils.enable(ADDON, default_set=True)
    assert ADDON in bpy.context.preferences.addons
    assert bpy.types.OBJECT_OT_shape_diameter.is_registered


def test_registers_when_the_native_core_cannot_load():
    """A Blender whose dynamic loader cannot load the core (simulated by an import hook in a
    fresh process): the add-on registers, the panel says why, the operator reports it."""
    script = textwrap.dedent(f"""
        import sys
        class Broken:
            def find_spec(self, name, path=None, target=None):
                if name.split(".")[0] == "shape_diameter":
                    raise ImportError("libstdc++.so.6: version `GLIBCXX_3.4.99' not found")
        sys.meta_path.insert(0, Broken())
        import bpy
        import addon_utils
        addon_utils.enable({ADDON!r}, default_set=True, handle_error=None)
        assert bpy.types.VIEW3D_PT_shape_diameter.is_registered
        from {ADDON} import core
        loaded, text = core.status()
        assert not loaded and "GLIBCXX_3.4.99" in text, text
        from {ADDON} import props
        engines = [item[0] for item in props.engine_items(True)]
        assert engines == ["DEFAULT", "auto"], engines
        bpy.ops.mesh.primitive_monkey_add()
        names = [a.name for a in bpy.context.active_object.data.attributes]
        try:
            bpy.ops.object.shape_diameter()
        except RuntimeError as ex:
            assert "could not be loaded" in str(ex), ex
        else:
            raise AssertionError("no error reported")
        assert [a.name for a in bpy.context.active_object.data.attributes] == names
        print("CORE-UNAVAILABLE-OK")
    """)
    out = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, cwd=ROOT, timeout=300
    )
    assert "CORE-UNAVAILABLE-OK" in out.stdout, out.stdout[-3000:] + out.stderr[-3000:]


def test_show_colors_operator():
    """view3d.shape_diameter_show on a stand-in 3D view (headless Blender has none)."""
    show = addon_module("operators").VIEW3D_OT_shape_diameter_show
    assert not bpy.ops.view3d.shape_diameter_show.poll()  # no 3D view here
    shading = types.SimpleNamespace(type="WIREFRAME", color_type="MATERIAL")
    context = types.SimpleNamespace(
        space_data=types.SimpleNamespace(type="VIEW_3D", shading=shading)
    )
    assert show.execute(types.SimpleNamespace(), context) == {"FINISHED"}
    assert (shading.type, shading.color_type) == ("SOLID", "VERTEX")
    enum = bpy.types.View3DShading.bl_rna.properties["color_type"].enum_items
    assert enum["VERTEX"].name == "Attribute"  # what the user sees in the shading popover
