# SPDX-License-Identifier: GPL-3.0-or-later
# The headless example of docs/blender.md, run as it is by tests/blender/test_examples.py:
#   blender -b template.blend --python-exit-code 1 --python sdf_folder.py -- MESHES OUT
# Every .obj in MESHES, imported into template.blend, gets the Shape Diameter; the results are
# saved as OUT/<name>.blend (attributes sdf, sdf_normalized, sdf_color) and OUT/<name>.sdf.npz.
# isort: skip_file
import sys
from pathlib import Path

import bpy
import addon_utils  # Blender's own module (importable once bpy is, in the bpy package)
import numpy as np

addon_utils.enable("bl_ext.user_default.shape_diameter", default_set=True)  # if not yet
from bl_ext.user_default.shape_diameter import api  # noqa: E402

meshes, out = map(Path, sys.argv[sys.argv.index("--") + 1 :])
out.mkdir(parents=True, exist_ok=True)
for path in sorted(meshes.glob("*.obj")):
    before = set(bpy.data.objects)
    bpy.ops.wm.obj_import(filepath=str(path))
    new = [ob for ob in bpy.data.objects if ob not in before]
    results = api.compute_objects(new, rays=30)  # raises on a failure: exit status 1
    np.savez(out / f"{path.stem}.sdf.npz", **{r.object_name: r.values for r in results})
    bpy.ops.wm.save_as_mainfile(filepath=str(out / f"{path.stem}.blend"), copy=True)
    for ob in new:
        bpy.data.objects.remove(ob)
    print(f"{path.name}: {', '.join(f'{r.object_name} {len(r.values)} values' for r in results)}")
