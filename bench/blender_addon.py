# SPDX-License-Identifier: GPL-3.0-or-later
"""What the benchmarks run in Blender (bpy from PyPI) share: a user folder of their own (so
that installing the extension touches no real Blender set-up), the newest extension zip
scripts/build_extension.sh made, and that zip installed."""

import glob
import importlib
import os
import tempfile

os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="sdf-bench-user-"))

import bpy  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ADDON = "bl_ext.user_default.shape_diameter"


def newest_zip():
    """dist's newest linux-x64 extension zip, or None."""
    found = sorted(glob.glob(os.path.join(ROOT, "dist", "shape_diameter-*-linux_x64.zip")))
    return found[-1] if found else None


def install(path, modules):
    """Installs and enables the extension from `path` (once); returns {name: its module}."""
    if ADDON not in bpy.context.preferences.addons:
        result = bpy.ops.extensions.package_install_files(
            filepath=os.path.abspath(path), repo="user_default", enable_on_install=True
        )
        assert result == {"FINISHED"}, result
    return {name: importlib.import_module(f"{ADDON}.{name}") for name in modules}
