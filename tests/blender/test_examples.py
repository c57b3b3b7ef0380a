# SPDX-License-Identifier: GPL-3.0-or-later
"""The headless examples of docs/blender.md, each in a new Blender process (bpy from PyPI runs a
script as `blender -b --python script.py -- args` would)."""

import shutil
import subprocess
import sys

import bpy
import numpy as np
from helpers import DATA, ROOT

EXAMPLES = ROOT / "examples" / "blender"


def blender(script, *args):
    return subprocess.run(
        [sys.executable, str(EXAMPLES / script), "--", *map(str, args)],
        capture_output=True,
        text=True,
        timeout=600,
        cwd=ROOT,
        check=False,
    )


def test_batch_example_processes_a_folder(tmp_path):
    meshes = tmp_path / "meshes"
    meshes.mkdir()
    for name in ("suzanne.obj", "spot.obj"):
        shutil.copy(DATA / name, meshes / name)
    out = tmp_path / "out"
    run = blender("batch_sdf.py", meshes, out, "--rays", "16")
    assert run.returncode == 0, run.stdout[-2000:] + run.stderr[-2000:]
    assert "done: 2 meshes" in run.stdout
    counts = {"suzanne": 500, "spot": 5856}
    for stem, polygons in counts.items():
        values = np.load(out / f"{stem}.sdf.npz")
        (array,) = values.values()
        assert array.shape == (polygons,) and array.dtype == np.float32 and (array > 0).all()
        with bpy.data.libraries.load(str(out / f"{stem}.blend")) as (source, target):
            target.meshes = [name for name in source.meshes if name.startswith(stem)]
        me = target.meshes[0]
        assert me.attributes["sdf"].domain == "FACE" and len(me.attributes["sdf"].data) == polygons
        assert me.color_attributes.active_color_name == "sdf_color"


def test_readme_example(tmp_path):
    meshes = tmp_path / "meshes"
    meshes.mkdir()
    for name in ("suzanne.obj", "spot.obj"):
        shutil.copy(DATA / name, meshes / name)
    run = blender("sdf_folder.py", meshes, tmp_path / "out")
    assert run.returncode == 0, run.stdout[-2000:] + run.stderr[-2000:]
    assert "suzanne.obj: suzanne 500 values" in run.stdout
    assert "spot.obj: spot 5856 values" in run.stdout
    for stem in ("suzanne", "spot"):
        assert (tmp_path / "out" / f"{stem}.blend").exists()
        assert (tmp_path / "out" / f"{stem}.sdf.npz").exists()
    (meshes / "zzz_no_faces.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\n")
    assert blender("sdf_folder.py", meshes, tmp_path / "out2").returncode != 0


def test_batch_example_fails_loudly(tmp_path):
    meshes = tmp_path / "meshes"
    meshes.mkdir()
    shutil.copy(DATA / "suzanne.obj", meshes / "suzanne.obj")
    (meshes / "broken.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\n")  # no faces
    run = blender("batch_sdf.py", meshes, tmp_path / "out")
    assert run.returncode != 0
    assert "failed: broken.obj" in run.stderr
    assert (tmp_path / "out" / "suzanne.sdf.npz").exists()


def test_render_example_shows_a_coloured_mesh(tmp_path):
    png = tmp_path / "spot.png"
    run = blender("render_sdf.py", DATA / "spot.obj", png, "--size", "160", "--rays", "8")
    assert run.returncode == 0, run.stdout[-2000:] + run.stderr[-2000:]
    image = bpy.data.images.load(str(png))
    try:
        assert tuple(image.size) == (160, 120)
        pixels = np.empty(160 * 120 * 4, dtype=np.float32)
        image.pixels.foreach_get(pixels)
        rgb = pixels.reshape(-1, 4)[:, :3]
    finally:
        bpy.data.images.remove(image)
    saturation = rgb.max(axis=1) - rgb.min(axis=1)
    coloured = rgb[saturation > 0.2]
    assert len(coloured) > 0.1 * len(rgb)  # the mesh, not just a white background
    # Both ends of the colour map: purple-blue (thin) and green-yellow (thick) pixels.
    assert (coloured[:, 2] > coloured[:, 1]).any() and (coloured[:, 1] > coloured[:, 2]).any()


def test_segment_example_processes_a_folder(tmp_path):
    meshes = tmp_path / "meshes"
    meshes.mkdir()
    for name in ("suzanne.obj", "spot.obj"):
        shutil.copy(DATA / name, meshes / name)
    (meshes / "broken.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\n")  # no faces
    out = tmp_path / "out"
    run = blender("segment_folder.py", meshes, out, "--clusters", "4")
    assert run.returncode != 0 and "failed: broken.obj" in run.stderr
    for stem, polygons in {"suzanne": 500, "spot": 5856}.items():
        (labels,) = np.load(out / f"{stem}.segments.npz").values()
        assert labels.shape == (polygons,) and labels.dtype == np.int32
        count = int(labels.max()) + 1
        assert f"{stem}.obj: {stem}: {count} parts over {polygons} polygons" in run.stdout
        with bpy.data.libraries.load(str(out / f"{stem}.blend")) as (source, target):
            target.objects = [name for name in source.objects if name.startswith(stem)]
        mesh = next(ob for ob in target.objects if ob.type == "MESH")
        rig = next(ob for ob in target.objects if ob.type == "ARMATURE")
        assert rig.name == f"{stem}_parts" and len(rig.data.bones) == count
        assert [g.name for g in mesh.vertex_groups] == [
            f"part_{i:02d}" for i in range(1, count + 1)
        ]
        face_sets = np.empty(polygons, dtype=np.int32)
        mesh.data.attributes[".sculpt_face_set"].data.foreach_get("value", face_sets)
        np.testing.assert_array_equal(face_sets, labels + 1)


def test_render_segments_example_shows_parts_and_bones(tmp_path):
    png = tmp_path / "human.png"
    run = blender(
        "render_segments.py",
        DATA / "psb" / "1.off",
        png,
        "--size",
        "320",
        "--up",
        "z",
        "--view-y",
        "1.6",
    )
    assert run.returncode == 0, run.stdout[-2000:] + run.stderr[-2000:]
    assert "1: " in run.stdout and "armature 1_parts" in run.stdout
    image = bpy.data.images.load(str(png))
    try:
        assert tuple(image.size) == (320, 240)
        pixels = np.empty(320 * 240 * 4, dtype=np.float32)
        image.pixels.foreach_get(pixels)
        rgb = pixels.reshape(-1, 4)[:, :3]
    finally:
        bpy.data.images.remove(image)
    # The bones: near-black pixels; the parts: several distinct saturated colours.
    assert (rgb.max(axis=1) < 0.15).sum() > 50
    saturated = rgb[(rgb.max(axis=1) - rgb.min(axis=1)) > 0.15]
    hues = {tuple(np.round(c / c.max() * 4)) for c in saturated}
    assert len(saturated) > 200 and len(hues) >= 3
