# SPDX-License-Identifier: GPL-3.0-or-later
"""The mesh nodes of a glTF/GLB scene in the file's own order.

trimesh walks a glTF node tree with a stack, so its scene lists the mesh nodes roughly
backwards (the last root first, a node's children last to first). Values are written per
triangle, so triangles must come in an order a user can work out from the file: depth first,
roots in the scene's order, each node before its children in their listed order, and a
node's primitives in their order.
"""

from __future__ import annotations

import json
import struct

import trimesh
from trimesh.util import unique_name

_GLB_MAGIC = b"glTF"
_JSON_CHUNK = 0x4E4F534A


def mesh_nodes_in_file_order(header: dict, scene: trimesh.Scene) -> list:
    """trimesh's geometry nodes of ``scene``, loaded from the glTF/GLB file whose JSON is
    ``header`` (json_header), in the file's order. Nodes the file's tree does not account for
    (none are known) keep trimesh's order, after the others. Raises ValueError for a node tree
    it cannot follow."""
    try:
        return _ordered(header, scene)
    except (struct.error, KeyError, TypeError, IndexError, AttributeError) as exc:
        raise ValueError(f"its node tree cannot be followed ({type(exc).__name__}: {exc})") from exc


def _ordered(header: dict, scene: trimesh.Scene) -> list:
    nodes = header.get("nodes", [])
    frames = _frame_names(nodes, scene.graph.base_frame)
    node_frames = set(frames)
    geometry_nodes = set(scene.graph.nodes_geometry)
    children = scene.graph.transforms.children
    ordered = []
    for index in _depth_first(header):
        frame = frames[index]
        if frame in geometry_nodes:
            ordered.append(frame)
        else:  # a mesh of several primitives: trimesh gives each a child frame, in order
            ordered.extend(
                child
                for child in children.get(frame, ())
                if child in geometry_nodes and child not in node_frames
            )
    placed = set(ordered)
    return ordered + [node for node in scene.graph.nodes_geometry if node not in placed]


def json_header(path: str) -> dict:
    with open(path, "rb") as stream:
        data = stream.read()
    if data[:4] == _GLB_MAGIC:
        length, kind = struct.unpack_from("<II", data, 12)
        if kind != _JSON_CHUNK:
            raise ValueError("the GLB's first chunk is not its JSON")
        data = data[20 : 20 + length]
    return json.loads(data)


def _frame_names(nodes: list, base_frame: str) -> list:
    """The frame name trimesh's glTF reader gives each node: its name, or its index for
    one without, made unique in node order; a node named like the base frame is renamed."""
    taken, counts = {}, {}
    for index, node in enumerate(nodes):
        taken[unique_name(node.get("name", str(index)), taken, counts=counts)] = index
    names = [""] * len(nodes)
    for name, index in taken.items():
        names[index] = name
    if base_frame in taken:
        names[taken[base_frame]] = unique_name(base_frame, set(names))
    return names


def _depth_first(header: dict) -> list:
    """Indices of the scene's nodes, each node before its children; a node met twice
    (which the glTF specification forbids) counts once."""
    scenes = header.get("scenes", [])
    scene_index = header.get("scene", 0)
    roots = scenes[scene_index].get("nodes", []) if scene_index < len(scenes) else []
    order, seen = [], set()
    stack = list(reversed(roots))
    nodes = header.get("nodes", [])
    while stack:
        index = stack.pop()
        if index in seen or not 0 <= index < len(nodes):
            continue
        seen.add(index)
        order.append(index)
        stack.extend(reversed(nodes[index].get("children", [])))
    return order
