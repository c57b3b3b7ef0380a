# SPDX-License-Identifier: GPL-3.0-or-later
"""The shape-diameter command on several inputs: each computed in turn in one process, output
names checked before any work, a bad file reported while the others go on, --quiet, --json per
input, folders; and shape_diameter.load_mesh for scripts."""

import json
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

trimesh = pytest.importorskip("trimesh")

import shape_diameter
from shape_diameter import batch_job, cli, mesh_io

DATA = Path(__file__).resolve().parents[1] / "data"
RAYS = "4"


def _copy(folder, *names):
    paths = []
    for name in names:
        source = DATA / name.split(":")[0]
        path = folder / name.split(":")[-1]
        shutil.copy(source, path)
        paths.append(path)
    return paths


def _no_compute(*args, **kwargs):
    raise AssertionError("compute() ran: the inputs should have been refused first")


def _assert_one_line_error(stderr):
    assert stderr.endswith("\n") and stderr.count("\n") == 1, stderr
    assert stderr.startswith("shape-diameter: error: "), stderr


def test_several_inputs_are_computed_in_turn(tmp_path, capsys):
    inputs = _copy(tmp_path, "suzanne.obj", "cow.obj", "bunny00.off")
    assert cli.main([*map(str, inputs), "--rays", RAYS, "--save-values"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert len(out) == 3
    for line, source in zip(out, inputs):
        output = source.with_name(source.stem + ".sdf.ply")
        values = source.with_name(source.stem + ".sdf.npy")
        assert line.startswith(f"{source}: ") and line.endswith(f" -> {output}")
        vertices, triangles = mesh_io.load_mesh(source)
        expected = shape_diameter.compute(vertices, triangles, rays=int(RAYS)).raw
        np.testing.assert_array_equal(np.load(values), expected)
        np.testing.assert_array_equal(mesh_io.load_mesh(output)[0], vertices)


REFUSED = {
    "same input twice": (["a.obj", "./a.obj"], "./a.obj: is given twice"),
    "an input is another's output": (["a.obj", "b.obj", "a.sdf.ply"], "is an input, and"),
    "-o with several": (["a.obj", "b.obj", "-o", "x.ply"],
                        "-o/--output names one file, but there are 2 inputs"),
    "--values with several": (["a.obj", "b.obj", "--values", "x.npy"],
                              "--values names one file, but there are 2 inputs: use --save-values"),
    "-o with a folder": (["folder", "-o", "x.ply"], "-o/--output names one file"),
}  # fmt: skip


@pytest.mark.parametrize("case", sorted(REFUSED))
def test_clashing_outputs_are_refused_before_any_work(tmp_path, capsys, monkeypatch, case):
    argv, message = REFUSED[case]
    _copy(tmp_path, "suzanne.obj:a.obj", "cow.obj:b.obj", "spot.obj:c.obj")
    trimesh.load(DATA / "cow.obj").export(tmp_path / "a.ply")
    (tmp_path / "a.sdf.ply").write_bytes((tmp_path / "a.ply").read_bytes())
    (tmp_path / "folder").mkdir()
    _copy(tmp_path / "folder", "suzanne.obj:only.obj")
    before = {p: p.read_bytes() for p in tmp_path.rglob("*") if p.is_file()}
    monkeypatch.setattr(batch_job, "compute", _no_compute)
    monkeypatch.chdir(tmp_path)
    assert cli.main(argv) == 2
    captured = capsys.readouterr()
    _assert_one_line_error(captured.err)
    assert message in captured.err and captured.out == ""
    assert {p: p.read_bytes() for p in tmp_path.rglob("*") if p.is_file()} == before


def test_a_second_input_writing_an_earlier_ones_output_fails_alone(tmp_path, capsys):
    # a.obj and a.ply both make a.sdf.ply: it refused the whole run (one such pair in a
    # folder of thousands); now a.ply fails and the others are computed.
    _copy(tmp_path, "suzanne.obj:a.obj", "cow.obj:b.obj")
    trimesh.load(DATA / "cow.obj").export(tmp_path / "a.ply")
    assert cli.main([str(tmp_path), "--rays", RAYS, "--json", "-q"]) == 2
    captured = capsys.readouterr()
    reports = {Path(r["input"]).name: r for r in map(json.loads, captured.out.splitlines())}
    assert {name: r["status"] for name, r in reports.items()} == {
        "a.obj": "ok",
        "a.ply": "error",
        "b.obj": "ok",
    }
    assert reports["a.ply"]["error"] == (
        f"{tmp_path / 'a.ply'}: would write {tmp_path / 'a.sdf.ply'}, which "
        f"{tmp_path / 'a.obj'} writes: give them separate runs, or rename one"
    )
    assert captured.err == f"shape-diameter: error: {reports['a.ply']['error']}\n"
    vertices, _ = mesh_io.load_mesh(tmp_path / "a.sdf.ply")
    np.testing.assert_array_equal(vertices, mesh_io.load_mesh(tmp_path / "a.obj")[0])


def test_a_link_to_nothing_in_a_folder_fails_as_an_input(tmp_path, capsys):
    # It was skipped without a word: the batch looked complete.
    _copy(tmp_path, "suzanne.obj:a.obj")
    (tmp_path / "gone.obj").symlink_to(tmp_path / "nowhere" / "m.obj")
    assert cli.main([str(tmp_path), "--rays", RAYS, "--json", "-q"]) == 2
    reports = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    assert [(Path(r["input"]).name, r["status"]) for r in reports] == [
        ("a.obj", "ok"),
        ("gone.obj", "error"),
    ]
    assert reports[1]["error"] == (
        f"{tmp_path / 'gone.obj'}: a link to nothing (it points to "
        f"{tmp_path / 'nowhere' / 'm.obj'})"
    )


def test_a_bad_file_among_good_ones_is_reported_and_the_others_go_on(tmp_path, capsys):
    good, other = _copy(tmp_path, "suzanne.obj", "cow.obj")
    bad = tmp_path / "broken.off"
    bad.write_text("OFF\n3 1 0\n0 0 0\n")  # truncated
    argv = [str(good), str(bad), str(other), "--rays", RAYS, "--json"]
    assert cli.main(argv) == 2
    captured = capsys.readouterr()
    _assert_one_line_error(captured.err)
    assert captured.err.startswith(f"shape-diameter: error: {bad}: truncated OFF file")
    reports = [json.loads(line) for line in captured.out.splitlines()]
    assert [r["input"] for r in reports] == [str(good), str(bad), str(other)]
    assert [r["status"] for r in reports] == ["ok", "error", "ok"]
    assert [r["exit_status"] for r in reports] == [0, 2, 0]
    assert reports[1]["error"] == captured.err.removeprefix("shape-diameter: error: ").strip()
    assert reports[1]["outputs"] == {"mesh": None, "values": None}
    assert (tmp_path / "suzanne.sdf.ply").is_file() and (tmp_path / "cow.sdf.ply").is_file()
    assert not (tmp_path / "broken.sdf.ply").exists()


def test_the_exit_status_is_the_first_failures(tmp_path, capsys, monkeypatch):
    # A write that fails (status 1), then a file that is bad (status 2): 1, and both reported.
    # A missing input in a missing folder is a failure of its own, not a refusal of the run.
    first, good = _copy(tmp_path, "suzanne.obj:first.obj", "cow.obj")
    bad = tmp_path / "gone" / "missing.obj"
    real_save = mesh_io.save_colored

    def save_failing_for_first(path, *args, **kwargs):
        if Path(path).name == "first.sdf.ply":
            raise OSError(f"{path}: cannot write (No space left on device); nothing written")
        return real_save(path, *args, **kwargs)

    monkeypatch.setattr(mesh_io, "save_colored", save_failing_for_first)
    assert cli.main([str(first), str(bad), str(good), "--rays", RAYS]) == 1
    captured = capsys.readouterr()
    errors = captured.err.splitlines()
    assert len(errors) == 2
    assert errors[0].startswith(f"shape-diameter: error: {tmp_path / 'first.sdf.ply'}: cannot")
    assert errors[1] == f"shape-diameter: error: {bad}: no such file"
    assert captured.out.count("\n") == 1 and (tmp_path / "cow.sdf.ply").is_file()


def test_quiet_prints_only_warnings_errors_and_json(tmp_path, capsys):
    good, flat = _copy(tmp_path, "suzanne.obj", "suzanne.obj:flat.obj")
    flat.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")  # every ray escapes: a warning
    assert cli.main([str(good), "--rays", RAYS, "--quiet"]) == 0
    assert capsys.readouterr() == ("", "")
    assert cli.main([str(good), str(flat), "--rays", RAYS, "-q"]) == 0
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err.count("\n") == 1
    assert captured.err.startswith(f"shape-diameter: warning: {flat}: no ray of any point")
    assert cli.main([str(good), str(flat), "--rays", RAYS, "-q", "--json"]) == 0
    reports = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    assert [r["status"] for r in reports] == ["ok", "ok"]
    assert reports[0]["warnings"] == []
    assert len(reports[1]["warnings"]) == 1
    assert reports[1]["warnings"][0].startswith("no ray of any point found the other side")


def test_json_lists_each_files_warnings(tmp_path, capsys):
    # Warnings of writing too: a GLB far from the origin.
    sphere = trimesh.creation.icosphere(subdivisions=2, radius=5.0)
    source = tmp_path / "site.off"
    trimesh.Trimesh(sphere.vertices + (5e5, 5.4e6, 0), sphere.faces).export(source, digits=17)
    output = tmp_path / "site.glb"
    assert cli.main([str(source), "-o", str(output), "--rays", RAYS, "--json"]) == 0
    captured = capsys.readouterr()
    report = json.loads(captured.out)
    assert len(report["warnings"]) == 1
    assert report["warnings"][0].startswith(f"{output}: GLB holds 32-bit float coordinates")
    assert captured.err == f"shape-diameter: warning: {report['warnings'][0]}\n"


def test_a_folder_stands_for_its_meshes_without_the_commands_outputs(tmp_path, capsys):
    folder = tmp_path / "meshes"
    (folder / "sub").mkdir(parents=True)
    _copy(folder, "suzanne.obj:b.obj", "bunny00.off:a.off", "cow.obj:.hidden.obj",
          "cow.obj:sub/c.obj")  # fmt: skip
    (folder / "notes.txt").write_text("not a mesh\n")
    for _ in range(2):  # the second run meets the first one's outputs and skips them
        assert cli.main([str(folder), "--rays", RAYS, "--json"]) == 0
        reports = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
        assert [r["input"] for r in reports] == [str(folder / "a.off"), str(folder / "b.obj")]
    assert sorted(p.name for p in folder.iterdir()) == [
        ".hidden.obj", "a.off", "a.sdf.ply", "b.obj", "b.sdf.ply", "notes.txt", "sub"
    ]  # fmt: skip


def test_a_folder_without_meshes_is_a_failure_of_its_own(tmp_path, capsys):
    empty = tmp_path / "empty"
    empty.mkdir()
    (good,) = _copy(tmp_path, "suzanne.obj")
    assert cli.main([str(empty), str(good), "--rays", RAYS, "-q"]) == 2
    captured = capsys.readouterr()
    _assert_one_line_error(captured.err)
    assert f"{empty}: no mesh files in the folder" in captured.err
    assert (tmp_path / "suzanne.sdf.ply").is_file()


def test_a_folder_that_cannot_be_listed_is_a_failure_of_its_own(tmp_path, capsys, monkeypatch):
    # (Permissions do not stop root, who runs the tests: the listing is made to fail.)
    locked = tmp_path / "locked"
    locked.mkdir()
    (good,) = _copy(tmp_path, "suzanne.obj")
    real_scandir = cli.os.scandir

    def scandir(path):
        if Path(path) == locked:
            raise PermissionError(13, "Permission denied")
        return real_scandir(path)

    monkeypatch.setattr(cli.os, "scandir", scandir)
    assert cli.main([str(locked), str(good), "--rays", RAYS, "-q"]) == 2
    captured = capsys.readouterr()
    assert captured.err == (f"shape-diameter: error: {locked}: cannot list the folder "
                            "(Permission denied)\n")  # fmt: skip
    assert (tmp_path / "suzanne.sdf.ply").is_file()


def test_a_batch_in_one_process_costs_one_startup(tmp_path):
    # Three files in one process, against three processes: the start-up (Python, numpy,
    # trimesh: about 0.9 s here) is paid once.
    inputs = _copy(tmp_path, "suzanne.obj:a.obj", "suzanne.obj:b.obj", "suzanne.obj:c.obj")
    command = [sys.executable, "-m", "shape_diameter", "--rays", "2", "-q"]
    import time

    # Once first, so that neither side compiles OpenCL programs (a machine with a GPU and a
    # cold program cache: the batch, timed first, compiled them; 8.9 s against 7.3).
    assert subprocess.run([*command, str(inputs[0])], check=False, timeout=120).returncode == 0
    start = time.perf_counter()
    done = subprocess.run([*command, *map(str, inputs)], check=False, timeout=120)
    together = time.perf_counter() - start
    assert done.returncode == 0
    start = time.perf_counter()
    for source in inputs:
        assert subprocess.run([*command, str(source)], check=False, timeout=120).returncode == 0
    apart = time.perf_counter() - start
    assert together < apart


# --- shape_diameter.load_mesh ------------------------------------------------------------


@pytest.mark.parametrize("name", ["suzanne.obj", "horse.ply", "bunny00.off"])
def test_load_mesh_is_the_command_lines_reader(name):
    vertices, triangles = shape_diameter.load_mesh(DATA / name)
    expected_vertices, expected_triangles = mesh_io.load_mesh(DATA / name)
    np.testing.assert_array_equal(vertices, expected_vertices)
    np.testing.assert_array_equal(triangles, expected_triangles)
    assert vertices.dtype == np.float64 and triangles.dtype == np.int64
    assert "load_mesh" in shape_diameter.__all__ and shape_diameter.load_mesh.__doc__


def test_load_mesh_refuses_bad_files_with_value_error(tmp_path):
    with pytest.raises(ValueError, match="missing.obj: no such file"):
        shape_diameter.load_mesh(tmp_path / "missing.obj")


def test_load_mesh_without_trimesh_says_what_to_install():
    code = (
        "import sys; sys.modules['trimesh'] = None\n"
        "import shape_diameter\n"
        "try:\n"
        f"    shape_diameter.load_mesh({str(DATA / 'cow.obj')!r})\n"
        "except ImportError as exc:\n"
        "    print(exc)\n"
    )
    done = subprocess.run([sys.executable, "-c", code], check=False, capture_output=True,
                          text=True, timeout=60)  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert "pip install 'shape_diameter[cli]'" in done.stdout


def test_a_folder_run_that_finds_no_mesh_makes_no_output_folder(tmp_path, capsys):
    empty = tmp_path / "empty"
    empty.mkdir()
    out = tmp_path / "out"
    assert cli.main([str(empty), "--output-dir", str(out), "--rays", RAYS, "-q"]) == 2
    assert f"{empty}: no mesh files in the folder" in capsys.readouterr().err
    assert not out.exists()
