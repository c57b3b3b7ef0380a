# SPDX-License-Identifier: GPL-3.0-or-later
"""The numpy API: input checks, the pipeline call, normalisation and the Result."""

from __future__ import annotations

import os
import time
from dataclasses import dataclass, field
from typing import Callable, Optional

import numpy as np

from . import _core
from .normalization import NORMALIZATIONS
from .part_warnings import part_warnings
from .smoothing import (
    check_smoothing,
    prepare_projected_for,
    prepare_texture_for,
    run_checked,
    run_with_fallback,
    unit_scale_exponent,
)
from .warning_log import recorded, warn

SAMPLINGS = ("fibonacci", "random", "cgal")
POINTS = ("faces", "vertices")
MAX_RAYS = _core.MAX_RAYS


@dataclass
class Result:
    """What compute() returns. Arrays have one entry per point (face or vertex)."""

    raw: np.ndarray
    """float32: the SDF in mesh units, after points with no valid ray were filled."""
    values: np.ndarray
    """float32: the field after smoothing (compute's `smoothing`); equal to raw for 'none'."""
    normalized: np.ndarray
    """float32 in [0, 1]: values normalised as asked (linear or log)."""
    valid_rays: np.ndarray
    """int32: rays kept per point; 0 means the point's value was filled from its neighbours."""
    timings: dict = field(default_factory=dict)
    """Seconds per stage: devices (finding OpenCL devices; the first run of a process loads
    the drivers), twins (the search for faces with a reversed twin: twin_faces; 'twins
    (beside cast)' where a GPU makes the tree; where some were found, 'twins (first run)',
    the run that found them until it stopped, and 'twins: values given'), prepare
    (orientation, points, their Morton order, and with threads=0 the copy of the mesh the
    build reads; its steps follow as 'prepare: ...'),
    build, build wait, cast (cast and reduce, fused), fill, normalize, total; on OpenCL also
    setup, upload and download; with smoothing, smooth (its steps follow as 'smooth: ...'),
    and for 'texture' 'beside cast' (the mesh and UVs made ready, their UV islands, and on
    OpenCL the UVs' upload: on OpenCL done during the cast, on the CPU after it; its steps
    follow as 'beside cast: mesh', 'beside cast: islands', ...); for 'projected' on OpenCL,
    'beside cast: upload' (the cast points' frames). With threads=0 the BVH builds beside
    'prepare' (and on OpenCL beside the points' upload): 'build' is its own time, 'build
    wait' what it added to the wall time. Where a GPU makes the tree (bvh_quality 'fast' or
    'auto' on GPUs, points 'faces'): 'build (device)' (the faces' sort and the tree; the
    cast makes the faces' points) instead of 'build' and 'build wait', and 'auto'
    orientation runs beside the cast as 'orientation (beside cast)' with its steps
    ('orientation: edges', ...); where it reversed faces, 'cast (discarded)' (the cast of the
    mesh as wound, until it stopped: the orientation's time is within it) and 'orientation:
    reverse faces' come before the stages of the cast that counts."""
    engine: str = "cpu"
    """What ran, e.g. 'cpu (2 threads, bvh, 8-wide)' (the tree's width: 8 with AVX2, 4 with
    SSE, binary elsewhere) or 'opencl:0 <device name> (bvh)'; after an 'auto' fallback, with
    ' [fell back: <why>]'."""
    points: str = "faces"
    rays: int = 30
    device_memory: int = 0
    """Bytes of OpenCL buffers the run used on its device (0 for the CPU engine)."""
    flipped_faces: int = 0
    """Faces whose winding the computation reversed (orientation='auto' or 'flip'); the
    caller's arrays are never changed."""
    reversed_faces: Optional[np.ndarray] = None
    """bool per face: which ones it reversed (None when none was). The winding it cast and
    smoothed on is `triangles` with those faces' corners swapped, e.g.
    `t = triangles.copy(); t[r.reversed_faces] = t[r.reversed_faces][:, [0, 2, 1]]`:
    smooth(vertices, t, r.raw, ...) then gives compute()'s smoothing (where twin_faces is 0)."""
    near_cutoff: float = 0.0
    """Hits nearer than this (in mesh units) were ignored: 2e-5 of the largest side of the
    whole mesh's bounding box (paper 4.2; it lets self-intersecting meshes work). A part
    thinner than a few times this, in a mesh much larger than it, measures high or keeps no
    ray: compute it apart (compute() warns of such parts). `raw < 4 * near_cutoff` (where
    valid_rays > 0) marks values within its reach."""
    twin_faces: int = 0
    """Faces of a double-sided mesh left out of the cast: a face is, when the lowest-index
    face at its three positions is wound the other way and every face of its part (faces
    joined by shared vertices) has such a twin (the back of a double-sided mesh; two solids
    meeting at a wall have faces elsewhere, and keep theirs). Cast with both, a ray meets two
    coincident walls and keeps either. Each takes that face's values, and a vertex only such
    faces use the value of the twin's vertex at its position. Orientation and smoothing ran
    on the mesh without them (they are never in reversed_faces)."""
    warnings: list = field(default_factory=list)
    """The messages of the warnings compute() gave (also issued as RuntimeWarnings, unless
    inside collect_warnings()), in order: few rays kept, parts the near-hit cutoff reaches, an
    'auto' engine on the CPU, ..."""


def engines() -> list:
    """The engines that can run here. Each is a dict with 'name' (what `engine=` takes),
    'type' ('CPU' or 'GPU') and 'description'; OpenCL devices add 'device', 'platform',
    'driver', 'memory' (bytes), 'compute_units' and 'double' (double precision: texture
    smoothing runs on a device only with it), among others ('threads' on "cpu"; 'index',
    'vendor', 'version', 'max_allocation', 'clock_mhz' on devices). "cpu" is always there;
    OpenCL devices are listed when an OpenCL driver is installed (none is needed otherwise)."""
    threads = _core.hardware_threads()
    found = [
        {
            "name": "cpu",
            "type": "CPU",
            "threads": threads,
            "description": f"{threads} thread{'s' if threads != 1 else ''}",
        }
    ]
    for d in _core.opencl_devices():
        entry = dict(d)
        entry["name"] = f"opencl:{d['index']}"
        entry["description"] = f"{d['device']} ({d['platform']}, {d['memory'] >> 20} MiB)"
        found.append(entry)
    return found


def _resolve_engine(engine: str) -> str:
    """'auto' is the best OpenCL GPU when there is one, else the CPU engine (on a CPU, the
    native engine outruns OpenCL on PoCL)."""
    if engine != "auto":
        return engine
    if any(d["type"] == "GPU" for d in _core.opencl_devices()):
        return "opencl"
    if _core.opencl_gpu_lost_to_fork():  # a fork-started worker: its OpenCL calls hang
        warn(f"engine='auto' runs on the CPU: {_core.opencl_unavailable_reason()}")
    return "cpu"


def _array(name, value, shape, rows):
    """np.asarray(value), or ValueError naming `name` where its rows differ in length (numpy's
    own words name no argument)."""
    try:
        return np.asarray(value)
    except ValueError as error:
        raise ValueError(
            f"{name} must have shape {shape}, but its rows differ in length{rows}"
        ) from error


_PROGRAM_CACHES_CHECKED = set()


def _unwritable_program_cache():
    """The OpenCL program cache's folder the first time this process finds it cannot be made
    or written, else None: the core then compiles in every process without a word (about 9 s a
    run on PoCL). Each folder is checked once a process, so said once (a batch
    said it for every input)."""
    folder = _core.opencl_cache_directory()
    if not folder or folder in _PROGRAM_CACHES_CHECKED:
        return None
    _PROGRAM_CACHES_CHECKED.add(folder)
    try:
        os.makedirs(folder, exist_ok=True)
    except OSError:
        return folder
    return None if os.access(folder, os.W_OK) else folder


def _check_mesh(vertices, triangles, threads=0):
    """The mesh as contiguous float64 and int64 arrays; ValueError naming what is wrong. The
    value checks run on `threads` (an already checked count, 0 = every core)."""
    polygons = "polygons: triangulate them first (load_mesh does)"
    v = _array("vertices", vertices, "(n, 3)", "")
    t = _array("triangles", triangles, "(m, 3)", f" (of {polygons})")
    if v.ndim != 2 or v.shape[1] != 3:
        raise ValueError(f"vertices must have shape (n, 3), got {v.shape}")
    if v.dtype.kind not in "fiu":
        raise ValueError(f"vertices must be real numbers, got dtype {v.dtype}")
    if t.ndim != 2 or t.shape[1] != 3:
        hint = f": {t.shape[1]}-corner {polygons}" if t.ndim == 2 and t.shape[1] > 3 else ""
        raise ValueError(f"triangles must have shape (m, 3), got {t.shape}{hint}")
    if t.dtype.kind not in "iu":
        raise ValueError(f"triangles must be integers, got dtype {t.dtype}")
    if v.shape[0] == 0:
        raise ValueError("the mesh is empty: no vertices")
    if t.shape[0] == 0:
        raise ValueError("the mesh is empty: no triangles")
    v = np.ascontiguousarray(v, dtype=np.float64)
    # Unsigned 64-bit indices may not fit int64: checked as they are. Otherwise one parallel
    # native pass (numpy's took 6 ms on 1.2M faces on a 16-core host).
    wide_unsigned = t.dtype.kind == "u" and t.dtype.itemsize == 8
    if wide_unsigned:
        lo, hi = int(np.min(t)), int(np.max(t))
    t = np.ascontiguousarray(t, dtype=np.int64)
    not_finite, first_not_finite, min_index, max_index = _core.mesh_values(v, t, threads)
    if not wide_unsigned:
        lo, hi = min_index, max_index
    if not_finite:
        raise ValueError(
            f"vertices must be finite: {not_finite} have NaN or infinite coordinates "
            f"(first: vertex {first_not_finite})"
        )
    if lo < 0:
        raise ValueError(f"triangles contain a negative vertex index ({lo})")
    if hi >= v.shape[0]:
        raise ValueError(
            f"triangles contain vertex index {hi}, but there are only {v.shape[0]} vertices"
        )
    return v, t


def _check_integer(name, value, lo, hi):
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not lo <= value <= hi:
        raise ValueError(f"{name} must be an integer in [{lo}, {hi}], got {value!r}")


def _check_cone_angle(cone_angle):
    if (
        isinstance(cone_angle, bool)
        or not isinstance(cone_angle, (int, float, np.integer, np.floating))
        or not 0.0 < float(cone_angle) < 180.0
    ):
        raise ValueError(f"cone_angle must be a number in (0, 180) degrees, got {cone_angle!r}")


def _check_choice(name, value, choices):
    if value not in choices:
        raise ValueError(f"{name} must be one of {choices}, got {value!r}")


ACCELERATIONS = ("bvh", "octree")
ORIENTATIONS = ("auto", "as_is", "flip")
BVH_QUALITIES = ("auto", "high", "fast")


def _check_engine(engine):
    if not isinstance(engine, str) or not (
        engine in ("auto", "cpu") or engine == "opencl" or engine.startswith("opencl:")
    ):
        names = ", ".join(["auto"] + [e["name"] for e in engines()])
        raise ValueError(
            f"unknown engine {engine!r}; available here: {names} (also 'opencl' for the best "
            "OpenCL device, 'opencl:all' for every GPU (every OpenCL device where there is no "
            "GPU), 'opencl:<part of a device name>')"
        )


def _check_options(rays, cone_angle, sampling, points, normalize_method, engine, progress, seed):
    _check_integer("rays", rays, 1, MAX_RAYS)
    _check_cone_angle(cone_angle)
    _check_choice("sampling", sampling, SAMPLINGS)
    _check_choice("points", points, POINTS)
    _check_choice("normalize", normalize_method, NORMALIZATIONS)
    _check_engine(engine)
    if progress is not None and not callable(progress):
        raise ValueError("progress must be a callable taking a fraction in [0, 1], or None")
    _check_integer("seed", seed, 0, 2**32 - 1)


def _fallback_line(failed, failure):
    """A device failure that engine='auto' ran past (run_with_fallback), told in one line
    ('<failed> failed: ...'), or None when there was none."""
    return None if failure is None else f"{failed} failed: {failure}".splitlines()[0]


@recorded
def compute(
    vertices,
    triangles,
    *,
    rays: int = 30,
    cone_angle: float = 120.0,
    sampling: str = "fibonacci",
    seed: int = 0,
    points: str = "faces",
    normalize: str = "linear",
    engine: str = "auto",
    progress: Optional[Callable[[float], None]] = None,
    threads: int = 0,
    accel: str = "bvh",
    octree_depth: int = 10,
    octree_leaf_size: int = 8,
    orientation: str = "auto",
    bvh_quality: str = "auto",
    smoothing: str = "none",
    uvs=None,
    smoothing_options: Optional[dict] = None,
) -> Result:
    """Shape Diameter Function of a triangle mesh.

    vertices: (n, 3) real array, any float or integer dtype (converted to float64).
    triangles: (m, 3) integer array of 0-based vertex indices, counter-clockwise seen from
        outside (outward normals).
    rays: rays per point, 1..MAX_RAYS (paper: 30). cone_angle: full apex angle in degrees,
        (0, 180) (paper: 120).
    sampling: 'fibonacci' (deterministic spherical Fibonacci in the cone, paper 4.2), 'random'
        (uniform in the cone, reproducible with `seed`) or 'cgal' (CGAL sdf_values' rules:
        Vogel disk rays, equal weights, median-absolute-deviation outliers).
    points: 'faces' (a value per triangle, rays from its centroid) or 'vertices' (a value per
        vertex, normal = area-weighted mean of the face normals around it).
    normalize: 'linear' or 'log' for Result.normalized.
    engine: 'auto' (the best OpenCL GPU if there is one, else 'cpu'), 'cpu', 'opencl' (the
        best OpenCL device), 'opencl:N' (the N-th OpenCL device of engines()), 'opencl:all'
        (every GPU, sharing the points; same results as one; where there is no GPU, every
        OpenCL device, e.g. PoCL's CPU device) or 'opencl:<part of a device name>'. With
        'auto', an OpenCL failure falls back to the CPU engine and Result.engine says why.
    orientation: 'auto' (default: faces are made consistent with their neighbours, then each
        part whose signed volume is clearly negative is turned outward, e.g. meshes exported
        inside out; a part inside another, like a hollow solid's inner wall, keeps its winding
        relative to the part around it), 'as_is' (trust the winding) or 'flip' (reverse every
        face).
    accel: 'bvh' (binned-SAH bounding volume hierarchy) or 'octree' (the paper's, section 4.2,
        with octree_depth levels at most and octree_leaf_size triangles per unsplit cell).
    bvh_quality: 'high' (SAH at every node: the fastest tree to cast), 'fast' (SAH down to
        nodes of 1024 triangles, Morton-code splits below: faster to build, slower to cast) or
        'auto' (default: 'fast' when every device casting is a GPU and rays <= 64, where the
        build costs more than the slower cast; 'high' otherwise). Same values either way.
    progress: called with the fraction done in [0, 1] from the calling thread; if it raises,
        the computation stops and the exception propagates.
    threads: CPU threads, 0 for every core the process may use (its affinity; then the BVH
        builds beside orientation and sampling, each on every core).
    smoothing: 'none', 'kring', 'projected' or 'texture' (paper 4.4; see smooth()), applied
        to the SDF after filling: Result.values and Result.normalized are the smoothed field,
        Result.raw stays as cast. 'projected' and 'texture' run on the engine that cast (an
        OpenCL device, or the CPU; after an 'auto' fallback, the CPU; 'opencl:all': its first
        device), 'kring' on the CPU; with 'auto', an OpenCL smoothing failure also falls back
        to the CPU and Result.engine says so. uvs: per-corner (m, 3, 2) or per-vertex (n, 2)
        texture coordinates, needed by 'texture' (checked whenever given). smoothing_options:
        a dict of the method's options (smooth()'s keyword options; return_image is smooth()'s
        alone).

    Points where no ray was kept (zero-area faces, rays escaping an open mesh, ...) take the
    mean of their neighbours' values (valid_rays == 0 marks them). Raises ValueError for bad
    input; the GIL is released while native code runs. Warnings (few rays kept, ...) are
    issued as RuntimeWarnings and kept in Result.warnings (collect_warnings() keeps them from
    being issued).
    """
    start = time.perf_counter()
    _check_integer("threads", threads, 0, 4096)  # first: the mesh's checks run on them
    v, t = _check_mesh(vertices, triangles, int(threads))
    _check_options(rays, cone_angle, sampling, points, normalize, engine, progress, seed)
    _check_choice("accel", accel, ACCELERATIONS)
    _check_choice("orientation", orientation, ORIENTATIONS)
    _check_choice("bvh_quality", bvh_quality, BVH_QUALITIES)
    _check_integer("octree_depth", octree_depth, 0, 16)
    _check_integer("octree_leaf_size", octree_leaf_size, 1, 2**31 - 1)
    smoothing_resolved = check_smoothing(
        smoothing, smoothing_options, uvs=uvs, face_count=len(t), vertex_count=len(v), triangles=t
    )
    if smoothing_options and smoothing_options.get("return_image"):
        raise ValueError("return_image is an option of shape_diameter.smooth(), not compute()")
    clock = time.perf_counter()
    chosen = _resolve_engine(engine)
    if chosen.startswith("opencl") and (folder := _unwritable_program_cache()):
        warn(
            f"the OpenCL program cache {folder} cannot be written: each process compiles the "
            "kernels again (seconds each, more on PoCL); set SDF_CACHE_DIR to a writable "
            "folder"
        )
    choosing = time.perf_counter() - clock  # 'auto' lists the devices (drivers load once)

    def attempt(v, t, smoothing_resolved, find_twins, progress):
        """The cast (and smoothing) of the mesh (v, t): a Result, or, where find_twins found
        faces with a reversed twin, the core's (dropped, twin, corner) and its timings."""
        # With smoothing, casting reports [0, 0.9] of the progress and smoothing the rest.
        cast_progress = progress
        if progress is not None and smoothing != "none":
            cast_progress = lambda fraction: progress(0.9 * fraction)  # noqa: E731

        # Smoothing's work that needs no SDF, done while a device casts, when the host would
        # only wait (for the CPU engine, after its cast): texture smoothing's UV islands (on a
        # device, the UVs and islands uploaded); on a device, projected smoothing's point
        # frames uploaded from the cast's own points (oriented as the cast saw the mesh).
        prepared, prepare_failure = [], []
        far_from_unit_size = smoothing == "projected" and unit_scale_exponent(v, t) != 0

        def run(engine_name):
            prepared.clear()
            prepare_failure.clear()

            def prepare(cast_points):
                try:
                    if smoothing == "texture":
                        prepared.append(
                            prepare_texture_for(
                                v, t, points, smoothing_resolved, int(threads), engine_name
                            )
                        )
                    else:
                        prepared.append(
                            prepare_projected_for(cast_points, int(threads), engine_name)
                        )
                except Exception as error:  # raised after the cast: not a device failure
                    prepare_failure.append(error)

            beside = None
            if smoothing == "texture" or (
                smoothing == "projected" and engine_name != "cpu" and not far_from_unit_size
            ):
                beside = prepare  # (projected far from unit size runs scaled: smoothing.py)
            return _core.compute(
                v,
                t,
                int(rays),
                float(cone_angle),
                sampling,
                int(seed),
                points,
                int(threads),
                cast_progress,
                engine_name,
                accel,
                int(octree_depth),
                int(octree_leaf_size),
                orientation,
                bvh_quality,
                beside,
                find_twins,
            )

        out, failure = run_with_fallback(run, chosen, engine)
        if out["twins"] is not None:
            return out["twins"], out["timings"]
        fallback = _fallback_line(chosen, failure)
        if prepare_failure:
            raise prepare_failure[0]
        if out["fill"] == "no-value-anywhere":
            warn(
                "no ray of any point found the other side of the mesh (is it open, flat or "
                "inside out?); every value is 0 and valid_rays is 0 everywhere"
            )
        timings = dict(out["timings"])
        if engine == "auto":
            timings["devices"] = timings.get("devices", 0.0) + choosing
        if prepared and prepared[0] is not None:  # what 'beside cast' spent its time on
            timings.update({f"beside cast: {k}": x for k, x in prepared[0].timings.items()})
        raw = out["raw"]
        values = raw.copy()
        if smoothing != "none":
            clock = time.perf_counter()
            smooth_engine = "cpu" if fallback else chosen
            stages = {}  # of the smoothing, as 'smooth: <stage>'

            def run_smoothing(engine_name):
                stages.clear()  # a failed device's partial stages
                ready = prepared[0] if prepared else None
                if smoothing == "projected" and engine_name == "cpu":
                    ready = None  # the frames on a device that failed: the CPU works from the mesh
                # Projected smoothing moves points along their inward axes, and the k-ring's
                # corner weights compare face normals: both on the mesh as the cast oriented it
                # (prepared frames come from the cast's points, oriented already). Texture
                # smoothing does not depend on the winding, and its UVs follow the caller's
                # corners.
                smooth_t = t
                if (
                    smoothing in ("projected", "kring")
                    and ready is None
                    and out["reversed"] is not None
                ):
                    smooth_t = t.copy()
                    smooth_t[out["reversed"]] = smooth_t[out["reversed"]][:, [0, 2, 1]]
                # compute()'s own checked mesh, options and SDF (raw: finite, >= 0): no second
                # round of checks.
                return run_checked(
                    v,
                    smooth_t,
                    raw,
                    points,
                    smoothing,
                    smoothing_resolved,
                    int(threads),
                    None if progress is None else lambda f: progress(0.9 + 0.1 * f),
                    engine_name,
                    ready,
                    stages,
                )

            values, failure = run_with_fallback(run_smoothing, smooth_engine, engine)
            fallback = _fallback_line(f"smoothing on {smooth_engine}", failure) or fallback
            timings["smooth"] = time.perf_counter() - clock
            timings.update({f"smooth: {k}": x for k, x in stages.items()})
        return Result(
            raw=raw,
            values=values,
            normalized=values,  # normalised by compute(), once the twins have their values
            valid_rays=out["valid_rays"],
            timings=timings,
            engine=out["engine"] + (f" [fell back: {fallback}]" if fallback else ""),
            points=points,
            rays=int(rays),
            device_memory=int(out["device_bytes"]),
            near_cutoff=float(out["near_cutoff"]),
            flipped_faces=int(out["flipped_faces"]),
            reversed_faces=out["reversed"],
        )

    told = None if progress is None else _Monotone(progress)
    clock = time.perf_counter()
    result = attempt(v, t, smoothing_resolved, True, told)
    if not isinstance(result, Result):  # faces with a reversed twin: cast without them
        found, first_timings = result
        first_run = time.perf_counter() - clock
        twins = _Twins(v, t, *found)
        resolved = dict(smoothing_resolved)
        if "uvs" in resolved:
            resolved["uvs"] = resolved["uvs"][twins.kept]
        result = attempt(twins.v, twins.t_cast, resolved, False, told)
        clock = time.perf_counter()
        twins.fill(result)
        # The run that found them, until it stopped (the search's own time within it), and
        # the values given to the faces left out.
        result.timings["twins (first run)"] = first_run
        for name in ("twins", "twins (beside cast)"):
            if name in first_timings:
                result.timings[name] = first_timings[name]
        result.timings["twins: values given"] = time.perf_counter() - clock
    if result.valid_rays.any():  # (none anywhere has its own warning)
        _warn_if_few_rays_kept(
            result.valid_rays, int(rays), orientation, t if points == "vertices" else None
        )
        for message in part_warnings(v, t, result, int(threads)):
            warn(message)
    clock = time.perf_counter()
    # The core's own values (finite, >= 0, float32): normalize_values' checks would only cost
    # time (1 ms a million values).
    result.normalized = _core.normalize(result.values, normalize, int(threads))
    result.timings["normalize"] = time.perf_counter() - clock
    result.timings["total"] = time.perf_counter() - start
    return result


# A closed mesh wound outward keeps nearly every ray (29-30 of 30 on the test meshes; open ones
# 25-27, an open hemisphere 13). One wound inside out keeps 1.5-2.5 of 30: its rays leave
# through the near wall. Below a quarter, the values mean little and the caller should know.
FEW_RAYS_KEPT = 0.25


def few_rays_kept(valid_rays, rays, orientation) -> Optional[str]:
    """What to tell a caller whose points kept, on average, fewer than FEW_RAYS_KEPT of their
    rays (valid_rays of a Result of `rays` rays and that orientation), or None. The add-on
    reports the same words."""
    mean = float(valid_rays.mean()) if valid_rays.size else 0.0
    if mean >= FEW_RAYS_KEPT * rays:
        return None
    hint = {
        "as_is": " (orientation='as_is' trusts the winding; 'auto' turns an inside-out part "
        "outward)",
        "flip": " (orientation='flip' reversed every face)",
    }.get(orientation, "")
    return (
        f"only {mean:.1f} of {rays} rays a point, on average, found the other side of the "
        f"mesh, and {float((valid_rays == 0).mean()):.0%} of the points none (their values "
        f"are their neighbours'): is the mesh inside out{hint}, open or flat?"
    )


def _warn_if_few_rays_kept(valid_rays, rays, orientation, triangles=None):
    """Warns as few_rays_kept says; with per-vertex values, the triangles: vertices no face
    uses cast nothing and do not count."""
    if valid_rays.size and valid_rays.mean() >= FEW_RAYS_KEPT * rays:
        return  # the common case, without the count below
    if triangles is not None:
        used = np.zeros(len(valid_rays), dtype=bool)
        used[triangles.ravel()] = True
        valid_rays = valid_rays[used]
    message = few_rays_kept(valid_rays, rays, orientation)
    if message:
        warn(message)


class _Twins:
    """Faces with a reversed twin (a double-sided mesh), left out of the cast: their values,
    and those of vertices only they use, are their twins' (core's mesh_twins.h). Those
    vertices are left out of the cast too (v, t_cast): k-ring smoothing merges vertices at
    one position, and would average their stand-in values into the front's."""

    def __init__(self, v, t, dropped, twin, corner):
        self.t, self.dropped, self.twin = t, dropped.astype(np.int64), twin.astype(np.int64)
        self.corner = corner.astype(np.int64)
        self.kept = np.ones(len(t), dtype=bool)
        self.kept[self.dropped] = False
        self.vertex_count = len(v)
        used = np.zeros(len(v), dtype=bool)
        used[t[self.kept].ravel()] = True
        self.lonely = np.zeros(len(v), dtype=bool)
        self.lonely[t[self.dropped].ravel()] = True
        self.lonely &= ~used
        self.v, self.t_cast = v, t[self.kept]
        if self.lonely.any():
            number = np.cumsum(~self.lonely) - 1  # the kept vertices, renumbered in order
            self.v, self.t_cast = v[~self.lonely], number[self.t_cast]

    def fill(self, result: Result) -> None:
        """Result of the mesh without the twins -> Result of the whole mesh, in place."""
        names = ("raw", "values", "valid_rays")
        if result.points == "faces":
            for name in names:
                part = getattr(result, name)
                whole = np.empty(len(self.t), dtype=part.dtype)
                whole[self.kept] = part
                whole[self.dropped] = whole[self.twin]
                setattr(result, name, whole)
        else:
            # A vertex only faces left out use (the back of a double-sided mesh on vertices of
            # its own) takes the value of the twin's corner at its position.
            own = self.t[self.dropped]  # (k, 3)
            theirs = self.t[self.twin[:, None], (self.corner[:, None] - np.arange(3)) % 3]
            lonely = self.lonely[own]
            for name in names:
                part = getattr(result, name)
                whole = np.empty(self.vertex_count, dtype=part.dtype)
                whole[~self.lonely] = part
                whole[own[lonely]] = whole[theirs[lonely]]
                setattr(result, name, whole)
        if result.reversed_faces is not None:
            whole = np.zeros(len(self.t), dtype=bool)
            whole[self.kept] = result.reversed_faces
            result.reversed_faces = whole
        result.twin_faces = len(self.dropped)


class _Monotone:
    """The caller's progress, never told less than it was told already: the run cast again
    without twin faces reports from 0 again."""

    def __init__(self, progress):
        self.progress, self.high = progress, 0.0

    def __call__(self, fraction):
        self.high = max(self.high, fraction)
        self.progress(self.high)


def cone_rays(
    normal, rays=30, cone_angle=120.0, sampling="fibonacci", seed=0, point_index=0, tangent=None
):
    """The directions the engine casts for one point whose inward axis is `normal` and whose
    tangent (where the ray set starts in azimuth) is `tangent`; give the point's tangent from
    sample_points() to get exactly the engine's rays. Without a tangent, a fixed fallback
    frame is used. 'cgal' sampling uses CGAL's own frame and ignores the tangent.

    Returns (directions float32 (rays, 3), unit; angles float32 (rays,), radians to the axis).
    """
    _check_options(rays, cone_angle, sampling, "faces", "linear", "auto", None, seed)
    _check_integer("point_index", point_index, 0, 2**32 - 1)
    n = np.asarray(normal, dtype=np.float32).reshape(-1)
    t = None if tangent is None else np.asarray(tangent, dtype=np.float32).reshape(-1)
    return _core.cone_rays(
        n, int(rays), float(cone_angle), sampling, int(seed), int(point_index), t
    )


def reduce_lengths(lengths, angles, sampling="fibonacci", rays=None, cone_angle=120.0) -> float:
    """The engine's per-point reduction of kept ray lengths (with their angles to the axis, in
    radians) to one value: for 'fibonacci' and 'random', lengths within one standard deviation
    of the median, averaged with weight 1 / max(angle, floor) where floor is the angle of the
    innermost Fibonacci ray for `rays` rays (default: len(lengths)) in the cone; for 'cgal',
    CGAL's rule. NaN for no lengths."""
    _check_choice("sampling", sampling, SAMPLINGS)
    if rays is not None:
        _check_integer("rays", rays, 1, MAX_RAYS)
    _check_cone_angle(cone_angle)
    lengths = np.asarray(lengths, dtype=np.float32).reshape(-1)
    angles = np.asarray(angles, dtype=np.float32).reshape(-1)
    # What the engine keeps: a hit's length is a distance past the start, an angle lies in
    # the cone (a NaN or negative length gave NaN or a meaningless mean without a word).
    if not (np.isfinite(lengths).all() and (lengths >= 0).all()):
        raise ValueError("lengths must be finite and >= 0 (kept rays' distances to their hits)")
    if not (np.isfinite(angles).all() and (angles >= 0).all()):
        raise ValueError("angles must be finite and >= 0 (radians from the cone's axis)")
    return float(_core.reduce_lengths(lengths, angles, sampling, int(rays or 0), float(cone_angle)))


def sample_points(vertices, triangles, points="faces"):
    """Stage 1 alone, for points='faces' (centroids) or 'vertices': (origins (k, 3) float32,
    inward unit axes (k, 3) float32 (zero where undefined: such points cast no ray), tangents
    (k, 3) float32 (unit, perpendicular to the axis: where each point's ray set starts, taken
    from a mesh edge so the rays turn with the mesh))."""
    v, t = _check_mesh(vertices, triangles)
    _check_choice("points", points, POINTS)
    return _core.sample_points(v, t, points)
