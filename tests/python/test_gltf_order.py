"""glTF/GLB scenes come in the file's node order, whatever order trimesh walks them in."""

import base64
import json
import re
import struct

import numpy as np
import pytest
from shape_diameter.mesh_io import load_mesh, load_mesh_with_uvs


def _primitive(x, views, accessors, chunks):
    """One triangle with its corner at (x, 0, 0) and u = x at every corner, as a primitive."""
    arrays = [
        (np.array([0, 1, 2], np.uint32), 5125, "SCALAR"),
        (np.array([[x, 0, 0], [x + 1, 0, 0], [x, 1, 0]], np.float32), 5126, "VEC3"),
        (np.full((3, 2), [x, 0.5], np.float32), 5126, "VEC2"),
    ]
    first = len(accessors)
    for array, component, kind in arrays:
        offset = sum(len(chunk) for chunk in chunks)
        chunks.append(array.tobytes())
        views.append({"buffer": 0, "byteOffset": offset, "byteLength": array.nbytes})
        accessor = {
            "bufferView": len(views) - 1,
            "componentType": component,
            "count": len(array),
            "type": kind,
        }
        if kind == "VEC3":
            accessor.update(min=array.min(0).tolist(), max=array.max(0).tolist())
        accessors.append(accessor)
    # trimesh keeps a primitive's UVs only when it has a material.
    return {
        "attributes": {"POSITION": first + 1, "TEXCOORD_0": first + 2},
        "indices": first,
        "material": 0,
    }


def _scene_file(tmp_path, suffix):
    """Nodes listed so that the file's depth-first order is not trimesh's stack order:
    a mesh node with children, children sharing a name, a mesh of three primitives, a
    group without a mesh, a node whose name is another's index, one named 'world'."""
    views, accessors, chunks = [], [], []
    meshes = [{"primitives": [_primitive(x, views, accessors, chunks)]} for x in range(6)]
    meshes.append({"primitives": [_primitive(x, views, accessors, chunks) for x in (10, 11, 12)]})
    nodes = [
        {"mesh": 0, "children": [1, 2]},
        {"mesh": 1, "name": "twin"},
        {"mesh": 2, "name": "twin"},
        {"mesh": 6, "translation": [0, 0, 5]},
        {"name": "group", "children": [5, 6]},
        {"mesh": 3},
        {"mesh": 4, "name": "5", "children": [7]},
        {"mesh": 5, "name": "world"},
    ]
    data = b"".join(chunks)
    header = {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0, 3, 4]}],
        "nodes": nodes,
        "meshes": meshes,
        "materials": [{}],
        "buffers": [{"byteLength": len(data)}],
        "bufferViews": views,
        "accessors": accessors,
    }
    path = tmp_path / f"scene{suffix}"
    if suffix == ".gltf":
        header["buffers"][0]["uri"] = (
            "data:application/octet-stream;base64," + base64.b64encode(data).decode()
        )
        path.write_text(json.dumps(header))
    else:
        text = json.dumps(header).encode()
        text += b" " * (-len(text) % 4)
        data += b"\0" * (-len(data) % 4)
        body = (
            struct.pack("<II", len(text), 0x4E4F534A)
            + text
            + struct.pack("<II", len(data), 0x004E4942)
            + data
        )
        path.write_bytes(b"glTF" + struct.pack("<II", 2, 12 + len(body)) + body)
    return path


# Depth first, roots in the scene's order, a node before its children, primitives in order.
FILE_ORDER = [0, 1, 2, 10, 11, 12, 3, 4, 5]


@pytest.mark.parametrize("suffix", [".gltf", ".glb"])
def test_gltf_triangles_come_in_the_files_node_order(tmp_path, suffix):
    vertices, triangles = load_mesh(_scene_file(tmp_path, suffix))
    corners = vertices[triangles]
    np.testing.assert_array_equal(corners[:, 0, 0], FILE_ORDER)
    # The translated node keeps its transform: its three primitives sit at z = 5.
    np.testing.assert_array_equal(corners[:, 0, 2], [5 if x >= 10 else 0 for x in FILE_ORDER])


@pytest.mark.parametrize("suffix", [".gltf", ".glb"])
def test_gltf_uvs_follow_their_triangles(tmp_path, suffix):
    vertices, triangles, uvs = load_mesh_with_uvs(_scene_file(tmp_path, suffix))
    assert uvs is not None
    np.testing.assert_array_equal(
        uvs[:, :, 0], vertices[triangles][:, :, 0].min(1)[:, None] * np.ones((1, 3))
    )


def test_a_gltf_node_tree_that_cannot_be_followed_is_a_clear_error(tmp_path):
    path = _scene_file(tmp_path, ".gltf")
    header = json.loads(path.read_text())
    header["nodes"][4]["children"] = [5, "six"]
    path.write_text(json.dumps(header))
    with pytest.raises(ValueError, match=r"scene\.gltf: cannot read mesh"):
        load_mesh(path)


# What trimesh reads wrongly without a word (game assets, each computed as 'ok'):
# refused, saying what.
UNREAD = {
    "draco": (
        lambda h: h.update(extensionsRequired=["KHR_draco_mesh_compression"]),
        "requires the glTF extension KHR_draco_mesh_compression",
    ),
    "quantized positions": (
        lambda h: h["accessors"][1].update(normalized=True),
        "mesh 0 primitive 0's POSITION is stored as normalized integers",
    ),
    "sparse positions": (
        lambda h: h["accessors"][1].update(sparse={"count": 1}),
        "mesh 0 primitive 0's POSITION is a sparse accessor",
    ),
    "triangle fan": (
        lambda h: h["meshes"][2]["primitives"][0].update(mode=6),
        "mesh 2 primitive 0 is a triangle fan",
    ),
    "camera with a mesh": (
        lambda h: h["nodes"][3].update(camera=0),
        "node 3 is a camera holding a mesh",
    ),
}


@pytest.mark.parametrize("case", sorted(UNREAD))
def test_what_the_reader_would_get_wrong_is_refused(tmp_path, case):
    change, message = UNREAD[case]
    path = _scene_file(tmp_path, ".gltf")
    header = json.loads(path.read_text())
    change(header)
    path.write_text(json.dumps(header))
    with pytest.raises(ValueError, match=re.escape(message)):
        load_mesh(path)


def test_harmless_required_extensions_are_read(tmp_path):
    path = _scene_file(tmp_path, ".gltf")
    header = json.loads(path.read_text())
    header["extensionsRequired"] = ["KHR_materials_unlit", "KHR_texture_transform"]
    path.write_text(json.dumps(header))
    assert len(load_mesh(path)[1]) == len(FILE_ORDER)


def test_quantized_uvs_are_refused_only_where_uvs_are_read(tmp_path):
    path = _scene_file(tmp_path, ".gltf")
    header = json.loads(path.read_text())
    header["accessors"][2].update(normalized=True)  # the first primitive's TEXCOORD_0
    path.write_text(json.dumps(header))
    assert len(load_mesh(path)[1]) == len(FILE_ORDER)
    with pytest.raises(ValueError, match="TEXCOORD_0 is stored as normalized integers"):
        load_mesh_with_uvs(path)
