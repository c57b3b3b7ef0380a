# SPDX-License-Identifier: GPL-3.0-or-later
"""Parts by thickness for every mesh in a folder, headless, with the Blender extension installed:

    blender -b template.blend --python-exit-code 1 --python segment_folder.py -- MESHES OUT
        [--clusters 5] [--smoothness 0.26] [--no-armature]

Each .obj, .ply, .stl, .glb or .gltf in MESHES is imported into the open file, segmented by the
extension (face sets, the 'segment' attribute, the 'segment_color' colours, vertex groups
part_01, part_02, ... and a proto-skeleton '<object>_parts' deforming the mesh), then saved as
OUT/<name>.blend, with the labels per polygon as OUT/<name>.segments.npz (one int32 array per
object). The imported objects and their armatures are removed before the next mesh. Any
failure ends Blender with exit status 1 (--python-exit-code 1), after the other meshes.
"""

import argparse
import sys
from pathlib import Path

import bpy
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from batch_sdf import IMPORTERS, run_folder  # noqa: E402


def arguments():
    argv = sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else []
    parser = argparse.ArgumentParser(prog="segment_folder.py", description=__doc__.split("\n")[0])
    parser.add_argument("meshes", type=Path, help="folder of meshes")
    parser.add_argument("out", type=Path, help="folder for the results (made if missing)")
    parser.add_argument("--clusters", type=int, default=5)
    parser.add_argument("--smoothness", type=float, default=0.26)
    parser.add_argument("--no-armature", dest="armature", action="store_false")
    return parser.parse_args(argv)


def process(api, path, args):
    before = set(bpy.data.objects)
    IMPORTERS[path.suffix.lower()](str(path))
    objects = [ob for ob in bpy.data.objects if ob not in before and ob.type == "MESH"]
    try:
        results = api.segment_objects(
            objects, clusters=args.clusters, smoothness=args.smoothness, armature=args.armature
        )
        np.savez(
            args.out / f"{path.stem}.segments.npz", **{r.object_name: r.labels for r in results}
        )
        bpy.ops.wm.save_as_mainfile(filepath=str(args.out / f"{path.stem}.blend"), copy=True)
        for r in results:
            rig = f", armature {r.armature}" if r.armature else ""
            print(
                f"{path.name}: {r.object_name}: {r.segment_count} parts over {len(r.labels)} "
                f"polygons{rig}; {r.timings['total']:.2f} s"
            )
    finally:
        for ob in [ob for ob in bpy.data.objects if ob not in before]:
            data = ob.data
            bpy.data.objects.remove(ob)
            if data is not None and data.users == 0:
                collection = bpy.data.meshes if isinstance(data, bpy.types.Mesh) else None
                collection = collection or (
                    bpy.data.armatures if isinstance(data, bpy.types.Armature) else None
                )
                if collection is not None:
                    collection.remove(data)


def main():
    run_folder(arguments(), process)


if __name__ == "__main__":
    main()
