# SPDX-License-Identifier: GPL-3.0-or-later
"""Tests inside real Blender (bpy from PyPI). Run by scripts/test_blender.sh in .venv-bpy45
(bpy 4.5 LTS, Python 3.11) and .venv-bpy51 (bpy >= 5.1, Python 3.13):

    BLENDER_USER_RESOURCES=<empty dir> SDF_EXTENSION_ZIP=dist/...zip python -m pytest tests/blender

Collecting installs the built extension zip through Blender's own install path
(extensions.package_install_files) into the isolated user directory and enables it; every
test starts from an empty factory file.
"""

import importlib.util
import os
import sys
import tempfile
from pathlib import Path

if importlib.util.find_spec("bpy") is None:
    # Outside a bpy venv (`pytest tests` in .venv): nothing here can run.
    collect_ignore_glob = ["*.py"]
else:
    # Blender reads BLENDER_USER_RESOURCES when bpy is imported: never touch the real
    # user's Blender directories.
    os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="sdf-blender-user-"))
    sys.path.insert(0, str(Path(__file__).parent))
    from blender_session import *  # noqa: F403, E402  (installs the extension; fixtures)
