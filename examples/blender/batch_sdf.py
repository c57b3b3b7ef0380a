# SPDX-License-Identifier: GPL-3.0-or-later
"""Shape Diameter of every mesh in a folder, headless, with the Blender extension installed:

    blender -b template.blend --python-exit-code 1 --python batch_sdf.py -- MESHES OUT [--rays 30]
        [--points faces|vertices] [--normalize linear|log]

Each .obj, .ply, .stl, .glb or .gltf in MESHES is imported into the open file (template.blend:
your lights, camera, materials; leave it out for Blender's default scene), computed by the
extension (attributes sdf, sdf_normalized and the color attribute sdf_color), then saved as
OUT/<name>.blend, with the values as OUT/<name>.sdf.npz (one float32 array per object, per
polygon or per vertex, in world units). The imported objects are removed before the next mesh.
Any failure ends Blender with exit status 1 (--python-exit-code 1), after the other meshes.
"""

import argparse
import importlib
import sys
import traceback
from pathlib import Path

import bpy
import numpy as np

# The extension's module: bl_ext.<repository>.<id>; "user_default" for a zip installed from
# disk or with `blender --command extension install-file -r user_default`.
EXTENSION = "bl_ext.user_default.shape_diameter"

IMPORTERS = {
    ".obj": lambda path: bpy.ops.wm.obj_import(filepath=path),
    ".ply": lambda path: bpy.ops.wm.ply_import(filepath=path),
    ".stl": lambda path: bpy.ops.wm.stl_import(filepath=path),
    ".glb": lambda path: bpy.ops.import_scene.gltf(filepath=path),
    ".gltf": lambda path: bpy.ops.import_scene.gltf(filepath=path),
}


def arguments():
    argv = sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else []
    parser = argparse.ArgumentParser(prog="batch_sdf.py", description=__doc__.split("\n")[0])
    parser.add_argument("meshes", type=Path, help="folder of meshes")
    parser.add_argument("out", type=Path, help="folder for the results (made if missing)")
    parser.add_argument("--rays", type=int, default=30)
    parser.add_argument("--points", choices=("faces", "vertices"), default="faces")
    parser.add_argument("--normalize", choices=("linear", "log"), default="linear")
    return parser.parse_args(argv)


def extension_api():
    """The extension's scripting API, enabling the extension if Blender has not (with
    --factory-startup, or in the bpy module from PyPI, preferences are not loaded)."""
    if EXTENSION not in bpy.context.preferences.addons:
        import addon_utils  # Blender's own module: importable once bpy is

        addon_utils.enable(EXTENSION, default_set=True, handle_error=None)
    return importlib.import_module(EXTENSION + ".api")


def process(api, path, args):
    before = set(bpy.data.objects)
    IMPORTERS[path.suffix.lower()](str(path))
    objects = [ob for ob in bpy.data.objects if ob not in before and ob.type == "MESH"]
    try:
        results = api.compute_objects(
            objects, rays=args.rays, points=args.points, normalize=args.normalize
        )
        np.savez(args.out / f"{path.stem}.sdf.npz", **{r.object_name: r.values for r in results})
        bpy.ops.wm.save_as_mainfile(filepath=str(args.out / f"{path.stem}.blend"), copy=True)
        for r in results:
            print(
                f"{path.name}: {r.object_name}: {len(r.values)} {r.domain.lower()} values, "
                f"min {r.values.min():.4g}, median {np.median(r.values):.4g}, "
                f"max {r.values.max():.4g}; {r.engine}, {r.timings['total']:.2f} s"
            )
    finally:
        for ob in [ob for ob in bpy.data.objects if ob not in before]:
            data = ob.data
            bpy.data.objects.remove(ob)
            if isinstance(data, bpy.types.Mesh) and data.users == 0:
                bpy.data.meshes.remove(data)


def run_folder(args, process):
    """process(api, path, args) on every mesh of args.meshes, into args.out; a mesh that fails
    is reported and the others go on, then the run exits non-zero naming the failed ones.
    Returns the meshes' paths."""
    paths = sorted(p for p in args.meshes.iterdir() if p.suffix.lower() in IMPORTERS)
    if not paths:
        raise SystemExit(f"no meshes ({', '.join(IMPORTERS)}) in {args.meshes}")
    args.out.mkdir(parents=True, exist_ok=True)
    api = extension_api()
    failed = []
    for path in paths:
        try:
            process(api, path, args)
        except Exception:
            traceback.print_exc()
            failed.append(path.name)
    if failed:
        raise SystemExit(f"failed: {', '.join(failed)}")
    return paths


def main():
    args = arguments()
    paths = run_folder(args, process)
    print(f"done: {len(paths)} meshes -> {args.out}")


if __name__ == "__main__":
    main()
