# SPDX-License-Identifier: GPL-3.0-or-later
"""Mesh files through trimesh: the file's numbering is kept, bad files are refused clearly."""

import os
import re
import shutil
from pathlib import Path

import numpy as np
import pytest

trimesh = pytest.importorskip("trimesh")

import shape_diameter
from polygon_files import cube_of_quads, fanned, prism, write_polygons
from shape_diameter.mesh_io import WRITE_SUFFIXES, load_mesh, save_colored

DATA = Path(__file__).resolve().parents[1] / "data"


def _read_obj_by_hand(path):
    """Positions and polygons straight from the text, each polygon fanned in place."""
    vertices, triangles = [], []
    for line in Path(path).read_text(errors="replace").splitlines():
        fields = line.split()
        if fields and fields[0] == "v":
            vertices.append([float(x) for x in fields[1:4]])
        elif fields and fields[0] == "f":
            refs = [int(token.split("/")[0]) for token in fields[1:]]
            refs = [r - 1 if r > 0 else len(vertices) + r for r in refs]
            triangles += [[refs[0], refs[k], refs[k + 1]] for k in range(1, len(refs) - 1)]
    return np.array(vertices), np.array(triangles)


def _read_off_by_hand(path):
    words = Path(path).read_text().split()
    assert words[0] == "OFF"
    n, m = int(words[1]), int(words[2])
    numbers = words[4:]
    vertices = np.array(numbers[: 3 * n], dtype=float).reshape(n, 3)
    faces = np.array(numbers[3 * n : 3 * n + 4 * m], dtype=np.int64).reshape(m, 4)
    assert np.all(faces[:, 0] == 3)
    return vertices, faces[:, 1:]


def _signed_volume(vertices, triangles):
    a, b, c = (vertices[triangles[:, k]] for k in range(3))
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)


@pytest.fixture(scope="module")
def spot():
    return load_mesh(DATA / "spot.obj")


# --- reading ----------------------------------------------------------------


@pytest.mark.parametrize("name", ["spot.obj", "suzanne.obj", "cow.obj", "teapot.obj"])
def test_obj_keeps_the_files_vertices_and_faces_in_order(name):
    # spot has UV seams and suzanne has normals and quads: trimesh alone would
    # split vertices at the seams and move quad halves to the end.
    vertices, triangles = load_mesh(DATA / name)
    expected_vertices, expected_triangles = _read_obj_by_hand(DATA / name)
    assert vertices.dtype == np.float64 and vertices.shape == expected_vertices.shape
    assert triangles.dtype == np.int64 and triangles.shape == expected_triangles.shape
    np.testing.assert_array_equal(vertices, expected_vertices)
    np.testing.assert_array_equal(triangles, expected_triangles)


def test_suzanne_quads_become_two_triangles_each():
    lines = (DATA / "suzanne.obj").read_text().splitlines()
    corners = [len(line.split()) - 1 for line in lines if line.startswith("f ")]
    assert sorted(set(corners)) == [3, 4]  # the test needs a mixed file
    _, triangles = load_mesh(DATA / "suzanne.obj")
    assert len(triangles) == sum(c - 2 for c in corners)


def test_off_keeps_the_files_order():
    vertices, triangles = load_mesh(DATA / "ChineseDragon-10kv.off")
    expected_vertices, expected_triangles = _read_off_by_hand(DATA / "ChineseDragon-10kv.off")
    np.testing.assert_array_equal(vertices, expected_vertices)
    np.testing.assert_array_equal(triangles, expected_triangles)


@pytest.mark.parametrize("suffix", [".obj", ".off", ".ply"])
def test_polygons_are_fanned_in_place_with_their_source_faces(tmp_path, suffix):
    # PLY and OFF polygons came back grouped by size (triangles, then first halves of quads,
    # then second halves, ...), so --values rows did not follow the file; an OFF pentagon
    # failed in trimesh.
    vertices, polygons = prism()
    path = tmp_path / f"prism{suffix}"
    write_polygons(path, vertices, polygons)
    loaded_vertices, triangles, source = load_mesh(path, source_faces=True)
    expected_triangles, expected_source = fanned(polygons)
    np.testing.assert_array_equal(loaded_vertices, vertices)
    np.testing.assert_array_equal(triangles, expected_triangles)
    np.testing.assert_array_equal(source, expected_source)
    assert source.dtype == np.int64


def test_binary_ply_quads_are_fanned_in_place(tmp_path):
    # A binary PLY of quads only (trimesh reads binary lists of one length only).
    vertices, quads = cube_of_quads()
    header = (
        "ply\nformat binary_little_endian 1.0\nelement vertex 8\nproperty double x\n"
        "property double y\nproperty double z\nelement face 6\n"
        "property list uchar int vertex_indices\nend_header\n"
    )
    faces = np.zeros(6, dtype=[("n", "u1"), ("i", "<i4", (4,))])
    faces["n"], faces["i"] = 4, quads
    path = tmp_path / "cube.ply"
    path.write_bytes(header.encode() + vertices.astype("<f8").tobytes() + faces.tobytes())
    _, triangles, source = load_mesh(path, source_faces=True)
    expected_triangles, expected_source = fanned(quads)
    np.testing.assert_array_equal(triangles, expected_triangles)
    np.testing.assert_array_equal(source, expected_source)


@pytest.mark.parametrize(
    ("suffix", "shape", "uvs"),
    [(".obj", prism, "vt"), (".ply", prism, "vertex"), (".ply", cube_of_quads, "corner")],
)
def test_corner_uvs_follow_the_fanned_triangles(tmp_path, suffix, shape, uvs):
    # (trimesh reads PLY texcoord lists only where every face has as many corners)
    from shape_diameter.mesh_io import load_mesh_with_uvs

    vertices, polygons = shape()
    path = tmp_path / f"mesh{suffix}"
    write_polygons(path, vertices, polygons, uvs=uvs)
    _, triangles, loaded_uvs = load_mesh_with_uvs(path)
    np.testing.assert_array_equal(triangles, fanned(polygons)[0])
    expected = (vertices[triangles][:, :, :2] + (2.0, 3.0)).astype(np.float32)
    np.testing.assert_array_equal(loaded_uvs, expected)


def test_stl_and_glb_triangles_are_their_own_source(tmp_path, spot):
    for suffix in (".stl", ".glb"):
        path = tmp_path / f"spot{suffix}"
        trimesh.Trimesh(*spot, process=False).export(path)
        _, triangles, source = load_mesh(path, source_faces=True)
        np.testing.assert_array_equal(source, np.arange(len(triangles)))


def test_obj_relative_indices_polygons_and_continuations(tmp_path):
    path = tmp_path / "odd.obj"
    path.write_text(
        "mtllib nowhere.mtl\no thing\n"
        "v 0 0 0\nv 1 0 0\nv 1 1 0\n"
        "f -3 -2 -1\n"  # relative to the vertices read so far
        "v 0 1 0\nv 0.5 1.5 0\n"
        "usemtl red\nf 1/1/1 2/2/2 \\\n 3/3/3 4/4/4 5/5/5\n"  # a pentagon over two lines
    )
    vertices, triangles = load_mesh(path)
    assert vertices.shape == (5, 3)
    np.testing.assert_array_equal(triangles, [[0, 1, 2], [0, 1, 2], [0, 2, 3], [0, 3, 4]])


@pytest.mark.parametrize("suffix", [".ply", ".off", ".glb", ".obj"])
def test_other_formats_give_back_the_same_mesh(tmp_path, spot, suffix):
    vertices, triangles = spot
    path = tmp_path / f"spot{suffix}"
    trimesh.Trimesh(vertices, triangles, process=False).export(path)
    loaded_vertices, loaded_triangles = load_mesh(path)
    np.testing.assert_array_equal(loaded_triangles, triangles)
    # PLY and GLB store float32 coordinates.
    np.testing.assert_allclose(loaded_vertices, vertices, rtol=0, atol=1e-6)


def test_stl_corners_are_merged_back_into_a_connected_mesh(tmp_path, spot):
    vertices, triangles = spot
    path = tmp_path / "spot.stl"
    trimesh.Trimesh(vertices, triangles, process=False).export(path)
    loaded_vertices, loaded_triangles = load_mesh(path)
    # STL repeats every corner; merging gives back spot's vertex count, the
    # triangles keep their order and each corner its (float32) position.
    assert loaded_vertices.shape == vertices.shape
    assert loaded_triangles.shape == triangles.shape
    np.testing.assert_allclose(
        loaded_vertices[loaded_triangles], vertices[triangles], rtol=0, atol=1e-6
    )
    # Numbered by first use: the first triangle is 0, 1, 2.
    np.testing.assert_array_equal(loaded_triangles[0], [0, 1, 2])


@pytest.mark.parametrize("suffix", [".glb", ".gltf"])
def test_gltf_scene_meshes_are_joined_with_their_transforms(tmp_path, suffix):
    box = trimesh.creation.box()  # unit cube, outward normals
    ball = trimesh.creation.icosphere(subdivisions=1)
    mirror = np.diag([-1.0, 1.0, 1.0, 1.0])
    mirror[0, 3] = 5.0  # mirrored in x, then moved 5 along x
    scene = trimesh.Scene()
    scene.add_geometry(box, node_name="box", geom_name="box")
    scene.add_geometry(box, node_name="mirrored box", geom_name="box", transform=mirror)
    scene.add_geometry(ball, node_name="ball", geom_name="ball")
    path = tmp_path / f"scene{suffix}"
    scene.export(path)

    vertices, triangles = load_mesh(path)
    assert len(triangles) == 2 * len(box.faces) + len(ball.faces)
    assert len(vertices) == 2 * len(box.vertices) + len(ball.vertices)
    assert vertices[:, 0].max() == pytest.approx(5.5, abs=1e-6)
    # Every part stays outward facing, the mirrored one included: volumes add up.
    expected = 2 * box.volume + _signed_volume(ball.vertices, ball.faces)
    assert _signed_volume(vertices, triangles) == pytest.approx(expected, rel=1e-5)


def _truncated_ply(tmp_path, spot):
    whole = tmp_path / "whole.ply"
    trimesh.Trimesh(*spot, process=False).export(whole, encoding="binary")
    data = whole.read_bytes()
    path = tmp_path / "truncated.ply"
    path.write_bytes(data[: len(data) // 2])
    return path


BAD_FILES = {
    "missing.obj": None,
    "garbage.obj": "this is not a mesh\n\x00\x01 at all\n",
    "bad face.obj": "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n",
    "index zero.obj": "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n",
    "out of range.obj": "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n",
    "points only.obj": "v 0 0 0\nv 1 0 0\nv 0 1 0\n",
    "nan.obj": "v 0 0 nan\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    "empty.off": "",
    "garbage.ply": b"\x00\x01\x02 not a ply" * 20,
    "unknown.xyz2": "1 2 3\n",
}


@pytest.mark.parametrize("name", sorted(BAD_FILES))
def test_bad_files_raise_a_value_error_naming_the_file(tmp_path, name):
    path = tmp_path / name
    if BAD_FILES[name] is not None:
        content = BAD_FILES[name]
        path.write_bytes(content if isinstance(content, bytes) else content.encode())
    with pytest.raises(ValueError, match=re.escape(str(path))):
        load_mesh(path)


def test_truncated_binary_ply_is_refused(tmp_path, spot):
    path = _truncated_ply(tmp_path, spot)
    with pytest.raises(ValueError, match=re.escape(str(path))):
        load_mesh(path)


@pytest.mark.parametrize("polygons", ["prism", "quads after a pentagon"])
def test_a_binary_ply_of_mixed_polygons_says_why_it_cannot_be_read(tmp_path, polygons):
    # Where the lengths add up as if every face had the first one's corners (the prism: 136
    # bytes either way), trimesh read wrong faces; otherwise it said "PLY is unexpected
    # length!", as for a truncated file.
    vertices, faces = prism()
    if polygons == "quads after a pentagon":  # shorter than three pentagons: trimesh sees it
        faces = [faces[1], faces[0], faces[2]]
    header = (
        "ply\nformat binary_little_endian 1.0\nelement vertex 10\nproperty double x\n"
        f"property double y\nproperty double z\nelement face {len(faces)}\n"
        "property list uchar int vertex_indices\nend_header\n"
    )
    rows = b"".join(bytes([len(f)]) + np.array(f, dtype="<i4").tobytes() for f in faces)
    path = tmp_path / "prism.ply"
    path.write_bytes(header.encode() + vertices.astype("<f8").tobytes() + rows)
    message = (
        "binary PLY whose faces have different numbers of corners: trimesh cannot read that"
        if polygons == "prism"
        else "it is truncated, or mixes faces of "
        "different corner counts, which trimesh cannot read in binary PLY"
    )
    with pytest.raises(ValueError, match=re.escape(f"{path}: ") + ".*" + re.escape(message)):
        load_mesh(path)


def _ascii_copy(tmp_path, spot, suffix):
    """spot as an ASCII OFF or PLY file (trimesh writes both)."""
    path = tmp_path / f"whole{suffix}"
    options = {"encoding": "ascii"} if suffix == ".ply" else {}
    trimesh.Trimesh(*spot, process=False).export(path, **options)
    return path


@pytest.mark.parametrize("suffix", [".off", ".ply"])
@pytest.mark.parametrize("kept", [0.3, 0.6, 0.9, None])
def test_truncated_ascii_off_and_ply_are_refused(tmp_path, spot, suffix, kept):
    # trimesh once read them as a smaller mesh without a word. Cut in the vertices, in the
    # faces, or (None) just before the last index of the last face.
    data = _ascii_copy(tmp_path, spot, suffix).read_bytes().rstrip()
    path = tmp_path / f"truncated{suffix}"
    path.write_bytes(data[: int(len(data) * kept) if kept else data.rindex(b" ")])
    expected = "vertices" if kept == 0.3 else "faces" if kept else "last face"
    with pytest.raises(ValueError, match=rf"{re.escape(str(path))}: truncated .*{expected}"):
        load_mesh(path)


def test_whole_ascii_off_and_ply_still_read(tmp_path, spot):
    for suffix in (".off", ".ply"):
        vertices, triangles = load_mesh(_ascii_copy(tmp_path, spot, suffix))
        np.testing.assert_allclose(vertices, spot[0], atol=1e-6)
        np.testing.assert_array_equal(triangles, spot[1])


def _whole_binary_stl(tmp_path, spot):
    path = tmp_path / "whole.stl"
    trimesh.Trimesh(*spot, process=False).export(path)
    return path.read_bytes()


NOT_THAT_FORMAT = {
    # The name, its bytes, and what the message says. These once failed with "No module
    # named 'charset_normalizer'" (trimesh's guess at the encoding of text that is none).
    "random.off": (lambda tmp, spot: np.random.default_rng(0).bytes(5000),
                   r"not a valid OFF file \(it is not text\)"),
    "random.stl": (lambda tmp, spot: np.random.default_rng(0).bytes(5000),
                   "not a valid STL file .*header declares"),
    "truncated.stl": (lambda tmp, spot: _whole_binary_stl(tmp, spot)[:-1],
                      ("not a valid STL file .*declares 5856 triangles, 292884 bytes, the file "
                       "has 292883")),
    "ply.stl": (lambda tmp, spot: (DATA / "horse.ply").read_bytes(),
                r"not a valid STL file \(it looks like a PLY file\)"),
    "obj.off": (lambda tmp, spot: (DATA / "spot.obj").read_bytes(),
                r"not a valid OFF file \(it looks like an OBJ file\)"),
    "text.off": (lambda tmp, spot: b"hello\n1 2 3\n", r"not a valid OFF file \(no OFF header\)"),
    # These once said "no triangles found", or repeated trimesh's exception.
    "ply.obj": (lambda tmp, spot: (DATA / "horse.ply").read_bytes(),
                r"not a valid OBJ file \(it looks like a PLY file\)"),
    "off.stl": (lambda tmp, spot: (DATA / "bunny00.off").read_bytes(),
                r"not a valid STL file \(it looks like an OFF file\)"),
    "text.stl": (lambda tmp, spot: b"hello\n",
                 r"not a valid STL file \(text that does not start with 'solid'\)"),
    "random.obj": (lambda tmp, spot: np.random.default_rng(1).bytes(5000) + b"\x00",
                   r"not a valid OBJ file \(it is not text\)"),
    "obj.ply": (lambda tmp, spot: (DATA / "spot.obj").read_bytes(),
                r"not a valid PLY file \(it looks like an OBJ file\)"),
    "stl.glb": (lambda tmp, spot: _whole_binary_stl(tmp, spot),
                r"not a valid GLB file \(it looks like an STL file\)"),
    "glb.gltf": (lambda tmp, spot: trimesh.Trimesh(*spot).export(file_type="glb"),
                 r"not a valid glTF file \(it looks like a GLB file\)"),
    "off.glb": (lambda tmp, spot: (DATA / "bunny00.off").read_bytes(),
                r"not a valid GLB file \(it looks like an OFF file\)"),
}  # fmt: skip


@pytest.mark.parametrize("name", sorted(NOT_THAT_FORMAT))
def test_a_file_not_of_its_format_says_so(tmp_path, spot, name):
    content, message = NOT_THAT_FORMAT[name]
    path = tmp_path / name
    path.write_bytes(content(tmp_path, spot))
    with pytest.raises(ValueError, match=f"{re.escape(str(path))}: {message}"):
        load_mesh(path)


@pytest.mark.parametrize("name", ["horse", "horse.xyz", "horse.ply.bak"])
def test_a_name_without_a_mesh_suffix_says_which_are_read(tmp_path, name):
    # A file without an extension once gave trimesh's "file_type '/tmp/.../noext' not
    # supported".
    path = tmp_path / name
    shutil.copy(DATA / "horse.ply", path)
    start = (
        "no file extension to tell the mesh format by"
        if name == "horse"
        else (f"cannot read '{path.suffix}' files")
    )
    supported = ".obj, .ply, .off, .stl, .gltf, .glb"
    with pytest.raises(ValueError) as raised:
        load_mesh(path)
    assert str(raised.value) == (
        f"{path}: {start} (it looks like a PLY file; supported: {supported})"
    )


def test_other_formats_are_not_mistaken_for_obj(tmp_path):
    # OBJ is told by its records, so ordinary OBJ files (comments first, objects, groups,
    # a byte order mark) are still read.
    path = tmp_path / "odd.obj"
    path.write_bytes(
        b"\xef\xbb\xbf# made by hand\nmtllib x.mtl\no a\nv 0 0 0\nv 1 0 0\n"
        b"v 0 1 0\ng part\nf 1 2 3\n"
    )
    np.testing.assert_array_equal(load_mesh(path)[1], [[0, 1, 2]])


def test_point_cloud_is_refused_as_such(tmp_path):
    path = tmp_path / "cloud.ply"
    trimesh.PointCloud(np.random.default_rng(0).random((20, 3))).export(path)
    with pytest.raises(ValueError, match="no triangles.*point cloud"):
        load_mesh(path)


def test_a_folder_is_not_a_mesh(tmp_path):
    folder = tmp_path / "folder.obj"
    folder.mkdir()
    with pytest.raises(ValueError, match="not a file"):
        load_mesh(folder)


# --- writing ----------------------------------------------------------------


def _colours(count, seed):
    rgba = np.random.default_rng(seed).integers(0, 256, (count, 4), dtype=np.uint8)
    rgba[:, 3] = 255
    return rgba


def _single_geometry(path):
    # force="scene" reads colours as stored, without trimesh's mesh
    # concatenation (which converts colours and needs SciPy).
    scene = trimesh.load(path, process=False, force="scene")
    assert len(scene.geometry) == 1
    return next(iter(scene.geometry.values()))


def _read_off_colours(path):
    lines = [line.split() for line in Path(path).read_text().splitlines()]
    n, m = int(lines[1][0]), int(lines[1][1])
    if lines[0] == ["COFF"]:
        return np.array([row[3:7] for row in lines[2 : 2 + n]], dtype=np.uint8)
    return np.array([row[4:8] for row in lines[2 + n : 2 + n + m]], dtype=np.uint8)


@pytest.mark.parametrize("per", ["faces", "vertices"])
@pytest.mark.parametrize("suffix", WRITE_SUFFIXES)
def test_save_colored_writes_mesh_and_colours(tmp_path, per, suffix):
    vertices, triangles = load_mesh(DATA / "cow.obj")
    colours = _colours(len(triangles) if per == "faces" else len(vertices), seed=1)
    path = tmp_path / f"cow{suffix}"
    save_colored(path, vertices, triangles, colours, per=per)

    loaded_vertices, loaded_triangles = load_mesh(path)
    assert loaded_triangles.shape == triangles.shape
    np.testing.assert_allclose(
        loaded_vertices[loaded_triangles], vertices[triangles], rtol=0, atol=1e-5
    )
    if suffix == ".stl":
        return  # STL has no colour
    if suffix == ".off":
        np.testing.assert_array_equal(_read_off_colours(path), colours)
        np.testing.assert_array_equal(loaded_vertices, vertices)  # %.17g is exact
        return
    visual = _single_geometry(path).visual
    if suffix == ".ply" or per == "vertices":
        np.testing.assert_array_equal(loaded_triangles, triangles)
        stored = visual.face_colors if per == "faces" else visual.vertex_colors
        assert visual.kind == ("face" if per == "faces" else "vertex")
        np.testing.assert_array_equal(stored, colours)
    else:
        # OBJ and GLB hold vertex colours only: each triangle gets its own corners.
        assert visual.kind == "vertex"
        assert len(loaded_vertices) == 3 * len(triangles)
        np.testing.assert_array_equal(visual.vertex_colors, np.repeat(colours, 3, axis=0))


# Meshes far from the origin or tiny: a 10 m sphere at UTM coordinates (float32 moves its
# vertices by up to 0.25 m), a unit sphere at 1e8 (float32 collapses it), a sphere 1e-5 wide
# (8 fixed decimals, trimesh's OBJ, kept 2.5e-4 of its size).
FAR_AND_SMALL = {
    "utm": (5.0, (500000.123, 5400000.456, 100.789)),
    "1e8": (1.0, (1e8, -3e7, 0.0)),
    "tiny": (1e-5, (0.0, 0.0, 0.0)),
}


def _sphere(radius, offset):
    sphere = trimesh.creation.icosphere(subdivisions=2, radius=radius)
    return np.asarray(sphere.vertices) + offset, np.asarray(sphere.faces, dtype=np.int64)


@pytest.mark.parametrize("per", ["faces", "vertices"])
@pytest.mark.parametrize("suffix", [".ply", ".obj", ".off"])
@pytest.mark.parametrize("case", sorted(FAR_AND_SMALL))
def test_ply_obj_and_off_give_the_coordinates_back_exactly(tmp_path, case, suffix, per):
    vertices, triangles = _sphere(*FAR_AND_SMALL[case])
    count = len(triangles) if per == "faces" else len(vertices)
    path = tmp_path / f"out{suffix}"
    save_colored(path, vertices, triangles, _colours(count, 4), per=per)
    loaded_vertices, loaded_triangles = load_mesh(path)
    # OBJ with colours per face gives each triangle its own corners: compare corners.
    np.testing.assert_array_equal(loaded_vertices[loaded_triangles], vertices[triangles])
    if suffix == ".ply":
        assert b"property double x" in path.read_bytes()[:300]


@pytest.mark.parametrize("suffix", [".glb", ".stl"])
@pytest.mark.parametrize("case", ["utm", "1e8", "1e6"])
def test_glb_and_stl_warn_when_32_bit_floats_move_the_vertices(tmp_path, case, suffix):
    # 1e6: a sphere 0.25 wide, whose vertices move by up to an eighth of it (it read 'as
    # much as the mesh is wide').
    vertices, triangles = _sphere(*FAR_AND_SMALL.get(case, (0.125, (1e6, 0.0, 0.0))))
    path = tmp_path / f"out{suffix}"
    with pytest.warns(RuntimeWarning) as caught:
        save_colored(path, vertices, triangles, _colours(len(triangles), 5))
    assert len(caught) == 1
    message = str(caught[0].message)
    assert message.startswith(f"{path}: {suffix[1:].upper()} holds 32-bit float coordinates")
    assert "write .ply, .off or .obj to keep them exactly" in message
    # A unit sphere at 1e8 collapses onto a few float32 values: said so, with the share as a
    # percentage (not "1 of the mesh's size", which is unclear); at UTM northings it moves a
    # little.
    if case in ("1e8", "1e6"):  # half and an eighth of the mesh's width
        share = {"1e8": "50%", "1e6": "1[0-9]%"}[case]
        assert re.search(rf"\({share} of the mesh's size: its shape is lost\)", message), message
    else:
        assert re.search(
            r"vertices move by up to [0-9.e-]+ units \([0-9.e-]+ of the mesh's "
            r"size\)",
            message,
        ), message
    # What the file holds is the float32 rounding of the mesh, as the warning says.
    loaded_vertices, loaded_triangles = load_mesh(path)
    expected = vertices.astype(np.float32).astype(np.float64)[triangles]
    np.testing.assert_array_equal(loaded_vertices[loaded_triangles], expected)


@pytest.mark.parametrize("suffix", [".glb", ".stl"])
def test_glb_and_stl_are_quiet_where_32_bit_floats_suffice(tmp_path, suffix):
    # A tiny mesh at the origin keeps float32's relative precision: no warning (warnings
    # are errors in this suite), and every vertex within 1e-7 of the size.
    vertices, triangles = _sphere(*FAR_AND_SMALL["tiny"])
    path = tmp_path / f"out{suffix}"
    save_colored(path, vertices, triangles, _colours(len(triangles), 6))
    loaded_vertices, loaded_triangles = load_mesh(path)
    np.testing.assert_allclose(loaded_vertices[loaded_triangles], vertices[triangles],
                               rtol=0, atol=1e-7 * 2e-5)  # fmt: skip


def test_ply_output_is_binary(tmp_path):
    vertices, triangles = load_mesh(DATA / "suzanne.obj")
    path = tmp_path / "out.ply"
    save_colored(path, vertices, triangles, _colours(len(triangles), 2))
    header = path.read_bytes()[:400]
    assert header.startswith(b"ply\n") and b"format binary_little_endian 1.0" in header


def test_save_colored_refuses_bad_arguments(tmp_path):
    vertices, triangles = load_mesh(DATA / "suzanne.obj")
    good = _colours(len(triangles), 3)
    with pytest.raises(ValueError, match="cannot write '.fbx'"):
        save_colored(tmp_path / "out.fbx", vertices, triangles, good)
    with pytest.raises(ValueError, match="shape"):
        save_colored(tmp_path / "out.ply", vertices, triangles, good[:-1])
    with pytest.raises(ValueError, match="uint8"):
        save_colored(tmp_path / "out.ply", vertices, triangles, good.astype(np.float32))
    with pytest.raises(ValueError, match="per"):
        save_colored(tmp_path / "out.ply", vertices, triangles, good, per="edges")
    with pytest.raises(ValueError, match=r"\(507, 4\)"):
        save_colored(tmp_path / "out.ply", vertices, triangles, good, per="vertices")


def test_load_mesh_takes_bytes_and_path_objects():
    # b'a.obj' (os.walk over bytes, for names that are not UTF-8) was read as
    # "cannot read 'b'.obj'' files".
    expected = shape_diameter.load_mesh(str(DATA / "suzanne.obj"))
    for path in (os.fsencode(DATA / "suzanne.obj"), DATA / "suzanne.obj"):
        got = shape_diameter.load_mesh(path)
        assert all(np.array_equal(a, b) for a, b in zip(got, expected))


@pytest.mark.parametrize("suffix", [".off", ".ply"])
def test_a_bad_coordinate_or_index_is_named(tmp_path, suffix):
    # "vertex coordinates are not all finite" and "a face refers to a vertex that
    # does not exist", naming neither.
    vertices = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
    faces = np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]])

    def write(v, f):
        path = tmp_path / f"m{suffix}"
        if suffix == ".off":
            lines = [
                "OFF",
                f"{len(v)} {len(f)} 0",
                *(" ".join(f"{x:.17g}" for x in p) for p in v),
                *(f"3 {a} {b} {c}" for a, b, c in f),
            ]
        else:
            lines = [
                "ply",
                "format ascii 1.0",
                f"element vertex {len(v)}",
                "property float x",
                "property float y",
                "property float z",
                f"element face {len(f)}",
                "property list uchar int vertex_indices",
                "end_header",
                *(" ".join(f"{x:.17g}" for x in p) for p in v),
                *(f"3 {a} {b} {c}" for a, b, c in f),
            ]
        path.write_text("\n".join(lines) + "\n")
        return path

    bad = vertices.copy()
    bad[2, 1] = np.nan
    with pytest.raises(
        ValueError,
        match=r"1 vertex has a coordinate that is not finite "
        r"\(NaN or infinite; the first: vertex 2, counting",
    ):
        load_mesh(write(bad, faces))
    far = faces.copy()
    far[2, 1] = 9
    with pytest.raises(
        ValueError,
        match=r"face 2 \(counting from 0\) refers to vertex 9, but "
        r"the file has 4 vertices \(0 to 3\)",
    ):
        load_mesh(write(vertices, far))
