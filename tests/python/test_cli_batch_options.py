# SPDX-License-Identifier: GPL-3.0-or-later
"""Options for batches: --output-dir, --skip-existing, and --list-engines."""

import json
import os
import shutil
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("trimesh")

import shape_diameter
from shape_diameter import cli, cli_jobs

DATA = Path(__file__).resolve().parents[1] / "data"


@pytest.fixture
def two_meshes(tmp_path):
    folder = tmp_path / "in"
    folder.mkdir()
    for name in ("spot.obj", "suzanne.obj"):
        shutil.copy(DATA / name, folder / name)
    return folder


def _run_json(capsys, argv):
    status = cli.main([str(arg) for arg in argv] + ["--json", "--rays", "4"])
    captured = capsys.readouterr()
    return status, [json.loads(line) for line in captured.out.splitlines()], captured.err


def test_output_dir_is_made_and_takes_every_output(tmp_path, capsys, two_meshes):
    out = tmp_path / "made" / "here"
    status, reports, _ = _run_json(capsys, [two_meshes, "--output-dir", out, "--save-values"])
    assert status == 0
    assert sorted(p.name for p in out.iterdir()) == [
        "spot.sdf.npy",
        "spot.sdf.ply",
        "suzanne.sdf.npy",
        "suzanne.sdf.ply",
    ]
    assert sorted(p.name for p in two_meshes.iterdir()) == ["spot.obj", "suzanne.obj"]
    for report in reports:
        stem = Path(report["input"]).stem
        assert report["outputs"] == {
            "mesh": str(out / f"{stem}.sdf.ply"),
            "values": str(out / f"{stem}.sdf.npy"),
        }


def test_output_dir_fails_the_second_input_of_one_name(tmp_path, capsys, two_meshes):
    other = tmp_path / "other"
    other.mkdir()
    shutil.copy(DATA / "spot.obj", other / "spot.obj")
    out = tmp_path / "out"
    status, reports, _ = _run_json(capsys, [two_meshes, other, "--output-dir", out])
    assert status == 2
    assert [r["status"] for r in reports] == ["ok", "ok", "error"]
    assert reports[2]["error"].startswith(
        f"{other / 'spot.obj'}: would write {out / 'spot.sdf.ply'}"
    )
    assert sorted(p.name for p in out.iterdir()) == ["spot.sdf.ply", "suzanne.sdf.ply"]


@pytest.mark.parametrize(
    "argv, message",
    [
        (["-o", "{tmp}/a.ply", "--output-dir", "{tmp}/d"], "-o/--output names the output itself"),
        (["--output-dir", "{tmp}/a_file"], "a_file: --output-dir is a file, not a folder"),
    ],
)
def test_output_dir_errors(tmp_path, capsys, argv, message):
    (tmp_path / "a_file").write_text("")
    argv = [DATA / "spot.obj"] + [a.replace("{tmp}", str(tmp_path)) for a in argv]
    assert cli.main([str(a) for a in argv]) == 2
    assert message in capsys.readouterr().err


def test_skip_existing_leaves_finished_inputs_and_runs_the_rest(tmp_path, capsys, two_meshes):
    out = tmp_path / "out"
    argv = [two_meshes, "--output-dir", out, "--save-values", "--skip-existing"]
    status, first, _ = _run_json(capsys, argv)
    assert status == 0 and [r["status"] for r in first] == ["ok", "ok"]
    spot_mesh = (out / "spot.sdf.ply").stat().st_mtime_ns
    # An interrupted batch: suzanne's values are missing, so suzanne runs again.
    (out / "suzanne.sdf.npy").unlink()
    status, second, _ = _run_json(capsys, argv)
    assert status == 0
    assert [(Path(r["input"]).name, r["status"]) for r in second] == [
        ("spot.obj", "skipped"),
        ("suzanne.obj", "ok"),
    ]
    assert second[0]["outputs"] == first[0]["outputs"]
    assert (out / "spot.sdf.ply").stat().st_mtime_ns == spot_mesh
    v, t = shape_diameter.load_mesh(two_meshes / "suzanne.obj")
    expected = shape_diameter.compute(v, t, rays=4).raw
    np.testing.assert_array_equal(np.load(out / "suzanne.sdf.npy"), expected)


def test_skip_existing_says_so_without_json(tmp_path, capsys):
    mesh = tmp_path / "spot.obj"
    shutil.copy(DATA / "spot.obj", mesh)
    (tmp_path / "spot.sdf.ply").write_text("")
    assert cli.main([str(mesh), "--skip-existing"]) == 0
    assert capsys.readouterr().out == f"{mesh}: skipped, {tmp_path / 'spot.sdf.ply'} exists\n"


def test_list_engines_lists_what_engine_takes(capsys):
    # Standard output holds the engines alone, one a line (an awk script read the note on
    # 'auto' as an engine); with --json, engines()' entries.
    assert cli.main(["--list-engines"]) == 0
    out, err = capsys.readouterr()
    names = [line.split()[0] for line in out.splitlines()]
    assert names == [engine["name"] for engine in shape_diameter.engines()]
    assert err.startswith("auto picks")
    for flag in ("--json", "--js"):  # (argparse's abbreviation too)
        assert cli.main(["--list-engines", flag]) == 0
        out, err = capsys.readouterr()
        assert [json.loads(line) for line in out.splitlines()] == shape_diameter.engines()
        assert err == ""


def test_list_engines_into_a_full_disk_says_so_in_one_line(tmp_path):
    import subprocess
    import sys

    with open("/dev/full", "w") as full:
        run = subprocess.run(
            [sys.executable, "-m", "shape_diameter", "--list-engines"],
            stdout=full,
            stderr=subprocess.PIPE,
            text=True,
            timeout=120,
        )
    assert run.returncode == 1
    assert run.stderr == (
        "shape-diameter: error: standard output: cannot write (No space left on device)\n"
    )


def test_skip_existing_does_not_skip_a_missing_input(tmp_path, capsys):
    # A mistyped name beside an old output was "skipped", status 0 (a review's).
    (tmp_path / "gone.sdf.ply").write_text("")
    status, reports, _ = _run_json(capsys, [tmp_path / "gone.obj", "--skip-existing"])
    assert status == 2
    assert reports[0]["status"] == "error" and "no such file" in reports[0]["error"]


def test_list_engines_into_a_closed_pipe_stops_quietly(tmp_path):
    import os
    import subprocess
    import sys

    read, write = os.pipe()
    os.close(read)
    run = subprocess.run(
        [sys.executable, "-m", "shape_diameter", "--list-engines"],
        stdout=write,
        stderr=subprocess.PIPE,
        text=True,
        timeout=120,
    )
    os.close(write)
    assert (run.returncode, run.stderr) == (141, "")


def test_a_link_to_itself_in_a_folder_fails_alone(tmp_path, capsys, two_meshes):
    # It stopped the whole folder: "cannot list the folder (Too many levels of symbolic links)".
    (two_meshes / "loop.obj").symlink_to(two_meshes / "loop.obj")
    status, reports, _ = _run_json(capsys, [two_meshes])
    assert status == 2
    assert [(Path(r["input"]).name, r["status"]) for r in reports] == [
        ("loop.obj", "error"),
        ("spot.obj", "ok"),
        ("suzanne.obj", "ok"),
    ]


def test_recursive_takes_subfolders_and_output_dir_mirrors_them(tmp_path, capsys):
    # An asset tree: nest/a/model.obj and nest/b/model.obj. Without --recursive the
    # folder held "no mesh files"; given as files with --output-dir, the second collided.
    nest = tmp_path / "nest"
    for sub in ("a", "b", "b/deeper", ".hidden"):
        (nest / sub).mkdir(parents=True)
        shutil.copy(DATA / "suzanne.obj", nest / sub / "model.obj")
    (nest / "loop").symlink_to(nest, target_is_directory=True)  # not followed
    status, reports, err = _run_json(capsys, [nest])
    assert status == 2 and "--recursive searches its subfolders" in err
    status, reports, _ = _run_json(capsys, [nest, "-r", "--save-values"])
    assert status == 0
    assert [Path(r["input"]).relative_to(nest).as_posix() for r in reports] == [
        "a/model.obj",
        "b/model.obj",
        "b/deeper/model.obj",
    ]
    assert (nest / "b" / "deeper" / "model.sdf.ply").is_file()
    out = tmp_path / "out"
    status, reports, _ = _run_json(
        capsys, [nest, "--recursive", "--output-dir", out, "--save-values"]
    )
    assert status == 0
    assert sorted(p.relative_to(out).as_posix() for p in out.rglob("*.sdf.*")) == [
        "a/model.sdf.npy",
        "a/model.sdf.ply",
        "b/deeper/model.sdf.npy",
        "b/deeper/model.sdf.ply",
        "b/model.sdf.npy",
        "b/model.sdf.ply",
    ]
    # Run again: the outputs beside the inputs are not taken for meshes.
    status, reports, _ = _run_json(capsys, [nest, "-r", "--skip-existing"])
    assert status == 0 and [r["status"] for r in reports] == ["skipped"] * 3


def test_recursive_goes_on_past_a_subfolder_it_cannot_list_or_write(tmp_path, capsys, monkeypatch):
    # A review's: one unreadable subfolder dropped the whole tree, blamed on the top folder,
    # and an output subfolder blocked by a file refused every input.
    nest = tmp_path / "nest"
    for sub in ("a", "b", "c"):
        (nest / sub).mkdir(parents=True)
        shutil.copy(DATA / "suzanne.obj", nest / sub / "m.obj")
    real_scandir = cli_jobs.os.scandir

    def scandir(path):
        if Path(path) == nest / "b":
            raise PermissionError(13, "Permission denied")
        return real_scandir(path)

    monkeypatch.setattr(cli_jobs.os, "scandir", scandir)
    out = tmp_path / "out"
    out.mkdir()
    (out / "c").write_text("")  # a file where the subfolder goes
    status, reports, err = _run_json(capsys, [nest, "-r", "--output-dir", out])
    assert status == 2
    assert [(Path(r["input"]).relative_to(nest).as_posix(), r["status"]) for r in reports] == [
        ("a/m.obj", "ok"),
        ("b", "error"),
        ("c/m.obj", "error"),
    ]
    assert reports[1]["error"] == f"{nest / 'b'}: cannot list the folder (Permission denied)"
    assert reports[2]["error"].startswith(
        f"{nest / 'c' / 'm.obj'}: cannot make its output folder {out / 'c'}"
    )
    assert (out / "a" / "m.sdf.ply").is_file()


def test_a_fifo_with_a_meshs_name_in_a_folder_fails_as_its_own_input(tmp_path, capsys):
    # Skipped without a word, while given directly it failed as 'not a file'.
    (tmp_path / "a.obj").write_bytes((DATA / "suzanne.obj").read_bytes())
    os.mkfifo(tmp_path / "b.obj")
    status, reports, _ = _run_json(capsys, [tmp_path])
    assert status == 2
    assert [(Path(r["input"]).name, r["status"]) for r in reports] == [
        ("a.obj", "ok"),
        ("b.obj", "error"),
    ]
    assert reports[1]["error"].endswith("b.obj: not a file")
