# SPDX-License-Identifier: GPL-3.0-or-later
"""What the mesh reading fuzzer (tests/fuzz/mesh_io_fuzzer.py) found, kept fixed.

Every input it saved in tests/fuzz/regressions/mesh_io is replayed through the fuzzer's own
check (only ValueError, or a well-formed mesh); each finding also has a readable test here.
"""

import base64
import importlib.util
import json
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("trimesh")

from shape_diameter.mesh_io import load_mesh, load_mesh_with_uvs

FUZZ = Path(__file__).resolve().parents[1] / "fuzz"
SAVED = sorted((FUZZ / "regressions" / "mesh_io").glob("*.bin"))


def _fuzzer():
    spec = importlib.util.spec_from_file_location("mesh_io_fuzzer", FUZZ / "mesh_io_fuzzer.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.filterwarnings("ignore")  # a broken file may make trimesh or numpy warn
@pytest.mark.parametrize("path", SAVED, ids=[p.stem for p in SAVED])
def test_saved_fuzzer_inputs_are_read_or_refused_with_value_error(path):
    _fuzzer().check_one(path.read_bytes())


def test_there_are_saved_inputs():
    assert SAVED, "tests/fuzz/regressions/mesh_io holds the fuzzer's findings"


# --- OBJ: a vertex needs three numbers --------------------------------------------------


@pytest.mark.parametrize("line", ["v 10", "v 1 2", "v", "v 1 2 x", "v 1 2 3x"])
def test_obj_vertex_without_three_numbers_is_refused(tmp_path, line):
    # trimesh read "v 10" as a one-column vertex array: load_mesh returned shape (n, 1).
    path = tmp_path / "bad.obj"
    path.write_text(f"v 0 0 0\n{line}\nv 1 0 0\nv 0 1 0\nf 1 3 4\n")
    with pytest.raises(ValueError, match=r"bad\.obj: cannot read mesh \(malformed vertex"):
        load_mesh(path)
    with pytest.raises(ValueError, match="malformed vertex"):
        load_mesh_with_uvs(path)


def test_obj_vertex_with_colours_or_w_keeps_three_coordinates(tmp_path):
    path = tmp_path / "extra.obj"
    path.write_text("v 0 0 0 1 0 0\nv 1 0 0 0.5\nv 0 1 0 0 0 1\nf 1 2 3\n")
    vertices, triangles = load_mesh(path)
    np.testing.assert_array_equal(vertices, [[0, 0, 0], [1, 0, 0], [0, 1, 0]])
    np.testing.assert_array_equal(triangles, [[0, 1, 2]])


# --- glTF: positions must be 3D ---------------------------------------------------------


def _gltf(position_type: str, components: int) -> str:
    indices = np.array([0, 1, 2], dtype=np.uint32).tobytes()
    positions = np.arange(3 * components, dtype=np.float32).tobytes()
    data = indices + positions
    return json.dumps(
        {
            "asset": {"version": "2.0"},
            "scene": 0,
            "scenes": [{"nodes": [0]}],
            "nodes": [{"mesh": 0}],
            "meshes": [{"primitives": [{"attributes": {"POSITION": 1}, "indices": 0}]}],
            "buffers": [
                {
                    "byteLength": len(data),
                    "uri": "data:application/octet-stream;base64,"
                    + base64.b64encode(data).decode(),
                }
            ],
            "bufferViews": [
                {"buffer": 0, "byteOffset": 0, "byteLength": len(indices)},
                {"buffer": 0, "byteOffset": len(indices), "byteLength": len(positions)},
            ],
            "accessors": [
                {"bufferView": 0, "componentType": 5125, "count": 3, "type": "SCALAR"},
                {"bufferView": 1, "componentType": 5126, "count": 3, "type": position_type},
            ],
        }
    )


def test_gltf_positions_of_one_component_are_refused(tmp_path):
    # trimesh kept them as a (3, 1) vertex array, which load_mesh returned.
    path = tmp_path / "flat.gltf"
    path.write_text(_gltf("SCALAR", 1))
    with pytest.raises(ValueError, match=r"flat\.gltf: cannot read mesh \(vertices of shape"):
        load_mesh(path)


def test_gltf_positions_of_three_components_are_read(tmp_path):
    path = tmp_path / "good.gltf"
    path.write_text(_gltf("VEC3", 3))
    vertices, triangles = load_mesh(path)
    np.testing.assert_array_equal(vertices, np.arange(9.0).reshape(3, 3))
    np.testing.assert_array_equal(triangles, [[0, 1, 2]])


# --- PLY: a list property without its types ----------------------------------------------


@pytest.mark.parametrize("encoding", ["ascii", "binary_little_endian"])
def test_ply_list_property_without_types_is_refused(tmp_path, encoding):
    # The binary PLY list check read the types of "property list" by position: IndexError.
    path = tmp_path / "short.ply"
    path.write_bytes(f"ply\nformat {encoding} 1.0\nelement vertex 3\nproperty float x\n"
                     "property float y\nproperty float z\nelement face 1\nproperty list\n"
                     "end_header\n".encode() + bytes(40))  # fmt: skip
    with pytest.raises(ValueError, match=r"short\.ply: "):
        load_mesh(path)


# --- PLY: a negative list count in the last ASCII row --------------------------------------


def test_ply_negative_list_count_in_the_last_row_is_refused(tmp_path):
    # The completeness check of the last row stepped back by the count and indexed outside
    # the row: IndexError (found by the fuzzer in CI).
    path = tmp_path / "negative.ply"
    path.write_text("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                    "property float y\nproperty float z\nelement face 1\n"
                    "property list uchar int vertex_indices\nproperty list uchar int tags\n"
                    "end_header\n0 0 0\n1 0 0\n0 1 0\n-9 0 1 2 1 5\n")  # fmt: skip
    with pytest.raises(ValueError, match=r"negative\.ply: "):
        load_mesh(path)
