# SPDX-License-Identifier: GPL-3.0-or-later
"""shape_diameter.distributed and `shape-diameter --scheduler`: a folder of meshes computed by
Dask worker processes gives the in-process command line's files, byte for byte; a broken mesh
is reported and the others go on; a worker killed mid-run loses nothing and duplicates
nothing; OpenCL works inside a worker; a GPU resource keeps GPU tasks on the worker that
declares one."""

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import shape_diameter as sd
from opencl_devices import OPENCL  # (lists the devices: this process has loaded OpenCL)
from shape_diameter import cli
from shape_diameter.distributed import compute_files, local_client, task_options

DATA = Path(__file__).resolve().parents[1] / "data"
RAYS = 8
# Small meshes of the repository, each copied several times under another affine map (a
# stretch changes the diameters, so every output differs), in two subfolders and formats.
SOURCES = {"suzanne.obj": 8, "cow.obj": 5, "spot.obj": 5, "teapot.obj": 4}
BROKEN = "b/broken.off"


def _write_mesh(path: Path, vertices, triangles) -> None:
    if path.suffix == ".off":
        lines = [f"OFF\n{len(vertices)} {len(triangles)} 0"]
        lines += [" ".join(f"{x:.17g}" for x in v) for v in vertices]
        lines += [f"3 {a} {b} {c}" for a, b, c in triangles]
    else:
        lines = ["v " + " ".join(f"{x:.17g}" for x in v) for v in vertices]
        lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in triangles]
    path.write_text("\n".join(lines) + "\n")


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    root = tmp_path_factory.mktemp("meshes")
    rng = np.random.default_rng(7)
    count = 0
    for name, copies in SOURCES.items():
        vertices, triangles = sd.load_mesh(DATA / name)
        for copy in range(copies):
            rotation, _ = np.linalg.qr(rng.normal(size=(3, 3)))
            stretch = np.diag(rng.uniform(0.5, 2.0, 3))
            moved = vertices @ (rotation @ stretch) + rng.uniform(-10, 10, 3)
            suffix = ".off" if count % 2 else ".obj"
            path = root / "ab"[count % 2] / f"{Path(name).stem}{copy}{suffix}"
            path.parent.mkdir(exist_ok=True)
            _write_mesh(path, moved, triangles)
            count += 1
    (root / BROKEN).write_text("OFF\n4 2 0\n0 0 0\n1 0 0\n")  # cut short
    return root


@pytest.fixture(scope="module")
def reference(folder, tmp_path_factory):
    """The in-process command line's outputs: path below the output folder -> bytes."""
    out = tmp_path_factory.mktemp("reference")
    status = cli.main(
        [
            str(folder),
            "-r",
            "--output-dir",
            str(out),
            "--save-values",
            "--rays",
            str(RAYS),
            "--engine",
            "cpu",
            "-q",
        ]
    )
    assert status == 2  # the broken mesh
    return _files(out)


@pytest.fixture(scope="module")
def client():
    with local_client(2) as own:
        yield own


def _files(folder: Path) -> dict:
    """Every file below `folder`, hidden ones too (a temporary file left behind counts)."""
    return {
        str(path.relative_to(folder)): path.read_bytes()
        for path in sorted(folder.rglob("*"))
        if path.is_file()
    }


def test_a_folder_on_two_workers_gives_the_command_lines_files(folder, reference, client, tmp_path):
    out = tmp_path / "out"
    rows = compute_files([folder], out, client=client, rays=RAYS, save_values=True)
    assert len(rows) == sum(SOURCES.values()) + 1 and len(reference) == 2 * (len(rows) - 1)
    assert _files(out) == reference  # same names, same bytes, nothing else
    by_input = {Path(row["input"]).relative_to(folder).as_posix(): row for row in rows}
    broken = by_input.pop(BROKEN)
    assert (broken["status"], broken["exit_status"]) == ("error", 2)
    assert (broken["faces"], broken["seconds"], broken["engine"]) == (None, None, None)
    assert broken["error"].startswith(str(folder / BROKEN))
    assert {row["status"] for row in by_input.values()} == {"ok"}
    assert all(row["engine"].startswith("cpu") for row in by_input.values())
    assert all(row["faces"] > 0 and row["seconds"]["total"] > 0 for row in by_input.values())
    assert len({row["worker"] for row in by_input.values()}) == 2  # both processes worked


def test_a_worker_of_two_threads_gives_the_command_lines_files(folder, reference, tmp_path):
    # Its two tasks at a time compute in turn, one reading or writing meanwhile.
    out = tmp_path / "out"
    rows = compute_files([folder], out, workers=1, worker_threads=2, rays=RAYS, save_values=True)
    assert _files(out) == reference
    assert sorted(row["status"] for row in rows) == ["error"] + ["ok"] * sum(SOURCES.values())


def test_a_worker_killed_mid_run_loses_and_repeats_nothing(folder, reference, client, tmp_path):
    out = tmp_path / "out"
    pids = client.run(os.getpid)  # worker address -> process id
    killed = []

    def kill_one(job, row):  # on the first result: the other worker is mid-task
        if not killed and row["worker"] in pids:
            victim = next(address for address in pids if address != row["worker"])
            os.kill(pids[victim], signal.SIGKILL)
            killed.append(victim)

    first = compute_files(
        [folder], out, client=client, rays=RAYS, save_values=True, on_result=kill_one
    )
    assert killed
    written = {path: os.stat(out / path) for path in _files(out)}
    second = compute_files([folder], out, client=client, rays=RAYS, save_values=True)
    assert _files(out) == reference  # every output once, whole, no temporary file left
    for path, before in written.items():  # the rerun wrote nothing the first run had
        after = os.stat(out / path)
        assert (after.st_ino, after.st_mtime_ns) == (before.st_ino, before.st_mtime_ns)
    for row, again in zip(first, second):
        if row["status"] == "ok":
            assert again["status"] == "skipped"
    assert sum(row["status"] == "error" for row in second) == 1  # the broken mesh alone


def _some_meshes(folder: Path) -> list:
    return sorted(str(path) for path in folder.rglob("s*.o*"))[:3]


def test_opencl_runs_inside_a_worker_process(folder, client, tmp_path):
    # This process has loaded OpenCL: a forked worker could not use it (its calls hung);
    # the cluster's workers are spawned.
    meshes = _some_meshes(folder)
    here = tmp_path / "here"
    assert (
        cli.main(
            [*meshes, "--output-dir", str(here), "--rays", str(RAYS), "--engine", OPENCL[0], "-q"]
        )
        == 0
    )
    rows = compute_files(meshes, tmp_path / "workers", client=client, rays=RAYS, engine=OPENCL[0])
    assert [row["status"] for row in rows] == ["ok"] * len(meshes)
    assert all(row["engine"].startswith("opencl") for row in rows)
    assert _files(tmp_path / "workers") == _files(here)


def test_gpu_tasks_hold_the_gpu_resource_of_the_worker_declaring_one(folder, client, tmp_path):
    # The cluster's way: `dask worker ADDRESS --nthreads 2 --resources GPU=2` on the machine with
    # the GPU (PoCL plays the GPU here): its two tasks read and write beside each other's cast.
    address = client.scheduler.address
    worker = subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_worker", address,
                               "--nworkers", "1", "--nthreads", "2", "--resources", "GPU=2",
                               "--no-dashboard"],
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)  # fmt: skip
    try:
        gpu_worker = _worker_declaring_a_gpu(client)
        meshes = _some_meshes(folder)
        rows = compute_files(
            meshes, tmp_path / "out", client=client, rays=RAYS, gpu=True, engine=OPENCL[0]
        )
        assert [row["status"] for row in rows] == ["ok"] * len(meshes)
        assert {row["worker"] for row in rows} == {gpu_worker}
        assert all(row["engine"].startswith("opencl") for row in rows)
    finally:
        worker.terminate()
        worker.wait(timeout=60)


def _worker_declaring_a_gpu(client, timeout=120.0) -> str:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        workers = client.scheduler_info()["workers"].items()
        found = [address for address, info in workers if info["resources"].get("GPU")]
        if found:
            return found[0]
        time.sleep(0.2)
    raise AssertionError(f"no worker declared a GPU in {timeout} s")


def test_a_retry_removes_the_temporary_files_of_a_try_killed_while_writing(
    folder, client, tmp_path
):
    # A worker killed outright (SIGKILL: the OOM killer, a preemption) cannot remove the
    # temporary file it was writing; the task's next try, wherever it runs, does.
    mesh = _some_meshes(folder)[0]
    out = tmp_path / "out"
    out.mkdir()
    name = Path(mesh).stem + ".sdf.ply"
    left = [out / f".{name}.0123abcd.part", out / f".{Path(name).stem}.npy.4567cdef.part"]
    for path in left:
        path.write_bytes(b"half a file")
        os.utime(path, (time.time() - 60, time.time() - 60))
    (row,) = compute_files([mesh], out, client=client, rays=RAYS, save_values=True)
    assert row["status"] == "ok"
    assert sorted(path.name for path in out.iterdir()) == sorted([name, Path(name).stem + ".npy"])


def test_the_command_line_sends_a_folder_to_a_scheduler(folder, reference, client, tmp_path):
    out = tmp_path / "out"
    done = subprocess.run(
        [sys.executable, "-m", "shape_diameter", str(folder), "-r", "--output-dir", str(out),
         "--save-values", "--rays", str(RAYS), "--json", "--scheduler",
         client.scheduler.address],
        capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert done.returncode == 2, done.stderr  # the broken mesh's status; the others written
    assert _files(out) == reference
    lines = [json.loads(line) for line in done.stdout.splitlines()]
    assert len(lines) == sum(SOURCES.values()) + 1
    assert [line["status"] for line in lines].count("ok") == len(lines) - 1
    assert f"shape-diameter: error: {folder / BROKEN}:" in done.stderr


def test_options_are_checked_before_any_task():
    with pytest.raises(ValueError, match="no option 'ray'"):
        task_options({"ray": 8}, gpu=False)
    with pytest.raises(ValueError, match="not 'cpu'"):
        task_options({"engine": "cpu"}, gpu=True)
    assert task_options({}, gpu=False)["engine"] == "cpu"  # a worker's GPU only when held
    assert task_options({}, gpu=True)["engine"] == "auto"
    assert cli.main(["x.obj", "--gpu"]) == 2  # --gpu means nothing without --scheduler


def test_segments_on_workers_equal_the_command_lines(folder, client, tmp_path):
    # --segment's files (the mesh coloured by segment, the labels) come out of the workers as
    # the in-process command line writes them, through the API and through --scheduler.
    inputs = [str(folder / "a" / "suzanne0.obj"), str(folder / "b" / "cow1.off")]
    common = ["--rays", str(RAYS), "--engine", "cpu", "--segment", "3", "-q"]
    here, there = tmp_path / "here", tmp_path / "there"
    assert cli.main([*inputs, "--output-dir", str(here), *common]) == 0
    expected = _files(here)
    assert sum(name.endswith(".segments.npy") for name in expected) == 2
    rows = compute_files(inputs, tmp_path / "api", client=client, rays=RAYS,
                         segment={"clusters": 3})  # fmt: skip
    assert [row["segments"]["count"] > 0 for row in rows] == [True, True]
    assert _files(tmp_path / "api") == expected
    done = subprocess.run(
        [sys.executable, "-m", "shape_diameter", *inputs, "--output-dir", str(there), *common,
         "--scheduler", client.scheduler.address],
        capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert _files(there) == expected
    with pytest.raises(ValueError, match="'k'"):
        compute_files(inputs, tmp_path / "bad", client=client, segment={"k": 3})


def test_threads_of_a_worker_compute_in_turn_and_keep_their_own_warnings(tmp_path, monkeypatch):
    # A worker's threads run inputs side by side (run_job's overlapped mode): one computes while
    # another reads or writes, their compute() calls never at once; each input's warnings are
    # its own (a GLB far from the origin warns of float32 coordinates, the other input does
    # not), and the files are those of a run one input after the other.
    import threading

    from shape_diameter import batch_job, mesh_io
    from shape_diameter.cli_jobs import Job

    vertices, triangles = sd.load_mesh(DATA / "cow.obj")
    inputs = {"near": vertices, "far": vertices + 5.4e6}
    for name, moved in inputs.items():
        _write_mesh(tmp_path / f"{name}.obj", moved, triangles)
    options = task_options({"rays": RAYS}, gpu=False)
    inside, overlaps, real_compute = [], [], batch_job.compute

    def compute_in_turn(*args, **kwargs):
        inside.append(threading.get_ident())
        overlaps.append(len(inside))
        time.sleep(0.2)  # long enough for the other thread to come if it could
        try:
            return real_compute(*args, **kwargs)
        finally:
            inside.remove(threading.get_ident())

    def run(name: str, folder: str, overlapped: bool, rows: dict) -> None:
        (tmp_path / folder).mkdir(exist_ok=True)
        job = Job(str(tmp_path / f"{name}.obj"), str(tmp_path / folder / f"{name}.glb"),
                  str(tmp_path / folder / f"{name}.npy"))  # fmt: skip
        warned = []
        rows[name] = batch_job.run_job(
            job, options, mesh_io, warn=warned.append, overlapped=overlapped
        )
        rows[name]["warnings"] = warned

    alone = {}
    for name in inputs:
        run(name, "alone", False, alone)
    monkeypatch.setattr(batch_job, "compute", compute_in_turn)
    together = {}
    threads = [threading.Thread(target=run, args=(name, "together", True, together))
               for name in inputs]  # fmt: skip
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert overlaps == [1, 1]
    assert together["near"]["warnings"] == alone["near"]["warnings"] == []
    named = [message.replace("/together/", "/alone/") for message in together["far"]["warnings"]]
    assert named == alone["far"]["warnings"]
    assert any("32-bit float" in message for message in together["far"]["warnings"])
    assert _files(tmp_path / "together") == _files(tmp_path / "alone")
