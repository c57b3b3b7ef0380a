# SPDX-License-Identifier: GPL-3.0-or-later
"""Meshes on a Dask cluster against the command line, in one run.

1. Meshes per second over one folder: the in-process command line (`shape-diameter DIR -r
   --output-dir OUT`, one process, start-up included) against shape_diameter.distributed on a
   LocalCluster of 1 and of 2 worker processes (cluster start-up timed apart).
2. Per-mesh overhead for meshes of 50k faces and more, per size (a folder of --per-size
   copies of each), one worker of one thread (tasks one after the other: reading, writing
   and scheduling add up) and of two (one task's files read and written while the other
   computes): the run's wall time less compute()'s, against compute()'s, and whether that
   stays under 10%.
3. compute()'s peak memory per face, each mesh in a process of its own.

    .venv/bin/python bench/distributed.py [--rays 30] [--copies 4] [--per-size 3] [--large]
        [--gpu] [--skip throughput,overhead,memory]

--gpu adds LocalClusters whose workers declare GPU=1, the tasks holding it (engine 'auto');
--large adds meshes of 832k and 1.2M faces to the overhead's sizes.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

# This file's folder comes first on sys.path, and this file bears the name of dask's package:
# packages are looked for elsewhere first (the benchmark's meshes.py is found last).
HERE = Path(__file__).resolve().parent
sys.path[:] = [path for path in sys.path if Path(path or ".").resolve() != HERE] + [str(HERE)]
from meshes import DATA, read_off, subdivide, write_off  # noqa: E402
from shape_diameter.distributed import compute_files, local_client  # noqa: E402

SMALL = ("cow.obj", "spot.obj", "teapot.obj", "fandisk.obj", "ChineseDragon-10kv.off")


def _moved(vertices, rng):
    """The mesh under a random rotation and stretch (its own values, same cost)."""
    rotation, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    return vertices @ (rotation @ np.diag(rng.uniform(0.5, 2.0, 3)))


def small_folder(root: Path, copies: int) -> Path:
    import shape_diameter as sd

    folder, rng = root / "small", np.random.default_rng(1)
    folder.mkdir()
    for name in SMALL:
        vertices, triangles = sd.load_mesh(DATA / name)
        for copy in range(copies):
            write_off(folder / f"{Path(name).stem}{copy}.off", _moved(vertices, rng), triangles)
    return folder


# Meshes of 50k faces and more: (mesh, 1-to-4 subdivisions), 52k to 302k faces; --large adds
# 832k and 1.2M.
SIZES = (("armadillo", 0), ("bunny00", 0), ("armadillo", 1), ("bunny00", 1))
LARGE = (("armadillo", 2), ("bunny00", 2))


def size_folder(root: Path, name: str, times: int, copies: int) -> Path:
    """`copies` of one mesh of 52k faces or more, each moved apart (its own values, the same
    cost), as binary PLY: the command line's own output format."""
    from shape_diameter import mesh_io

    folder, rng = root / f"{name}-x{4**times}", np.random.default_rng(times)
    folder.mkdir()
    vertices, triangles = read_off(DATA / f"{name}.off")
    for _ in range(times):
        vertices, triangles = subdivide(vertices, triangles)
    colors = np.full((len(triangles), 4), 255, dtype=np.uint8)
    for copy in range(copies):
        path = folder / f"{name}-x{4**times}-{copy}.ply"
        mesh_io.save_colored(path, _moved(vertices, rng), triangles, colors)
    return folder


def command_line(folder: Path, out: Path, rays: int):
    """(the command's wall seconds, the seconds its inputs took: start-up left out)."""
    start = time.perf_counter()
    done = subprocess.run(
        [
            sys.executable,
            "-m",
            "shape_diameter",
            str(folder),
            "-r",
            "--output-dir",
            str(out),
            "-q",
            "--json",
            "--rays",
            str(rays),
            "--engine",
            "cpu",
        ],
        check=True,
        capture_output=True,
        text=True,
    )
    wall = time.perf_counter() - start
    return wall, sum(json.loads(line)["total_seconds"] for line in done.stdout.splitlines())


def _warm_up(folder: str) -> None:
    """A worker's first mesh read and written (the mesh library's lazy imports and first
    calls: once a worker's life, not a mesh's)."""
    from shape_diameter import mesh_io

    source = Path(folder) / "warm-up.ply"
    vertices, triangles = mesh_io.load_mesh(source)
    colors = np.full((len(triangles), 4), 255, dtype=np.uint8)
    mesh_io.save_colored(Path(folder) / f"warm-up-{os.getpid()}.ply", vertices, triangles, colors)


def on_cluster(folder: Path, out: Path, workers: int, rays: int, gpu: bool, threads=None):
    """(cluster start-up seconds, run seconds, rows)."""
    from shape_diameter import mesh_io

    start = time.perf_counter()
    with local_client(workers, gpu, threads) as client:
        # Every worker up, having read and written a small mesh of the folder's format.
        warm = Path(tempfile.mkdtemp(prefix="warm-up-", dir=folder.parent))
        vertices, triangles = read_off(DATA / "ChineseDragon-10kv.off")
        colors = np.full((len(triangles), 4), 255, dtype=np.uint8)
        mesh_io.save_colored(warm / "warm-up.ply", vertices, triangles, colors)
        client.run(_warm_up, str(warm))
        shutil.rmtree(warm)
        ready = time.perf_counter()
        rows = compute_files([folder], out, client=client, rays=rays, gpu=gpu)
        done = time.perf_counter()
    failed = [row["error"] for row in rows if row["status"] != "ok"]
    assert not failed, failed
    return ready - start, done - ready, rows


def throughput(root: Path, copies: int, rays: int, gpu: bool) -> None:
    folder = small_folder(root, copies)
    count = len(list(folder.iterdir()))
    print(f"\n## Meshes per second: {count} meshes of 5.8k-20k faces, {rays} rays\n")
    print("| run | start-up s | meshes s | meshes/s | vs command line |")
    print("|---|---|---|---|---|")
    wall, inputs = command_line(folder, root / "cli", rays)
    print(
        f"| command line, one process | {wall - inputs:.2f} | {inputs:.2f} | "
        f"{count / inputs:.2f} | 1.00x |"
    )
    runs = [(1, 1, False), (1, 2, False), (2, 1, False)]
    runs += [(1, 1, True), (2, 1, True)] if gpu else []
    for workers, threads, holds_gpu in runs:
        out = root / f"cluster-{workers}-{threads}-{holds_gpu}"
        startup, seconds, rows = on_cluster(folder, out, workers, rays, holds_gpu, threads)
        label = (
            f"LocalCluster, {workers} worker{'s' * (workers > 1)} of {threads} "
            f"thread{'s' * (threads > 1)}"
            + (", GPU=1 each, tasks hold it" if holds_gpu else "")
            + " ("
            + ", ".join(sorted({row["engine"] for row in rows}))
            + ")"
        )
        print(
            f"| {label} | {startup:.2f} | {seconds:.2f} | {count / seconds:.2f} | "
            f"{inputs / seconds:.2f}x |"
        )


# The target: a mesh's files and its scheduling cost under this share of its compute() time.
TARGET = 0.10


def overhead(root: Path, rays: int, copies: int, large: bool, gpu: bool) -> None:
    """Per size, a folder of `copies` meshes on one worker: compute() against the run's wall
    time. One thread a worker (the default) runs its tasks one after the other: reading,
    writing and scheduling (the wall time outside the tasks) add up. Two overlap one task's
    reading and writing with the other's compute(): what is left is the wall time in which
    no compute() ran (the first mesh's reading and the last one's writing included), and how
    much slower compute() ran beside the other thread's reading and writing (the cores are
    shared) than alone."""
    runs = [("1 thread", 1, False), ("2 threads", 2, False)]
    runs += [("GPU, 1 thread", 1, True), ("GPU, 3 threads", 3, True)] if gpu else []
    print(
        f"\n## Per-mesh overhead, 1 worker, {copies} meshes of each size, {rays} rays "
        f"(target: under {TARGET:.0%} of compute())\n"
    )
    print("| mesh | faces | run | engine | compute s a mesh | vs 1 thread | read | write "
          "| scheduling | overhead | in a stream | target |")  # fmt: skip
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for name, times in SIZES + (LARGE if large else ()):
        folder = size_folder(root, name, times, copies)
        alone = None  # compute() seconds with one thread a worker
        for label, threads, holds_gpu in runs:
            out = root / f"{folder.name}-{label.replace(',', '').replace(' ', '-')}-out"
            _, wall, rows = on_cluster(folder, out, 1, rays, holds_gpu, threads)
            compute = sum(row["seconds"]["total"] for row in rows)
            read = sum(row["io_seconds"]["load"] for row in rows)
            write = sum(row["io_seconds"]["write"] for row in rows)
            # One thread: outside every task. Two: not told apart from reading and writing.
            scheduling = wall - sum(row["total_seconds"] for row in rows)
            exposed = (wall - compute) / compute  # wall time with no compute() running
            # Less the first mesh's reading and the last one's writing, which no compute() can
            # hide: what each mesh of a long stream pays (a library of thousands).
            stream = (wall - compute - (read + write) / len(rows)) / compute
            alone = alone or compute
            slower = f"{compute / alone - 1:+.1%}" if threads != 1 and not holds_gpu else "-"
            print(
                f"| {folder.name} | {rows[0]['faces']} | {label} | {rows[0]['engine']} | "
                f"{compute / len(rows):.3f} | {slower} | {read / compute:.1%} | "
                f"{write / compute:.1%} | "
                f"{f'{scheduling / compute:.1%}' if threads == 1 else '-'} | {exposed:.1%} | "
                f"{stream:.1%} | {'met' if stream < TARGET else 'not met'} |",
                flush=True,
            )
        shutil.rmtree(folder)
    print(
        "\nread, write: inside the tasks, as shares of compute() (hidden behind another "
        "task's compute() where the worker has two threads); vs 1 thread: compute() time "
        "against the one-thread run's (noise, or the cores shared with the other thread); "
        "overhead: the run's wall time less its compute() time, over its compute() time; "
        "in a stream: the same less one mesh's reading and writing (the first mesh's reading "
        "and the last one's writing, which nothing can overlap: what each mesh of a long "
        "stream pays); the target is judged on it."
    )


# The peak of compute() alone: Linux's peak resident size (VmHWM) is reset to the current one
# (clear_refs 5) once the mesh is loaded, and read after the call.
MEMORY_CHILD = """
import sys, numpy as np, shape_diameter as sd
z = np.load(sys.argv[1]); vertices, triangles = z["vertices"], z["triangles"]
def status_kib(field):
    with open("/proc/self/status") as f:
        return next(int(line.split()[1]) for line in f if line.startswith(field + ":"))
with open("/proc/self/clear_refs", "w") as f:
    f.write("5")
before = status_kib("VmRSS")
sd.compute(vertices, triangles, rays=int(sys.argv[2]), engine="cpu")
print(len(triangles), status_kib("VmHWM") - before)
"""


def memory(root: Path, rays: int) -> None:
    print(f"\n## compute()'s peak memory per face (CPU engine, {rays} rays, a process each)\n")
    print("| mesh | faces | peak above the loaded mesh, MiB | bytes/face |")
    print("|---|---|---|---|")
    sizes = []
    for name, times in (
        ("armadillo", 0),
        ("bunny00", 0),
        ("armadillo", 1),
        ("bunny00", 1),
        ("armadillo", 2),
    ):
        vertices, triangles = read_off(DATA / f"{name}.off")
        for _ in range(times):
            vertices, triangles = subdivide(vertices, triangles)
        path = root / f"{name}-{times}.npz"
        np.savez(path, vertices=vertices, triangles=triangles)
        done = subprocess.run(
            [sys.executable, "-c", MEMORY_CHILD, str(path), str(rays)],
            capture_output=True,
            text=True,
            check=True,
        )
        faces, kib = map(int, done.stdout.split())
        sizes.append((faces, kib * 1024))
        print(f"| {name}-x{4**times} | {faces} | {kib / 1024:.0f} | {kib * 1024 / faces:.0f} |")
    slope, fixed = np.polyfit(*np.array(sizes, dtype=float).T, 1)
    print(f"\nLeast squares over the sizes: {fixed / 2**20:.0f} MiB + {slope:.0f} bytes a face.")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rays", type=int, default=30)
    parser.add_argument("--copies", type=int, default=4, help="copies of each small mesh")
    parser.add_argument("--gpu", action="store_true", help="also with GPU=1 workers")
    parser.add_argument("--per-size", type=int, default=3, help="meshes of each large size")
    parser.add_argument("--large", action="store_true", help="also 832k and 1.2M faces")
    parser.add_argument(
        "--skip", default="", help="sections to leave out: throughput,overhead,memory"
    )
    args = parser.parse_args()
    print(f"{os.cpu_count()} cores; load average {os.getloadavg()[0]:.1f} at the start")
    root = Path(tempfile.mkdtemp(prefix="sdf-distributed-"))
    try:
        if "throughput" not in args.skip:
            throughput(root, args.copies, args.rays, args.gpu)
        if "overhead" not in args.skip:
            overhead(root, args.rays, args.per_size, args.large, args.gpu)
        if "memory" not in args.skip:
            memory(root, args.rays)
    finally:
        shutil.rmtree(root, ignore_errors=True)
    print(
        f"\nLoad average {os.getloadavg()[0]:.1f} at the end (other processes share the cores "
        "when it is above their count)."
    )


if __name__ == "__main__":
    main()
