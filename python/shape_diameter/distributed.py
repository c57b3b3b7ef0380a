# SPDX-License-Identifier: GPL-3.0-or-later
"""Mesh files computed on a Dask cluster, one task per mesh: the command line's batch
(``shape-diameter DIR -r --output-dir OUT``) spread over worker processes and machines.

Needs the ``distributed`` extra (``pip install "shape_diameter[distributed]"``: dask's
distributed scheduler); ``import shape_diameter`` never imports it. Paths travel, not
arrays: each worker reads its mesh and writes its outputs itself, so every worker must see
the inputs and the output folder at the same paths (a shared filesystem).

>>> from shape_diameter.distributed import compute_files
>>> rows = compute_files(["meshes/"], "sdf/", rays=30)      # a LocalCluster of its own
>>> [row["error"] for row in rows if row["status"] == "error"]
"""

from __future__ import annotations

import argparse
import contextlib
import glob
import inspect
import os
import time
from typing import Optional

from .api import compute
from .batch_job import (
    SEGMENT_DEFAULTS,
    error_report,
    failure,
    naming_a_file,
    one_line,
    run_job,
    skipped_report,
)
from .cli_jobs import EXIT_ENVIRONMENT, CommandError, Job, plan
from .output_files import TEMPORARY_SUFFIX

try:
    import distributed
except ImportError as exc:  # the extra is not installed
    raise ImportError(
        f"shape_diameter.distributed needs dask: pip install 'shape_diameter[distributed]' ({exc})"
    ) from exc

# The Dask resource a worker with a GPU declares: one unit per thread of a worker process
# that owns one GPU (dask worker --nthreads 3 --resources GPU=3). A task that wants the GPU
# holds one unit, so it runs only where a GPU is; the tasks of one worker compute in turn
# (run_job's overlapped mode), so the device computes one mesh at a time while the others
# read and write theirs (on a GPU, compute() takes less time than reading and writing).
GPU = "GPU"

# Threads of a LocalCluster's worker process. A worker of two threads runs two tasks at once,
# one computing (with every core) while the other reads its mesh or writes its outputs, their
# compute() calls in turn (run_job's overlapped mode); a third would only wait. On 16 cores
# compute() is 15-20x faster than on 2 and the files are not: one thread left reading and
# writing at 15-28% of compute() there, two at 3% or less. On 2 cores, one thread kept them
# under 6%, and small meshes ran slower beside another task's reading (bench/distributed.py,
# docs/distributed.md): two threads where there are 4 cores or more, else one.
THREADS_PER_WORKER = 2 if (os.cpu_count() or 1) >= 4 else 1

# compute()'s keyword arguments a caller may give (the mesh, its UVs and the progress
# callback are the task's own).
_PER_MESH = {"vertices", "triangles", "uvs", "progress"}
COMPUTE_OPTIONS = {name: parameter.default
                   for name, parameter in inspect.signature(compute).parameters.items()
                   if name not in _PER_MESH}  # fmt: skip


def compute_files(
    inputs,
    output_dir,
    *,
    client=None,
    workers: int = 2,
    worker_threads: int = THREADS_PER_WORKER,
    gpu: bool = False,
    recursive: bool = True,
    save_values: bool = False,
    skip_existing: bool = True,
    segment: Optional[dict] = None,
    on_result=None,
    **options,
) -> list:
    """Compute the SDF of mesh files on a Dask cluster and write each as the command line
    does (``shape-diameter INPUTS -r --output-dir OUTPUT_DIR``): same output names and bytes,
    each file written whole or not at all.

    inputs: mesh files and folders (a folder stands for its meshes; with `recursive`, those of
    its subfolders too, mirrored under output_dir). options: compute()'s keyword arguments
    (rays, cone_angle, sampling, seed, points, normalize, orientation, engine, accel,
    bvh_quality, threads, smoothing, smoothing_options, ...). client: a
    ``dask.distributed.Client``; without one, a LocalCluster of `workers` processes is started
    and closed, each of `worker_threads` threads (1: a task at a time; 2: tasks on one worker
    compute in turn, each with every core, one reading and writing its files while the other
    computes). gpu: each task holds one ``GPU`` unit of a worker (``dask worker --nthreads 3
    --resources GPU=3``: a unit a thread; the worker's tasks cast in turn), so runs only on
    workers that declare them; without it, ``engine="auto"`` runs the CPU engine.
    save_values: each mesh's values next to its output as .npy (cow.sdf.npy).
    skip_existing: an input whose outputs exist is not computed again (a rerun after a crash or
    a preemption finishes the rest). segment: segment()'s keyword arguments (clusters,
    smoothness, mode, min_part_area; {} for its defaults) to also split each mesh into parts,
    as ``--segment``: the mesh coloured by segment and the labels written next to it
    (cow.sdf.segments.npy); None (the default) for the SDF alone.
    on_result(job, row): called on this process as each row arrives (job.source: the input).

    Returns one row per input, in the inputs' order: the command line's --json object
    (status "ok", "error" or "skipped", error, exit_status, warnings, input, outputs
    and, when computed: faces, vertices, engine, seconds (compute()'s stages),
    io_seconds, total_seconds, ...) with the worker's address (None when not computed);
    faces, seconds and engine are None in a row that computed nothing.
    An input that fails is a row with its error; the others go on. Raises ValueError for
    options compute() does not take, or inputs that cannot all be written (an input given
    twice, or one that another's output would overwrite).
    """
    options = task_options(options, gpu)
    segment = segment_options(segment)
    try:
        jobs = plan_jobs(inputs, output_dir, recursive, save_values, skip_existing, segment)
    except CommandError as exc:
        raise ValueError(str(exc)) from None
    with contextlib.ExitStack() as stack:
        if client is None:
            client = stack.enter_context(local_client(workers, gpu, worker_threads))
        rows = run_jobs(
            client,
            jobs,
            options,
            gpu=gpu,
            skip_existing=skip_existing,
            segment=segment,
            on_result=on_result,
        )
    # Every row answers faces, seconds and engine (None where nothing was computed).
    return [{"faces": None, "seconds": None, "engine": None, **row} for row in rows]


def task_options(given: dict, gpu: bool) -> dict:
    """compute()'s keyword arguments with its defaults filled in; "auto" is the CPU unless
    the tasks hold a GPU (a worker's GPU is used only by the task holding it)."""
    unknown = sorted(set(given) - set(COMPUTE_OPTIONS))
    if unknown:
        raise ValueError(
            f"compute() takes no option {', '.join(map(repr, unknown))} "
            f"(per mesh: {', '.join(sorted(_PER_MESH))} are the task's own)"
        )
    options = {**COMPUTE_OPTIONS, **given}
    if gpu and options["engine"] == "cpu":
        raise ValueError(
            "gpu=True holds a GPU for each task: give engine='auto' or an OpenCL engine, not 'cpu'"
        )
    if not gpu and options["engine"] == "auto":
        options["engine"] = "cpu"
    return options


def segment_options(given: Optional[dict]) -> Optional[dict]:
    """segment()'s keywords with the command line's defaults (clusters 5, smoothness 0.26,
    mode 'auto', min_part_area 0), or None for no segmentation; ValueError for a keyword it
    does not take."""
    if given is None:
        return None
    unknown = sorted(set(given) - set(SEGMENT_DEFAULTS))
    if unknown:
        raise ValueError(
            f"segment takes {', '.join(SEGMENT_DEFAULTS)} here, not {', '.join(map(repr, unknown))}"
        )
    return {**SEGMENT_DEFAULTS, **given}


def plan_jobs(
    inputs, output_dir, recursive: bool, save_values: bool, skip_existing: bool, segment=None
):
    """The command line's plan of INPUTS -r --output-dir OUTPUT_DIR (folders expanded, output
    names, the checks made before any work)."""
    from . import mesh_io  # (the cli extra: trimesh)

    if isinstance(inputs, (str, os.PathLike)):
        inputs = [inputs]
    args = argparse.Namespace(
        input=[os.fspath(path) for path in inputs],
        recursive=recursive,
        output=None,
        values=None,
        output_dir=os.fspath(output_dir),
        save_values=save_values,
        skip_existing=skip_existing,
        segment=None if segment is None else segment["clusters"],
    )
    return plan(args, mesh_io.WRITE_SUFFIXES)


def run_jobs(
    client, jobs, options: dict, *, gpu: bool, skip_existing: bool, segment=None, on_result=None
) -> list:
    """Planned jobs as tasks on `client`; the rows, in the jobs' order (on_result(job, row)
    as each arrives). Inputs that cannot start and inputs done already are rows at once."""
    rows = [None] * len(jobs)

    def arrived(index, row):
        rows[index] = row
        if on_result is not None:
            on_result(jobs[index], row)

    futures = {}
    resources = {GPU: 1} if gpu else None
    for index, job in enumerate(jobs):
        if job.problem is not None:
            arrived(index, {**error_report(job, 2, job.problem, []), "worker": None})
        elif job.done:
            arrived(index, {**skipped_report(job), "worker": None})
        else:
            future = client.submit(
                compute_on_worker,
                job.source,
                job.output,
                job.values,
                options,
                skip_existing,
                job.segments,
                segment,
                pure=False,
                resources=resources,
            )
            futures[future] = index
    for future in distributed.as_completed(list(futures)):
        index = futures.pop(future)
        arrived(index, _row_of(future, jobs[index]))
        future.release()
    return rows


def _row_of(future, job) -> dict:
    """A finished task's row; a task that failed as a whole (its workers died, as often as
    the scheduler allows) is a row with the reason."""
    if future.status == "finished":
        return future.result()
    exc = future.exception()
    message = one_line(f"{type(exc).__name__}: {exc}" if str(exc) else type(exc).__name__)
    return {**error_report(job, EXIT_ENVIRONMENT, naming_a_file(job, message), []), "worker": None}


def compute_on_worker(
    source, output, values, options: dict, skip_existing: bool, segments=None, segment=None
) -> dict:
    """The task: one input read, computed (and segmented, with `segment`: segment()'s
    keywords) and written on the worker running it; its row. A failure is the row's error
    (the worker goes on with the next)."""
    from . import mesh_io  # (the cli extra: trimesh)

    started = time.time()
    job = Job(source, output, values, segments=segments)
    worker = distributed.get_worker()
    written = [path for path in job.paths() if path is not None]
    if skip_existing and all(map(os.path.exists, written)):
        # A retry of a task whose worker died after writing: done once, not again.
        return {**skipped_report(job), "worker": worker.address}
    warned = []
    try:
        row = run_job(
            job,
            options,
            mesh_io,
            warn=lambda message: warned.append(one_line(message)),
            segment_options=segment,
            overlapped=worker.state.nthreads > 1,  # other tasks beside this one
        )
        row["warnings"] = warned
    except Exception as exc:  # noqa: BLE001 - every failure is this input's row
        try:
            status, message = failure(exc)
        except Exception:  # noqa: BLE001 - not a kind failure() knows: named as it is
            status, message = EXIT_ENVIRONMENT, f"{type(exc).__name__}: {exc}"
        row = error_report(job, status, naming_a_file(job, message), warned)
    _remove_stale_temporaries(written, started)
    row["worker"] = worker.address
    return row


def _remove_stale_temporaries(outputs, started: float) -> None:
    """The temporary files of these outputs made before this task started: those of an
    earlier try whose worker was killed while writing (no other task writes these outputs,
    and this one's are gone once it returns)."""
    for path in outputs:
        folder, name = os.path.split(os.path.abspath(path))
        pattern = os.path.join(glob.escape(folder), f".{glob.escape(name)}.*{TEMPORARY_SUFFIX}")
        for temporary in glob.glob(pattern):
            try:
                if os.stat(temporary).st_mtime < started:
                    os.unlink(temporary)
            except OSError:
                pass  # gone already, or not ours to remove


@contextlib.contextmanager
def local_client(workers: int, gpu: bool = False, threads: Optional[int] = None):
    """A LocalCluster of `workers` processes, `threads` threads each (THREADS_PER_WORKER
    unless given), and its client. Worker processes are spawned, never forked: a process
    forked from one that loaded OpenCL cannot use OpenCL (the driver's threads do not survive
    a fork)."""
    import dask

    with dask.config.set({"distributed.worker.multiprocessing-method": "spawn"}):
        cluster = distributed.LocalCluster(
            n_workers=workers,
            threads_per_worker=threads or THREADS_PER_WORKER,
            processes=True,
            dashboard_address=":0",  # (any free port: two clusters on one machine clash on none)
            resources={GPU: threads or THREADS_PER_WORKER} if gpu else None,
        )
    with cluster, distributed.Client(cluster) as client:
        yield client
