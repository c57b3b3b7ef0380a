# SPDX-License-Identifier: GPL-3.0-or-later
"""Shape Diameter: the Blender extension. This file only registers.

props.py     the run options as properties; the per-scene panel settings
operators.py Compute Shape Diameter (object.shape_diameter), Show SDF Colors, and the
             worker-thread machinery the run operators share
segment_operator.py  Segment by Thickness (object.shape_diameter_segment)
ui/          the 3D view sidebar panel (tab "SDF") and the preferences
process.py   one run: check and read objects, compute (worker thread), write all or nothing
segmenting.py, part_writing.py, part_outputs.py, armature.py
             a segmentation run in the same three steps; its bpy writers; the proto-skeleton
mesh_data.py bpy <-> numpy with foreach_get/foreach_set
core.py      the one module that imports the native package, lazily
api.py       for scripts: compute_object(obj, **options), segment_object(obj, **options)

Nothing here imports the native core: register() works even where it cannot load.
"""

from . import operators, props, segment_operator, ui

_modules = (props, operators, segment_operator, ui)


def register():
    for module in _modules:
        module.register()


def unregister():
    for module in reversed(_modules):
        module.unregister()
