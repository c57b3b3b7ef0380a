# SPDX-License-Identifier: GPL-3.0-or-later
"""The Blender test session (imported by conftest.py where bpy is importable): installs the
extension zip into the isolated user directory, and gives every test an empty file."""

import glob
import os
from pathlib import Path

import bpy
import pytest

ROOT = Path(__file__).resolve().parents[2]
ADDON = "bl_ext.user_default.shape_diameter"


def extension_zip():
    path = os.environ.get("SDF_EXTENSION_ZIP")
    if path:
        return os.path.abspath(path)
    found = sorted(glob.glob(str(ROOT / "dist" / "shape_diameter-*-linux_x64.zip")))
    if not found:
        pytest.exit("no extension zip: run scripts/build_extension.sh first", returncode=2)
    return found[-1]


def _install():
    user = os.environ["BLENDER_USER_RESOURCES"]
    assert bpy.utils.user_resource("EXTENSIONS").startswith(user)
    result = bpy.ops.extensions.package_install_files(
        filepath=extension_zip(), repo="user_default", enable_on_install=True
    )
    assert result == {"FINISHED"}, result
    assert ADDON in bpy.context.preferences.addons
    # Saved, as a user's would be: a Blender binary started with this user directory has it
    # enabled (bpy from PyPI does not read preferences; the examples enable it themselves).
    bpy.ops.wm.save_userpref()


# Installed before the test modules are collected: they import the package from it.
if ADDON not in bpy.context.preferences.addons:
    _install()


@pytest.fixture(scope="session")
def extension():
    import importlib

    return importlib.import_module(ADDON)


@pytest.fixture(autouse=True)
def empty_file(extension):
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    yield
    for ob in list(bpy.context.view_layer.objects):
        if ob.mode != "OBJECT":
            bpy.context.view_layer.objects.active = ob
            bpy.ops.object.mode_set(mode="OBJECT")
