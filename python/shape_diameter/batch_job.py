# SPDX-License-Identifier: GPL-3.0-or-later
"""One input of a batch, in whichever process runs it (the command line's own, or a Dask
worker's): read the mesh, compute, write its outputs whole, and its --json object.

The command line and shape_diameter.distributed both run inputs through run_job(), so that
the same options give the same files, byte for byte, wherever they were computed."""

from __future__ import annotations

import contextlib
import io
import threading
import time
import warnings

import numpy as np

from . import _core
from .api import compute, engines
from .cli_jobs import EXIT_ENVIRONMENT, EXIT_USAGE, CommandError
from .colormap import colormap, segment_colors
from .engine_choice import DEVICE_ERRORS
from .output_files import written_whole
from .segmentation import SDF_SHARE, _scaled, segment
from .smoothing import texture_cost
from .uv_plan import uv_layout
from .warning_log import collect_warnings

# Texture smoothing estimated past this on the CPU threads is announced before it starts (a
# 8192^2 run at a radius of 8192 texels went on for an hour without a word).
LONG_TEXTURE_SECONDS = 10.0


def one_line(text) -> str:
    return " ".join(str(text).split())


def naming_a_file(job, message: str) -> str:
    """A message about an input's run, starting with the file it is about: as it is where it
    names one of the run's files already, else after the input's name."""
    names = tuple(f"{path}:" for path in (job.source, job.output, job.values) if path)
    return message if message.startswith(names) else f"{job.source}: {message}"


def failure(exc: BaseException):
    """An exception of one input's run as (exit status, one-line message); any other kind is
    re-raised (a bug, not the input's fault)."""
    if isinstance(exc, CommandError):
        return exc.status, str(exc)
    if isinstance(exc, ValueError):  # load_mesh, compute and save_colored: bad input
        return EXIT_USAGE, str(exc)
    if isinstance(exc, OSError):  # e.g. the output could not be written
        return EXIT_ENVIRONMENT, str(exc)
    if isinstance(exc, DEVICE_ERRORS):
        # The device, not the mesh. Its first line: a kernel's build log follows it; the
        # advice is worded for the Python API.
        line = (str(exc) or "OpenCL failed").splitlines()[0]
        return EXIT_ENVIRONMENT, line.replace("engine='cpu'", "--engine cpu")
    if isinstance(exc, MemoryError):
        return EXIT_ENVIRONMENT, "out of memory"
    raise exc


def error_report(job, status: int, message: str, warned) -> dict:
    """The --json object of an input that failed."""
    return {"input": job.source, "status": "error", "error": one_line(message),
            "exit_status": status, "warnings": list(warned),
            "outputs": {"mesh": None, "values": None}}  # fmt: skip


def skipped_report(job) -> dict:
    """The --json object of an input whose outputs exist (--skip-existing)."""
    return {
        "input": job.source,
        "status": "skipped",
        "error": None,
        "exit_status": 0,
        "warnings": [],
        "outputs": {"mesh": job.output, "values": job.values},
    }


# run_job(overlapped=True), on the threads of one process: one input computes at a time, with
# every core, while another reads or writes its files; one reads at a time (reading silences
# the parsers' warnings through the process-wide filters).
_COMPUTING = threading.Lock()
_READING = threading.Lock()


# segment()'s keywords a batch takes, with the defaults --segment gives them.
SEGMENT_DEFAULTS = {
    "clusters": 5,
    "smoothness": 0.26,
    "mode": "auto",
    "min_part_area": 0.0,
    "segments": None,
}


def run_job(
    job,
    options: dict,
    mesh_io,
    *,
    warn,
    progress=None,
    check=None,
    segment_options=None,
    overlapped=False,
) -> dict:
    """Read, compute (compute()'s keyword arguments in `options`) and write one input; returns
    its --json object without its warnings, which go to warn(message) as they come.

    `segment_options`: segment()'s keywords (clusters, smoothness, mode, min_part_area,
    segments) to also segment the SDF: the mesh is coloured by segment and the labels written
    to job.segments.

    `progress`: compute()'s callback; `check`: called between the steps (the command line's
    Ctrl-C check points). Failures raise; failure() maps them to a status and a message.

    `overlapped`: for several threads of one process running inputs side by side (a Dask
    worker's): computing takes turns, so one input's reading and writing overlap another's
    compute(), and warn() gets the package's warnings alone (warnings.catch_warnings, which
    also catches other libraries', swaps process-wide state that threads would undo)."""
    check = check or (lambda: None)
    caught = _package_warnings_to if overlapped else _warnings_to
    turn = _COMPUTING if overlapped else contextlib.nullcontext()
    with _READING if overlapped else contextlib.nullcontext():
        started = time.perf_counter()  # (a turn to read waited for is not reading)
        vertices, triangles, uvs = _load(job, options, mesh_io)
        loaded = time.perf_counter()
    check()  # (trimesh catches BaseException in places)
    with turn, caught(warn):
        if uvs is not None and (notice := long_texture_work(options, uvs)):
            warn(notice)  # now, not once the work is done
        options = _with_uv_layout(options, vertices, triangles, uvs, warn)
        # With segmentation, the SDF reports [0, 0.8] and the segmentation the rest, as
        # segment(values=None) does.
        segmenting = segment_options is not None
        sdf_progress = _scaled(progress, 0.0, SDF_SHARE) if segmenting else progress
        result = compute(vertices, triangles, progress=sdf_progress, uvs=uvs, **options)
        parts = None
        if segmenting:
            parts = segment(
                vertices,
                triangles,
                result.values,
                postprocess=True,
                threads=options.get("threads", 0),
                progress=_scaled(progress, SDF_SHARE, 1.0),
                **segment_options,
            )
    computed = time.perf_counter()
    check()
    colors = colormap(result.normalized) if parts is None else segment_colors(parts.labels)

    def save_mesh():
        with caught(warn):  # GLB and STL: float32 coordinates
            mesh_io.save_colored(job.output, vertices, triangles, colors, options["points"])
        if parts is not None and job.segments:
            save_labels()

    def save_labels():
        # Written whole after the mesh's temporary file took its place: the labels are the
        # last output, so an existing one tells --skip-existing that the input is finished.
        with written_whole(job.segments) as temporary, open(temporary, "wb") as stream:
            npy = io.BytesIO()
            np.save(npy, np.asarray(parts.labels, dtype=np.int32))
            stream.write(npy.getbuffer())

    if job.values:
        # The values are written first and take their place after the mesh: a failure in
        # either leaves neither (the mesh was written and the report said nothing was).
        with written_whole(job.values) as temporary:
            with open(temporary, "wb") as stream:
                # Through memory: a pipe (a FIFO) has no position for np.save to ask.
                npy = io.BytesIO()
                np.save(npy, np.asarray(result.values, dtype=np.float32))
                stream.write(npy.getbuffer())
            check()  # (before the temporary files take the outputs' places)
            save_mesh()
    else:
        save_mesh()
    finished = time.perf_counter()
    # The batch's own stages, apart from compute()'s: reading and writing files.
    io_seconds = {"load": loaded - started, "write": finished - computed}
    report = _report(options, job, vertices, triangles, result, io_seconds, finished - started)
    if parts is not None:
        report["segments"] = {
            "count": parts.segment_count,
            "clusters": int(len(parts.mixture)),
            "smoothness": parts.smoothness,
            "mode": segment_options["mode"],
            "min_part_area": float(segment_options.get("min_part_area", 0.0)),
            "segments_asked": segment_options.get("segments"),
            "seconds": {stage: float(t) for stage, t in parts.timings.items()},
        }
        report["outputs"]["segments"] = job.segments
    return report


def _load(job, options: dict, mesh_io):
    with warnings.catch_warnings():
        # A parser warns before it fails on a broken file; the error line says it all.
        warnings.simplefilter("ignore")
        if options["smoothing"] != "texture":
            return (*mesh_io.load_mesh(job.source), None)
        vertices, triangles, uvs = mesh_io.load_mesh_with_uvs(job.source)
    if uvs is None:
        raise CommandError(
            f"{job.source}: no UVs for every face (--smooth texture needs OBJ vt, "
            "glTF TEXCOORD_0 of a primitive with a material (trimesh reads no UVs "
            "without one), or PLY texture coordinates)"
        )
    return vertices, triangles, uvs


def _with_uv_layout(options, vertices, triangles, uvs, warn):
    """For texture smoothing, its UV layout found and said now (faces outside every tile,
    overlapping shells), not once the work is done, and given to compute(), which then does
    not find it again."""
    if options.get("smoothing") != "texture" or uvs is None:
        return options
    smoothing = dict(options.get("smoothing_options") or {})
    layout = uv_layout(
        vertices,
        triangles,
        uvs,
        points=options.get("points", "faces"),
        weld_tolerance=smoothing.get("weld_tolerance", 1e-6),
        threads=options.get("threads", 0),
    )
    for message in layout.warnings:
        warn(message)
    return {**options, "smoothing_options": {**smoothing, "uv_layout": layout}}


@contextlib.contextmanager
def _package_warnings_to(warn):
    """The package's warnings raised inside, on this thread, handed to warn(message) once the
    block is left."""
    with collect_warnings() as caught:
        try:
            yield
        finally:
            for message in caught:
                warn(message)


@contextlib.contextmanager
def _warnings_to(warn):
    """Warnings raised inside, handed to warn(message) once the block is left."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            yield
        finally:
            for warning in caught:
                warn(str(warning.message))


def long_texture_work(options: dict, uvs):
    """Words for texture smoothing estimated to run long on the CPU, or None."""
    if _texture_on_gpus(options["engine"]):
        return None  # a GPU blurs far faster than the estimate's CPU threads
    smoothing_options = options["smoothing_options"] or {}
    size = smoothing_options.get("texture_size", 1024)
    cost = texture_cost(size, smoothing_options.get("radius"), uvs)
    threads = options["threads"] or _core.hardware_threads()
    seconds = cost.cpu_seconds(threads)
    if seconds <= LONG_TEXTURE_SECONDS:
        return None
    return (
        f"texture smoothing at {size} x {size} texels: about {seconds:.0f} s on {threads} "
        f"CPU threads and {cost.bytes / 2**20:.0f} MiB (an estimate); a smaller --radius or "
        "--texture-size costs less"
    )


def _texture_on_gpus(engine: str) -> bool:
    """Whether texture smoothing on `engine` runs on GPUs: every device it names is one, with
    the double precision texture smoothing needs there (else the CPU threads blur)."""
    devices = [e for e in engines() if e["name"] != "cpu"]
    gpus = [e for e in devices if e["type"] == "GPU"]
    if engine in ("auto", "opencl", "opencl:all"):
        chosen = gpus or devices if engine != "auto" else gpus
    elif engine.startswith("opencl:") and engine[7:].isdigit():
        chosen = [e for e in devices if e["name"] == engine]
    elif engine.startswith("opencl:"):
        chosen = [e for e in devices if engine[7:].lower() in e["device"].lower()][:1]
    else:
        chosen = []
    return bool(chosen) and all(e["type"] == "GPU" and e["double"] for e in chosen)


def _report(options, job, vertices, triangles, result, io_seconds, total_seconds) -> dict:
    """An input's --json object (documented in docs/cli.md); the
    caller adds its warnings."""
    point_count = len(result.raw)
    timings = {stage: float(seconds) for stage, seconds in result.timings.items()}
    cast = timings.get("cast", timings.get("total", 0.0))
    points = options["points"]
    cast_points = point_count - (result.twin_faces if points == "faces" else 0)
    return {
        "input": job.source,
        "status": "ok",
        "error": None,
        "exit_status": 0,
        "faces": len(triangles),
        "vertices": len(vertices),
        "points": points,
        "point_count": point_count,
        "rays": int(result.rays),
        "cone": float(options["cone_angle"]),
        "sampling": options["sampling"],
        "seed": int(options["seed"]),
        "normalize": options["normalize"],
        "smooth": options["smoothing"],
        "engine": result.engine,
        "flipped_faces": result.flipped_faces,
        "twin_faces": result.twin_faces,
        "seconds": timings,
        # Rays cast per second over the casting stage alone (or the whole
        # computation where the engine does not time casting separately); faces that took
        # a twin's values cast nothing.
        "Mrays_per_s": cast_points * int(result.rays) / cast / 1e6 if cast > 0 else None,
        "io_seconds": io_seconds,
        "total_seconds": total_seconds,
        "outputs": {"mesh": job.output, "values": job.values},
    }
