# SPDX-License-Identifier: GPL-3.0-or-later
"""The command line's words: options that would do nothing are refused, broken files say
what is wrong with them, and the library's warnings come in option spelling."""

import struct
from pathlib import Path

import numpy as np
import pytest

trimesh = pytest.importorskip("trimesh")

from shape_diameter import batch_job, cli

DATA = Path(__file__).resolve().parents[1] / "data"
SPOT = str(DATA / "spot.obj")


def _error(capsys, argv):
    """The one-line error of a run that must fail with status 2."""
    assert cli.main([str(arg) for arg in argv]) == 2
    captured = capsys.readouterr()
    assert captured.err.count("\n") == 1 and "Traceback" not in captured.err, captured.err
    assert captured.err.startswith("shape-diameter: error: ")
    return captured.err[len("shape-diameter: error: ") :].strip()


NO_OP_OPTIONS = {
    "seed without random sampling": (["--seed", "5"], "--seed applies to --sampling random"),
    "seed with cgal sampling": (
        ["--seed", "5", "--sampling", "cgal"],
        "--seed applies to --sampling random",
    ),
    "bvh quality with the octree": (
        ["--accel", "octree", "--bvh-quality", "high"],
        "--bvh-quality applies to --accel bvh",
    ),
    "values and save-values": (
        ["--values", "{tmp}/v.npy", "--save-values"],
        "--values and --save-values both say where values go",
    ),
}


@pytest.mark.parametrize("case", sorted(NO_OP_OPTIONS))
def test_an_option_that_would_do_nothing_is_refused(tmp_path, capsys, case):
    options, message = NO_OP_OPTIONS[case]
    options = [o.replace("{tmp}", str(tmp_path)) for o in options]
    assert _error(capsys, [SPOT, "-o", tmp_path / "out.ply", *options]).startswith(message)
    assert list(tmp_path.iterdir()) == []


def test_seed_and_bvh_quality_where_they_apply_are_accepted(tmp_path, capsys):
    out = tmp_path / "out.ply"
    assert (
        cli.main(
            [
                SPOT,
                "-o",
                str(out),
                "--rays",
                "4",
                "--sampling",
                "random",
                "--seed",
                "5",
                "--bvh-quality",
                "high",
                "-q",
            ]
        )
        == 0
    )
    assert out.exists()


def test_a_range_error_names_its_option_once(tmp_path, capsys):
    message = _error(capsys, [SPOT, "--smooth", "texture", "--radius", "-3"])
    assert message == "argument --radius: must be in [0, 16384], got -3"


def _sphere():
    return trimesh.creation.icosphere(subdivisions=2)


def _truncated_ascii_stl(folder):
    path = folder / "cut.stl"
    text = trimesh.exchange.stl.export_stl_ascii(_sphere())
    path.write_text(text[: len(text) // 2])
    return path


def _truncated_glb(folder):
    path = folder / "cut.glb"
    data = _sphere().export(file_type="glb")
    path.write_bytes(data[: len(data) // 2])
    return path, struct.unpack_from("<I", data, 8)[0]


def test_a_truncated_ascii_stl_says_so(tmp_path, capsys):
    # It said "no triangles found": trimesh drops the whole text.
    path = _truncated_ascii_stl(tmp_path)
    assert _error(capsys, [path, "-o", tmp_path / "o.ply"]) == (
        f"{path}: truncated: ASCII STL text ends with an 'endsolid' line, this file does not"
    )


def test_an_ascii_stl_with_padding_after_endsolid_is_read(tmp_path):
    # A DOS end-of-file byte after endsolid: trimesh reads it; the truncation check refused it.
    from shape_diameter.mesh_io import load_mesh

    path = tmp_path / "padded.stl"
    path.write_bytes(trimesh.exchange.stl.export_stl_ascii(_sphere()).encode() + b"\r\n\x1a")
    assert len(load_mesh(path)[1]) == len(_sphere().faces)


def test_a_truncated_glb_says_so(tmp_path, capsys):
    # It said "cannot read mesh (chunk was not expected length!)".
    path, declared = _truncated_glb(tmp_path)
    assert _error(capsys, [path, "-o", tmp_path / "o.ply"]) == (
        f"{path}: truncated: its header declares {declared} bytes, the file has "
        f"{path.stat().st_size}"
    )


OBJ_FILES = {
    # It said "a point cloud": the line records were dropped before trimesh saw the file.
    "lines": ("v 0 0 0\nv 1 0 0\nv 0 1 0\nl 1 2\nl 2 3\n", "no triangles found (it holds lines)"),
    # It gave numpy's "index 4 is out of bounds for axis 0 with size 3".
    "past the last vertex": (
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 5\n",
        "cannot read mesh (face 'f 1 2 5' uses vertex 5, but the file has 3 vertices)",
    ),
    # trimesh dropped it: a file cut inside its last face line read "ok".
    "a face of two corners": (
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 4",
        "cannot read mesh (face 'f 1 4' has 2 corners, fewer than a "
        "face's 3 (is the file cut short?))",
    ),
    # trimesh wrapped it around to a vertex from the end, and the run went on.
    "back past the first vertex": (
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -7\n",
        "cannot read mesh (face 'f 1 2 -7' counts back past the "
        "first vertex (a negative index counts back from its line))",
    ),
}


@pytest.mark.parametrize("case", sorted(OBJ_FILES))
def test_a_broken_obj_says_what_is_wrong(tmp_path, capsys, case):
    text, message = OBJ_FILES[case]
    path = tmp_path / "broken.obj"
    path.write_text(text)
    assert _error(capsys, [path, "-o", tmp_path / "o.ply"]) == f"{path}: {message}"


def test_relative_obj_indices_within_the_file_still_work(tmp_path):
    path = tmp_path / "relative.obj"
    path.write_text(
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf -4 -2 -3\nf -4 -3 -1\nf -3 -2 -1\nf -4 -1 -2\n"
    )
    from shape_diameter.mesh_io import load_mesh

    _, triangles = load_mesh(path)
    np.testing.assert_array_equal(triangles, [[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]])


def _inside_out(folder, mesh, name):
    path = folder / name
    trimesh.Trimesh(mesh.vertices, mesh.faces[:, ::-1], process=False).export(path)
    return str(path)


def test_warnings_name_options_not_python_arguments(tmp_path, capsys):
    # An inside-out cow trusted as wound keeps few rays: the hint spoke of orientation='as_is'.
    spot = trimesh.load(SPOT, process=False)
    path = _inside_out(tmp_path, spot, "spot.ply")
    assert (
        cli.main(
            [path, "-o", str(tmp_path / "o.ply"), "--orientation", "as_is", "--rays", "8", "-q"]
        )
        == 0
    )
    err = capsys.readouterr().err
    assert "--orientation as_is trusts the winding; --orientation auto turns" in err, err
    assert "orientation='" not in err, err
    # A convex one keeps none: the warning spoke of valid_rays, which the command never shows.
    path = _inside_out(tmp_path, _sphere(), "sphere.ply")
    assert (
        cli.main(
            [path, "-o", str(tmp_path / "o.ply"), "--orientation", "as_is", "--rays", "8", "-q"]
        )
        == 0
    )
    err = capsys.readouterr().err
    assert err.endswith(
        "no ray of any point found the other side of the mesh (is it open, "
        "flat or inside out?); every value is 0\n"
    ), err


def test_a_failed_write_names_the_file_that_failed_once(tmp_path):
    # With --save-values the mesh is written inside the values' write: its error was wrapped
    # again, naming the values file ("x.sdf.npy: cannot write (x.sdf.ply: cannot write ...)").
    import resource
    import subprocess
    import sys

    mesh = tmp_path / "spot.obj"
    mesh.write_bytes((DATA / "spot.obj").read_bytes())

    def small_files():  # 64 kB: the PLY (about 300 kB) cannot be written
        resource.setrlimit(resource.RLIMIT_FSIZE, (65536, 65536))

    run = subprocess.run(
        [sys.executable, "-m", "shape_diameter", str(mesh), "--save-values", "--rays", "4", "-q"],
        capture_output=True,
        text=True,
        preexec_fn=small_files,
        timeout=120,
    )
    assert run.returncode == 1
    assert run.stderr == (
        f"shape-diameter: error: {tmp_path / 'spot.sdf.ply'}: cannot write "
        "(File too large); nothing written\n"
    )
    assert sorted(p.name for p in tmp_path.iterdir()) == ["spot.obj"]


def test_long_texture_work_is_announced(tmp_path, capsys, monkeypatch):
    # An 8192^2 run at a radius of 8192 texels went on for an hour without a word.
    monkeypatch.setattr(batch_job, "LONG_TEXTURE_SECONDS", 0.0)
    assert (
        cli.main(
            [
                SPOT,
                "-o",
                str(tmp_path / "o.ply"),
                "--rays",
                "4",
                "--engine",
                "cpu",
                "--smooth",
                "texture",
                "--texture-size",
                "64",
                "--threads",
                "2",
                "-q",
            ]
        )
        == 0
    )
    err = capsys.readouterr().err
    assert (
        "warning: " in err
        and "texture smoothing at 64 x 64 texels: about 0 s on 2 CPU "
        "threads and 0 MiB (an estimate)"
        in err
    ), err
    monkeypatch.setattr(batch_job, "LONG_TEXTURE_SECONDS", 10.0)  # the real threshold: quiet
    assert (
        cli.main(
            [
                SPOT,
                "-o",
                str(tmp_path / "o.ply"),
                "--rays",
                "4",
                "--engine",
                "cpu",
                "--smooth",
                "texture",
                "--texture-size",
                "64",
                "-q",
            ]
        )
        == 0
    )
    assert "texture smoothing at" not in capsys.readouterr().err
