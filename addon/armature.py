# SPDX-License-Identifier: GPL-3.0-or-later
"""The proto-skeleton as a Blender armature: one bone per segment (head, tail and parent from
shape_diameter.rigging.proto_skeleton, in the mesh's coordinates), an armature object
parented to the mesh with no offset (so that the bones sit on the mesh wherever it is), and
an Armature modifier on the mesh, deforming it through the vertex groups named after the
bones. A starting point for rigging, editable like any armature.

Called on the main thread only. Bones can only be made in Edit Mode: the armature is made the
only selected and active object for that, and the selection and active object are put back.
"""

import bpy

MODIFIER = "Shape Diameter Parts"
MARK = "shape_diameter_parts"  # custom property of the armature objects this add-on made


def _link(context, ob, arm):
    """Links the armature into the mesh's first collection where that is in this view layer
    (Edit Mode needs it there), else into the scene's collection."""
    for collection in ob.users_collection[:1]:
        collection.objects.link(arm)
        if arm.name in context.view_layer.objects:
            return
        collection.objects.unlink(arm)
    context.scene.collection.objects.link(arm)


def build(context, ob, names, skeleton, name, undo):
    """A new armature object `name` (Blender adds a suffix when the name is taken: the caller
    renames it once the old one is gone) with one bone per segment. Returns the object."""
    data = bpy.data.armatures.new(name)
    arm = bpy.data.objects.new(name, data)
    made = [arm, data]

    def take_back():
        for thing in made:
            if isinstance(thing, bpy.types.Object):
                bpy.data.objects.remove(thing)
            elif thing.users == 0:
                bpy.data.armatures.remove(thing)

    undo.append(take_back)
    arm[MARK] = True
    data.display_type = "STICK"
    arm.show_in_front = True
    _link(context, ob, arm)
    arm.parent = ob
    view_layer = context.view_layer
    active, selected = view_layer.objects.active, list(context.selected_objects)
    try:
        for other in selected:
            other.select_set(False)
        arm.select_set(True)
        view_layer.objects.active = arm
        bpy.ops.object.mode_set(mode="EDIT")
        try:
            _add_bones(data, names, skeleton)
        finally:
            bpy.ops.object.mode_set(mode="OBJECT")
    finally:
        arm.select_set(False)
        for other in selected:
            other.select_set(True)
        view_layer.objects.active = active
    return arm


def _add_bones(data, names, skeleton):
    bones = []
    for index, bone_name in enumerate(names):
        bone = data.edit_bones.new(bone_name)
        bone.head = tuple(skeleton.head[index])
        bone.tail = tuple(skeleton.tail[index])
        bones.append(bone)
    for index, bone in enumerate(bones):
        parent = int(skeleton.parent[index])
        if parent >= 0:
            bone.parent = bones[parent]
            bone.use_connect = bool(skeleton.connected[index])


def attach(ob, arm, old_modifier, undo):
    """Points the Armature modifier at `arm`: the previous run's (`old_modifier`, ours) or a
    new one at the end of the stack."""
    modifier = ob.modifiers.get(old_modifier) if old_modifier else None
    if modifier is not None and modifier.type == "ARMATURE":
        before = modifier.object
        undo.append(lambda: setattr(modifier, "object", before))
    else:
        modifier = ob.modifiers.new(MODIFIER, "ARMATURE")
        undo.append(lambda: ob.modifiers.remove(ob.modifiers[modifier.name]))
    modifier.object = arm
    modifier.use_vertex_groups = True
    modifier.use_bone_envelopes = False
    return modifier


def remove(arm):
    """Removes an armature object this add-on made, and its data when nothing else uses it."""
    data = arm.data
    bpy.data.objects.remove(arm)
    if data is not None and data.users == 0:
        bpy.data.armatures.remove(data)
