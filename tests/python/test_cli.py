# SPDX-License-Identifier: GPL-3.0-or-later
"""The shape-diameter command: every input format, its outputs, --json, and one-line errors."""

import io
import json
import os
import shutil
import stat
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

trimesh = pytest.importorskip("trimesh")

import shape_diameter
from polygon_files import fanned, prism, write_polygons
from shape_diameter import batch_job, cli
from shape_diameter.colormap import colormap
from shape_diameter.mesh_io import load_mesh

DATA = Path(__file__).resolve().parents[1] / "data"
RAYS = 12  # enough rays to be a real run, few enough to keep the file fast
JSON_KEYS = {
    "input", "faces", "vertices", "points", "point_count", "rays", "cone", "sampling",
    "seed", "normalize", "smooth", "engine", "flipped_faces", "twin_faces", "seconds",
    "Mrays_per_s", "io_seconds", "total_seconds", "outputs", "status", "error", "exit_status",
    "warnings",
}  # fmt: skip


@pytest.fixture(scope="module")
def spot():
    return load_mesh(DATA / "spot.obj")


@pytest.fixture(scope="module")
def inputs(tmp_path_factory, spot):
    """spot.obj as it is, and converted by trimesh to each other input format."""
    folder = tmp_path_factory.mktemp("inputs")
    shutil.copy(DATA / "spot.obj", folder / "spot.obj")
    for suffix in (".ply", ".off", ".stl", ".glb"):
        trimesh.Trimesh(*spot, process=False).export(folder / f"spot{suffix}")
    return folder


def _run_process(*args, cwd=None):
    """The command as users run it: a separate Python process."""
    return subprocess.run(
        [sys.executable, "-m", "shape_diameter.cli", *map(str, args)],
        check=False,
        capture_output=True,
        text=True,
        cwd=cwd,
        timeout=120,
    )


def _assert_one_line_error(stderr, stdout=""):
    assert stderr.endswith("\n") and stderr.count("\n") == 1, stderr
    assert stderr.startswith("shape-diameter: error: "), stderr
    assert "Traceback" not in stderr
    assert stdout == ""


# --- every input format -------------------------------------------------------


@pytest.mark.parametrize("suffix", [".obj", ".ply", ".off", ".stl", ".glb"])
def test_each_input_format_gives_the_sdf_of_the_same_mesh(tmp_path, inputs, spot, suffix):
    source = inputs / f"spot{suffix}"
    output, values = tmp_path / "out.ply", tmp_path / "values.npy"
    status = cli.main(
        [str(source), "-o", str(output), "--values", str(values), "--rays", str(RAYS)]
    )
    assert status == 0

    saved = np.load(values)
    assert saved.dtype == np.float32 and saved.shape == (len(spot[1]),)
    # Exactly what compute() gives for the mesh as read from that file...
    expected = shape_diameter.compute(*load_mesh(source), rays=RAYS)
    np.testing.assert_array_equal(saved, expected.raw)
    # ...which is spot's SDF, up to the float32 coordinates of PLY, STL and GLB.
    reference = shape_diameter.compute(*spot, rays=RAYS).raw
    np.testing.assert_allclose(saved, reference, rtol=0, atol=1e-4 * reference.max())

    # The output is the same mesh, coloured per face by the normalised SDF.
    _, out_triangles = load_mesh(output)
    assert out_triangles.shape == spot[1].shape
    faces = next(iter(trimesh.load(output, process=False, force="scene").geometry.values()))
    np.testing.assert_array_equal(faces.visual.face_colors, colormap(expected.normalized))


def test_per_vertex_values_and_colours(tmp_path, spot):
    output, values = tmp_path / "out.ply", tmp_path / "values.npy"
    argv = [str(DATA / "spot.obj"), "-o", str(output), "--values", str(values)]
    assert cli.main([*argv, "--points", "vertices", "--rays", str(RAYS)]) == 0
    expected = shape_diameter.compute(*spot, rays=RAYS, points="vertices")
    np.testing.assert_array_equal(np.load(values), expected.raw)
    assert np.load(values).shape == (len(spot[0]),)
    mesh = next(iter(trimesh.load(output, process=False, force="scene").geometry.values()))
    assert mesh.visual.kind == "vertex"
    np.testing.assert_array_equal(mesh.visual.vertex_colors, colormap(expected.normalized))


def test_options_reach_compute(tmp_path, spot):
    values = tmp_path / "values.npy"
    argv = [str(DATA / "spot.obj"), "-o", str(tmp_path / "out.obj"), "--values", str(values)]
    options = ["--rays", "7", "--cone", "90", "--sampling", "random", "--seed", "5"]
    assert cli.main([*argv, *options, "--normalize", "log"]) == 0
    expected = shape_diameter.compute(
        *spot, rays=7, cone_angle=90.0, sampling="random", seed=5, normalize="log"
    )
    np.testing.assert_array_equal(np.load(values), expected.raw)


def test_default_output_is_next_to_the_input(tmp_path, capsys):
    source = tmp_path / "cow.obj"
    shutil.copy(DATA / "cow.obj", source)
    assert cli.main([str(source), "--rays", "4"]) == 0
    assert load_mesh(tmp_path / "cow.sdf.ply")[1].shape == (5804, 3)
    out = capsys.readouterr().out
    assert out.count("\n") == 1 and "cow.sdf.ply" in out
    assert ", no smoothing, " in out


def test_the_line_of_an_input_says_which_smoothing_ran(tmp_path, capsys):
    source = tmp_path / "cow.obj"
    shutil.copy(DATA / "cow.obj", source)
    assert cli.main([str(source), "--rays", "4", "--smooth", "kring"]) == 0
    assert ", kring smoothing, " in capsys.readouterr().out


def test_a_mesh_at_utm_coordinates_keeps_its_geometry(tmp_path, capsys):
    # A 10 m sphere at UTM coordinates: the default PLY output once held float32 coordinates
    # (0.25 m off); now the same doubles come back. GLB can only warn, in one line.
    sphere = trimesh.creation.icosphere(subdivisions=2, radius=5.0)
    vertices = np.asarray(sphere.vertices) + (500000.123, 5400000.456, 100.789)
    source = tmp_path / "site.off"
    trimesh.Trimesh(vertices, sphere.faces, process=False).export(source, digits=17)
    vertices, triangles = load_mesh(source)
    assert cli.main([str(source), "--rays", "4"]) == 0
    written_vertices, written_triangles = load_mesh(tmp_path / "site.sdf.ply")
    np.testing.assert_array_equal(written_vertices, vertices)
    np.testing.assert_array_equal(written_triangles, triangles)
    assert capsys.readouterr().err == ""

    assert cli.main([str(source), "--rays", "4", "-o", str(tmp_path / "site.glb")]) == 0
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("shape-diameter: warning: ")
    assert "GLB holds 32-bit float coordinates" in err and ".ply, .off or .obj" in err


def test_values_rows_follow_the_files_faces_in_every_format(tmp_path):
    # One polygon mesh as OBJ, OFF and PLY: the same rows, in the file's face order, each
    # polygon's triangles together (PLY and OFF rows were grouped by polygon size).
    vertices, polygons = prism()
    rows = {}
    for suffix in (".obj", ".off", ".ply"):
        source, values = tmp_path / f"prism{suffix}", tmp_path / f"{suffix[1:]}.npy"
        write_polygons(source, vertices, polygons)
        argv = [str(source), "-o", str(tmp_path / f"out{suffix}"), "--values", str(values)]
        assert cli.main([*argv, "--rays", str(RAYS), "-q"]) == 0
        rows[suffix] = np.load(values)
    triangles, _ = fanned(polygons)
    expected = shape_diameter.compute(vertices, triangles, rays=RAYS).raw
    for values in rows.values():
        np.testing.assert_array_equal(values, expected)
    _, _, source_faces = shape_diameter.load_mesh(tmp_path / "prism.ply", source_faces=True)
    assert source_faces.tolist() == [0, 0, 1, 1, 1, 2, 2, 3, 4, 5, 5, 5, 6, 6, 7, 7]


# --- --json -------------------------------------------------------------------


def test_json_is_one_object_with_the_documented_keys(tmp_path):
    output, values = tmp_path / "spot.glb", tmp_path / "v.npy"
    done = _run_process(
        DATA / "spot.obj", "-o", output, "--values", values, "--rays", RAYS, "--json"
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.endswith("\n") and done.stdout.count("\n") == 1
    report = json.loads(done.stdout)
    assert set(report) == JSON_KEYS
    assert (report["status"], report["error"], report["exit_status"]) == ("ok", None, 0)
    assert report["warnings"] == []
    assert (report["faces"], report["vertices"]) == (5856, 2930)
    assert (report["points"], report["point_count"], report["rays"]) == ("faces", 5856, RAYS)
    assert (report["cone"], report["sampling"], report["seed"]) == (120.0, "fibonacci", 0)
    assert report["input"] == str(DATA / "spot.obj")
    assert report["engine"].startswith(("cpu", "opencl"))  # auto: a GPU where there is one
    assert report["seconds"]["cast"] > 0
    assert report["Mrays_per_s"] == pytest.approx(5856 * RAYS / report["seconds"]["cast"] / 1e6)
    assert set(report["io_seconds"]) == {"load", "write"}
    assert report["total_seconds"] >= report["seconds"]["total"]
    assert report["outputs"] == {"mesh": str(output), "values": str(values)}
    assert output.is_file() and values.is_file()
    assert "Traceback" not in done.stderr


def test_console_script_runs():
    script = Path(sys.executable).with_name("shape-diameter")
    if not script.exists():
        pytest.skip("package not installed with its console script in this environment")
    done = subprocess.run(
        [str(script), "--version"], check=False, capture_output=True, text=True, timeout=60
    )
    assert done.returncode == 0
    assert done.stdout.strip() == f"shape-diameter {shape_diameter.__version__}"


# --- one-line errors, status 2 ---------------------------------------------------


def _garbage_obj(folder):
    path = folder / "garbage.obj"
    path.write_text("this is not\na mesh\nf 1 2 x\n")
    return path


def _truncated_ply(folder):
    whole, path = folder / "whole.ply", folder / "truncated.ply"
    save = trimesh.Trimesh(*load_mesh(DATA / "suzanne.obj"), process=False)
    save.export(whole, encoding="binary")
    path.write_bytes(whole.read_bytes()[:-700])
    return path


def _point_cloud(folder):
    path = folder / "cloud.ply"
    trimesh.PointCloud(np.random.default_rng(0).random((30, 3))).export(path)
    return path


def _truncated_off(folder):
    # 60% of an ASCII OFF: once read as a mesh of fewer faces than its header declares.
    path = folder / "truncated.off"
    data = (DATA / "bunny00.off").read_bytes()
    path.write_bytes(data[: int(len(data) * 0.6)])
    return path


PROCESS_FAILURES = {
    "missing file": lambda folder: [folder / "missing.obj"],
    "truncated off": lambda folder: [_truncated_off(folder)],
    "garbage obj": lambda folder: [_garbage_obj(folder)],
    "truncated ply": lambda folder: [_truncated_ply(folder)],
    "negative rays": lambda folder: [DATA / "spot.obj", "--rays", "-5"],
    "unknown points": lambda folder: [DATA / "spot.obj", "--points", "edges"],
}


@pytest.mark.parametrize("case", sorted(PROCESS_FAILURES))
def test_failures_print_one_line_and_exit_2(tmp_path, case):
    done = _run_process(*PROCESS_FAILURES[case](tmp_path), "--json", cwd=tmp_path)
    assert done.returncode == 2
    if case in ("negative rays", "unknown points"):  # refused before any input is read
        _assert_one_line_error(done.stderr, done.stdout)
    else:  # a bad input: its --json object says so too
        _assert_one_line_error(done.stderr)
        report = json.loads(done.stdout)
        assert done.stdout.count("\n") == 1
        assert (report["status"], report["exit_status"]) == ("error", 2)
        assert done.stderr == f"shape-diameter: error: {report['error']}\n"
        assert report["error"].startswith(f"{report['input']}: ")
    assert not list(tmp_path.glob("*.sdf.ply"))


IN_PROCESS_FAILURES = {
    "no input": lambda folder: [],
    "point cloud": lambda folder: [_point_cloud(folder)],
    "not a number of rays": lambda folder: [DATA / "spot.obj", "--rays", "many"],
    "too many rays": lambda folder: [DATA / "spot.obj", "--rays", "100000"],
    "cone too wide": lambda folder: [DATA / "spot.obj", "--cone", "180"],
    "unknown sampling": lambda folder: [DATA / "spot.obj", "--sampling", "grid"],
    "unknown bvh quality": lambda folder: [DATA / "spot.obj", "--bvh-quality", "best"],
    "unknown option": lambda folder: [DATA / "spot.obj", "--fast"],
    "unknown output format": lambda folder: [DATA / "spot.obj", "-o", folder / "out.fbx"],
    "output folder missing": lambda folder: [DATA / "spot.obj", "-o", folder / "no/out.ply"],
    "values folder missing": lambda folder: [
        DATA / "spot.obj", "-o", folder / "out.ply", "--values", folder / "no/v.npy"
    ],
}  # fmt: skip


@pytest.mark.parametrize("case", sorted(IN_PROCESS_FAILURES))
def test_bad_input_and_options_in_process(tmp_path, capsys, case):
    argv = [str(arg) for arg in IN_PROCESS_FAILURES[case](tmp_path)]
    assert cli.main(argv) == 2
    captured = capsys.readouterr()
    _assert_one_line_error(captured.err, captured.out)
    assert not (tmp_path / "out.ply").exists()


def test_a_value_error_from_compute_is_one_line_and_status_2(tmp_path, capsys, monkeypatch):
    # Options are checked before compute(), so force a real compute() refusal.
    real_compute = shape_diameter.compute

    def compute_with_bad_cone(*args, **kwargs):
        return real_compute(*args, **{**kwargs, "cone_angle": 500.0})

    monkeypatch.setattr(batch_job, "compute", compute_with_bad_cone)
    assert cli.main([str(DATA / "suzanne.obj"), "-o", str(tmp_path / "out.ply")]) == 2
    captured = capsys.readouterr()
    _assert_one_line_error(captured.err, captured.out)
    assert "cone_angle" in captured.err


def test_truncated_off_says_so(tmp_path, capsys):
    assert cli.main([str(_truncated_off(tmp_path)), "-o", str(tmp_path / "out.ply")]) == 2
    captured = capsys.readouterr()
    _assert_one_line_error(captured.err, captured.out)
    assert "truncated OFF file: the header declares 75408 faces" in captured.err


def test_a_file_not_of_its_format_says_so(tmp_path, capsys):
    # A PLY renamed .stl once failed with "No module named 'charset_normalizer'".
    renamed = tmp_path / "horse.stl"
    shutil.copy(DATA / "horse.ply", renamed)
    assert cli.main([str(renamed), "-o", str(tmp_path / "out.ply")]) == 2
    captured = capsys.readouterr()
    _assert_one_line_error(captured.err, captured.out)
    assert "not a valid STL file (it looks like a PLY file)" in captured.err


def test_a_mesh_too_wide_names_its_file(tmp_path, capsys):
    # compute()'s refusal of a mesh wider than 1e30 once did not say which file it was.
    source = tmp_path / "huge.obj"
    source.write_text("v 0 0 0\nv 2e30 0 0\nv 0 2e30 0\nv 0 0 2e30\n"
                      "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n")  # fmt: skip
    assert cli.main([str(source), "-o", str(tmp_path / "out.ply")]) == 2
    captured = capsys.readouterr()
    _assert_one_line_error(captured.err, captured.out)
    assert captured.err.startswith(f"shape-diameter: error: {source}: the mesh spans 2e+30")
    assert not (tmp_path / "out.ply").exists()


def _no_compute(*args, **kwargs):
    raise AssertionError("compute() ran: the paths should have been refused first")


@pytest.mark.parametrize("case", ["output", "output spelled otherwise", "values", "hard link",
                                  "values is output"])  # fmt: skip
def test_outputs_never_overwrite_the_input_or_each_other(tmp_path, capsys, monkeypatch, case):
    source = tmp_path / "in.obj"
    shutil.copy(DATA / "spot.obj", source)
    (tmp_path / "sub").mkdir()
    monkeypatch.setattr(batch_job, "compute", _no_compute)
    monkeypatch.chdir(tmp_path)
    if case == "hard link":
        (tmp_path / "link.obj").hardlink_to(source)
    argv = {
        "output": ["in.obj", "-o", "in.obj"],
        "output spelled otherwise": [str(source), "-o", "sub/../in.obj"],
        "values": ["in.obj", "-o", "out.ply", "--values", "./in.obj"],
        "hard link": ["in.obj", "-o", "link.obj"],
        "values is output": ["in.obj", "-o", "out.ply", "--values", "out.ply"],
    }[case]
    assert cli.main(argv) == 2
    captured = capsys.readouterr()
    _assert_one_line_error(captured.err, captured.out)
    assert ("is also the mesh output" if case == "values is output" else "is the input file") in (
        captured.err
    )
    assert source.read_bytes() == (DATA / "spot.obj").read_bytes()
    assert not (tmp_path / "out.ply").exists()


def _limit_file_size():
    import resource

    resource.setrlimit(resource.RLIMIT_FSIZE, (100_000, resource.RLIM_INFINITY))


@pytest.mark.parametrize("suffix", [".ply", ".obj", ".off", ".glb", ".stl"])
def test_a_failed_write_leaves_the_existing_output_as_it_was(tmp_path, suffix):
    # `ulimit -f 100` once left 100 KB of the output in place of a good, older one.
    output = tmp_path / f"big{suffix}"
    output.write_bytes(b"the output of an earlier run\n")
    done = subprocess.run(
        [sys.executable, "-m", "shape_diameter.cli", str(DATA / "horse.ply"), "-o", str(output),
         "--rays", "2", "--engine", "cpu"],
        check=False, capture_output=True, text=True, timeout=120, preexec_fn=_limit_file_size,
    )  # fmt: skip
    assert done.returncode == 1
    _assert_one_line_error(done.stderr, done.stdout)
    assert f"{output}: cannot write (File too large)" in done.stderr
    assert "the existing file is left as it was" in done.stderr
    assert output.read_bytes() == b"the output of an earlier run\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == [output.name]  # no temporary left


def test_a_failed_values_write_leaves_no_part_of_it(tmp_path, capsys, monkeypatch):
    values = tmp_path / "values.npy"
    real_save = np.save

    def save_half_then_fail(stream, array):
        real_save(stream, array[: len(array) // 2])
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(np, "save", save_half_then_fail)
    argv = [str(DATA / "suzanne.obj"), "-o", str(tmp_path / "out.ply"), "--values", str(values)]
    assert cli.main([*argv, "--rays", "2"]) == 1
    captured = capsys.readouterr()
    _assert_one_line_error(captured.err)
    assert f"{values}: cannot write (No space left on device); nothing written" in captured.err
    # Nor the mesh: both are written together (it was, while the report said nothing was).
    assert list(tmp_path.iterdir()) == []


def test_outputs_replace_files_whole_and_keep_links_and_permissions(tmp_path):
    # The new file takes the old one's permissions; a link stays a link to the new content.
    real, link = tmp_path / "real.ply", tmp_path / "link.ply"
    real.write_bytes(b"old")
    real.chmod(0o640)
    link.symlink_to(real)
    assert cli.main([str(DATA / "suzanne.obj"), "-o", str(link), "--rays", "2"]) == 0
    assert link.is_symlink() and real.read_bytes().startswith(b"ply\n")
    assert real.stat().st_mode & 0o777 == 0o640
    assert sorted(p.name for p in tmp_path.iterdir()) == ["link.ply", "real.ply"]


def test_an_opencl_failure_is_one_line_and_status_1(tmp_path, capsys, monkeypatch):
    # A RuntimeError the command did not catch: it once printed a traceback.
    from shape_diameter import _core

    if not hasattr(_core, "OpenCLError"):
        pytest.skip("built without OpenCL")

    def failing_compute(*args, **kwargs):
        raise _core.OpenCLError("OpenCL clBuildProgram failed: CL_BUILD_PROGRAM_FAILURE on X; "
                                "build log:\nerror: line 1\nerror: line 2")  # fmt: skip

    monkeypatch.setattr(batch_job, "compute", failing_compute)
    assert cli.main([str(DATA / "suzanne.obj"), "-o", str(tmp_path / "out.ply")]) == 1
    captured = capsys.readouterr()
    _assert_one_line_error(captured.err, captured.out)
    assert "clBuildProgram failed" in captured.err and "error: line" not in captured.err


def test_out_of_memory_is_one_line_and_status_1(tmp_path, capsys, monkeypatch):
    def failing_compute(*args, **kwargs):
        raise MemoryError()

    monkeypatch.setattr(batch_job, "compute", failing_compute)
    assert cli.main([str(DATA / "suzanne.obj"), "-o", str(tmp_path / "out.ply")]) == 1
    captured = capsys.readouterr()
    _assert_one_line_error(captured.err, captured.out)
    assert "out of memory" in captured.err


def test_a_device_too_small_is_one_line_and_status_1(tmp_path):
    if not any(e["name"].startswith("opencl") for e in shape_diameter.engines()):
        pytest.skip("no OpenCL device")
    done = subprocess.run(
        [sys.executable, "-m", "shape_diameter.cli", str(DATA / "bunny00.off"), "-o",
         str(tmp_path / "x.ply"), "--engine", "opencl:0"],
        check=False, capture_output=True, text=True, timeout=120,
        env={**os.environ, "SDF_OPENCL_MAX_MEMORY": "100000"},
    )  # fmt: skip
    assert done.returncode == 1
    _assert_one_line_error(done.stderr, done.stdout)
    assert "does not fit OpenCL device" in done.stderr and "use --engine cpu" in done.stderr


def test_help_documents_exit_statuses_and_overwriting(capsys):
    assert cli.main(["--help"]) == 0
    text = " ".join(capsys.readouterr().out.split())
    assert "an existing OUTPUT is overwritten" in text
    assert (
        "1 missing dependency, OpenCL missing for --engine opencl..., OpenCL device failure"
    ) in text
    assert "refused before any input is read" in text


def test_compute_warnings_are_one_line(tmp_path, capsys):
    # A lone triangle: every ray escapes, compute() warns and fills zeros.
    source = tmp_path / "flat.obj"
    source.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    assert cli.main([str(source), "--json"]) == 0
    captured = capsys.readouterr()
    assert captured.err.count("\n") == 1 and captured.err.startswith("shape-diameter: warning: ")
    assert json.loads(captured.out)["faces"] == 1


def test_version(capsys):
    assert cli.main(["--version"]) == 0
    assert capsys.readouterr().out.strip() == f"shape-diameter {shape_diameter.__version__}"


def test_python_dash_m_runs_the_command_line():
    done = subprocess.run([sys.executable, "-m", "shape_diameter", "--version"], check=False,
                          capture_output=True, text=True, timeout=60)  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == f"shape-diameter {shape_diameter.__version__}"


def test_help_documents_the_default_output(capsys):
    assert cli.main(["--help"]) == 0
    assert ".sdf.ply" in capsys.readouterr().out


# --- optional dependencies and the progress bar -------------------------------------


def test_package_imports_without_the_cli_extra(tmp_path):
    # None in sys.modules makes an import fail as if the package were absent.
    code = (
        "import sys; sys.modules['trimesh'] = None; sys.modules['tqdm'] = None\n"
        "import shape_diameter, shape_diameter.colormap\n"
        "from shape_diameter.cli import main\n"
        f"sys.exit(main([{str(DATA / 'spot.obj')!r}]))\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", code],
        check=False,
        capture_output=True,
        text=True,
        timeout=60,
        cwd=tmp_path,
    )
    assert done.returncode == 1
    _assert_one_line_error(done.stderr, done.stdout)
    assert "shape_diameter[cli]" in done.stderr


class _Terminal(io.StringIO):
    def isatty(self):
        return True


def test_progress_bar_only_on_a_terminal(monkeypatch):
    log = io.StringIO()
    monkeypatch.setattr(sys, "stderr", log)
    with cli._progress_bar() as progress:
        progress(0.5)  # a silent callback: Ctrl-C still gets through (below)
    assert log.getvalue() == ""
    terminal = _Terminal()
    monkeypatch.setattr(sys, "stderr", terminal)
    with cli._progress_bar() as progress:
        for fraction in (0.0, 0.5, 0.25, 1.0, 2.0):  # repeated or odd values are harmless
            progress(fraction)
    # Quick runs stay quiet: the bar shows only after half a second.
    assert terminal.getvalue() == ""


def test_progress_reaches_compute_and_json_stays_clean(tmp_path, capsys, monkeypatch):
    seen = []
    real_compute = shape_diameter.compute

    def recording_compute(*args, **kwargs):
        seen.append(kwargs["progress"])
        return real_compute(*args, **kwargs)

    monkeypatch.setattr(batch_job, "compute", recording_compute)
    monkeypatch.setattr(sys, "stderr", _Terminal())
    argv = [str(DATA / "suzanne.obj"), "-o", str(tmp_path / "out.ply"), "--json"]
    assert cli.main(argv) == 0
    assert len(seen) == 1 and callable(seen[0])
    assert json.loads(capsys.readouterr().out)["faces"] == 968


def test_engine_accel_and_orientation_options_reach_compute(tmp_path, capsys):
    out = tmp_path / "horse.ply"
    code = cli.main(
        [
            str(DATA / "horse.ply"),
            "-o",
            str(out),
            "--rays",
            "4",
            "--engine",
            "cpu",
            "--accel",
            "octree",
            "--orientation",
            "auto",
            "--threads",
            "1",
            "--json",
        ]
    )
    assert code == 0
    report = json.loads(capsys.readouterr().out)
    assert report["engine"] == "cpu (1 thread, octree)"
    assert report["flipped_faces"] == report["faces"]  # the horse is inside out


def test_an_unknown_device_is_one_line_and_status_2(tmp_path):
    done = subprocess.run(
        [
            sys.executable,
            "-m",
            "shape_diameter.cli",
            str(DATA / "cow.obj"),
            "-o",
            str(tmp_path / "x.ply"),
            "--engine",
            "opencl:99",
        ],
        capture_output=True,
        text=True,
    )
    assert done.returncode == 2
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and "no OpenCL device 99" in lines[0], done.stderr


@pytest.mark.parametrize("quality", ["high", "fast"])
def test_bvh_quality_reaches_compute_and_keeps_the_values(tmp_path, monkeypatch, quality):
    # The tree changes the speed, never the values: check the option arrives, and the result.
    seen = {}

    def recording(*args, **kwargs):
        seen.update(kwargs)
        return shape_diameter.compute(*args, **kwargs)

    monkeypatch.setattr(batch_job, "compute", recording)
    values = tmp_path / "values.npy"
    argv = [
        str(DATA / "cow.obj"),
        "-o",
        str(tmp_path / "out.ply"),
        "--values",
        str(values),
        "--engine",
        "cpu",
        "--bvh-quality",
        quality,
    ]
    assert cli.main(argv) == 0
    assert seen["bvh_quality"] == quality
    vertices, triangles = load_mesh(DATA / "cow.obj")
    expected = shape_diameter.compute(vertices, triangles, engine="cpu")
    np.testing.assert_array_equal(np.load(values), expected.raw)


def test_ctrl_c_stops_a_long_run_when_stderr_is_not_a_terminal(tmp_path):
    # Native code runs without Python, which sees SIGINT only when a progress callback returns
    # to it: without a terminal there is no bar, but still a callback (an interrupt once waited
    # for the whole run, 11-20 s here).
    import signal
    import time

    run = subprocess.Popen(
        [sys.executable, "-m", "shape_diameter", str(DATA / "spot.obj"), "-o",
         str(tmp_path / "out.ply"), "--engine", "cpu", "--smooth", "texture",
         "--texture-size", "8192"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    time.sleep(2.5)  # started, and into the work
    start = time.perf_counter()
    run.send_signal(signal.SIGINT)
    _, err = run.communicate(timeout=60)
    assert run.returncode == -signal.SIGINT and "interrupted" in err  # (test_cli_interrupt.py)
    assert time.perf_counter() - start < 5.0


def test_values_into_a_pipe_or_a_device_write_into_it(tmp_path):
    # --values /dev/null (or a FIFO) was replaced by a plain file: run as root, /dev/null of
    # the whole machine (and so /dev/full).
    import threading

    fifo = tmp_path / "values.npy"
    os.mkfifo(fifo)
    got = []
    reader = threading.Thread(target=lambda: got.append(fifo.read_bytes()))
    reader.start()
    assert (
        cli.main(
            [
                str(DATA / "suzanne.obj"),
                "-o",
                str(tmp_path / "a.ply"),
                "--rays",
                str(RAYS),
                "--values",
                str(fifo),
                "-q",
            ]
        )
        == 0
    )
    reader.join(timeout=60)
    assert stat.S_ISFIFO(os.stat(fifo).st_mode)
    values = np.load(io.BytesIO(got[0]))
    expected = shape_diameter.compute(*load_mesh(DATA / "suzanne.obj"), rays=RAYS).values
    np.testing.assert_array_equal(values, expected)
    assert (
        cli.main(
            [
                str(DATA / "suzanne.obj"),
                "-o",
                str(tmp_path / "b.ply"),
                "--rays",
                str(RAYS),
                "--values",
                os.devnull,
                "-q",
            ]
        )
        == 0
    )
    assert stat.S_ISCHR(os.stat(os.devnull).st_mode)


def test_one_input_whose_output_cannot_be_written_fails_alone(tmp_path, capsys):
    # An output path that is a folder stopped the whole batch, with no JSON.
    for name in ("a", "b"):
        (tmp_path / f"{name}.obj").write_bytes((DATA / "suzanne.obj").read_bytes())
    (tmp_path / "a.sdf.ply").mkdir()
    assert cli.main([str(tmp_path), "--rays", str(RAYS), "--json", "-q"]) == 2
    reports = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    assert [r["status"] for r in reports] == ["error", "ok"]
    assert "is a folder" in reports[0]["error"]
    assert (tmp_path / "b.sdf.ply").is_file()


def test_output_with_a_folder_of_one_mesh_says_it_is_a_folder(tmp_path, capsys):
    (tmp_path / "a.obj").write_bytes((DATA / "suzanne.obj").read_bytes())
    assert cli.main([str(tmp_path), "-o", str(tmp_path / "x.ply")]) == 2
    assert "but the input is a folder" in capsys.readouterr().err


def _shell(command, tmp_path):
    """`command` in bash, with $SD the command as users run it (its console entry)."""
    entry = f"{sys.executable} -c 'import _shape_diameter_entry as e, sys; sys.exit(e.main())'"
    return subprocess.run(
        ["bash", "-c", f'SD="{entry}"; {command}'],
        cwd=tmp_path,
        capture_output=True,
        timeout=120,
        check=False,
    )


def test_a_closed_stderr_loses_only_the_messages(tmp_path):
    # With standard error closed (2>&-, a daemon's wrapper) the run failed on its
    # first message, writing nothing, with exit status 1 and no word.
    shutil.copy(DATA / "suzanne.obj", tmp_path / "a.obj")
    done = _shell(f"eval $SD a.obj --rays {RAYS} 2>&-; echo status $?", tmp_path)
    assert done.stdout.decode().split()[-2:] == ["status", "0"], done
    assert (tmp_path / "a.sdf.ply").is_file()


def test_values_into_dev_stdout_on_a_pipe(tmp_path):
    # /dev/stdout on a pipe links to /proc/self/fd/1, 'pipe:[N]': 'cannot write
    # (No such file or directory)'.
    shutil.copy(DATA / "suzanne.obj", tmp_path / "a.obj")
    done = _shell(
        f"eval $SD a.obj -o b.ply -q --rays {RAYS} --values /dev/stdout | cat > v.npy; "
        "echo ${PIPESTATUS[0]}",
        tmp_path,
    )
    assert done.stdout.decode().split() == ["0"], done
    values = np.load(tmp_path / "v.npy")
    expected = shape_diameter.compute(*load_mesh(DATA / "suzanne.obj"), rays=RAYS).values
    np.testing.assert_array_equal(values, expected)


def test_a_stdout_that_cannot_be_written_says_so_in_one_line(tmp_path):
    # --json into /dev/full gave a traceback; without --json the input was named as
    # what failed, though its outputs were written.
    shutil.copy(DATA / "suzanne.obj", tmp_path / "a.obj")
    for options in ("--json -q", ""):
        done = _shell(f"eval $SD a.obj --rays {RAYS} {options} > /dev/full", tmp_path)
        assert done.returncode == 1, done
        _assert_one_line_error(done.stderr.decode())
        assert "standard output: cannot write (No space left on device)" in done.stderr.decode()
        assert (tmp_path / "a.sdf.ply").is_file()


def test_an_engine_that_cannot_run_is_refused_before_any_input(tmp_path, capsys):
    # A mistyped device, or a node without OpenCL, failed every input in turn, each
    # reported as a broken asset (status 2) after being read.
    for name in ("a", "b"):
        shutil.copy(DATA / "suzanne.obj", tmp_path / f"{name}.obj")
    assert cli.main([str(tmp_path), "--engine", "opencl:no-such-device", "--json", "-q"]) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.count("\n") == 1
    assert err.startswith(
        "shape-diameter: error: --engine opencl:no-such-device: no OpenCL "
        "device matches 'no-such-device'"
    )
    assert not list(tmp_path.glob("*.sdf.*"))
    # No OpenCL on the machine: its problem (status 1), once.
    done = subprocess.run(
        [sys.executable, "-m", "shape_diameter", str(tmp_path), "--engine", "opencl", "-q"],
        capture_output=True, text=True, timeout=120, check=False,
        env={**os.environ, "OCL_ICD_VENDORS": str(tmp_path / "none")},
    )  # fmt: skip
    assert done.returncode == 1, done
    _assert_one_line_error(done.stderr, done.stdout)
    assert "--engine opencl: OpenCL is not available" in done.stderr
