# SPDX-License-Identifier: GPL-3.0-or-later
"""Tests inside real Blender (bpy from PyPI). Run by scripts/test_blender.sh in .venv-bpy45
(bpy 4.5 LTS, Python 3.11) and .venv-bpy51 (bpy >= 5.1, Python 3.13):

    BLENDER_USER_RESOURCES=<empty dir> SDF_EXTENSION_ZIP=dist/...zip python -m pytest tests/blender

Collecting installs the built extension zip through Blender's own install path
(extensions.package_install_files) into the isolated user directory and enables it; every
test starts from an empty factory file.
"""

import glob
import os
import sys
import tempfile
from pathlib import Path

# Blender reads BLENDER_USER_RESOURCES when bpy is imported: never touch the real user's
# Blender directories.
os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="sdf-blender-user-"))

import bpy
import pytest

sys.path.insert(0, str(Path(__file__).parent))

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
    # Saved, so that a new Blender process with the same user directory has it enabled
    # (the README's headless example relies on this).
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
