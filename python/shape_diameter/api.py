# SPDX-License-Identifier: GPL-3.0-or-later
"""The numpy API: input checks, the pipeline call, normalisation and the Result."""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Callable, Optional

import numpy as np

from . import _core
from .checks import check_choice as _check_choice
from .checks import check_cone_angle as _check_cone_angle
from .checks import check_integer as _check_integer
from .checks import check_mesh as _check_mesh
from .checks import check_progress
from .engine_choice import check_engine as _check_engine
from .engine_choice import engines as engines  # the API lists them here too
from .engine_choice import resolve_engine as _resolve_engine
from .engine_choice import unwritable_program_cache as _unwritable_program_cache
from .normalization import NORMALIZATIONS
from .part_warnings import part_warnings
from .smoothing import check_bilateral_points, check_smoothing, warn_of_texture_limits
from .uv_plan import use_layout
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


ACCELERATIONS = ("bvh", "octree")
ORIENTATIONS = ("auto", "as_is", "flip")
BVH_QUALITIES = ("auto", "high", "fast")


def _check_options(rays, cone_angle, sampling, points, normalize_method, engine, progress, seed):
    _check_integer("rays", rays, 1, MAX_RAYS)
    _check_cone_angle(cone_angle)
    _check_choice("sampling", sampling, SAMPLINGS)
    _check_choice("points", points, POINTS)
    _check_choice("normalize", normalize_method, NORMALIZATIONS)
    _check_engine(engine)
    check_progress(progress)
    _check_integer("seed", seed, 0, 2**32 - 1)


# Over 80 lines for its signature and docstring, the API's reference; the body is the checks
# and the steps below it.
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
    smoothing: 'none', 'kring', 'projected', 'texture' (paper 4.4) or 'bilateral' (CGAL's
        filter, per face; see smooth()), applied
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
    if smoothing == "bilateral":
        check_bilateral_points(points)
    chosen, choosing = _choose_engine(engine)
    cast = {
        "rays": int(rays), "cone_angle": float(cone_angle), "sampling": sampling,
        "seed": int(seed), "points": points, "threads": int(threads), "engine": chosen,
        "accel": accel, "octree_depth": int(octree_depth),
        "octree_leaf_size": int(octree_leaf_size), "orientation": orientation,
        "bvh_quality": bvh_quality,
    }  # fmt: skip
    uv_corners = smoothing_resolved.pop("uvs", None)
    if smoothing == "texture":  # the layout found (and said) before the cast, once
        use_layout(v, t, uv_corners, smoothing_resolved, points, int(threads))
    # The whole pipeline runs in the core (pipeline/field.h): the cast, the second cast of a
    # double-sided mesh without its twin faces, smoothing, the twins' values, normalisation,
    # and engine='auto''s fallback from a failed OpenCL device to the CPU.
    out = _core.compute_field(
        v, t, cast, engine == "auto" and chosen != "cpu", smoothing, smoothing_resolved,
        uv_corners, normalize, progress,
    )  # fmt: skip
    result = _result_of(out, points, int(rays))
    if engine == "auto":
        result.timings["devices"] = result.timings.get("devices", 0.0) + choosing
    _warn_of_the_field(out, smoothing, smoothing_resolved, chosen)
    if result.valid_rays.any():  # (none anywhere has its own warning)
        _warn_if_few_rays_kept(result.valid_rays, int(rays), orientation, v, t, points)
        for message in part_warnings(v, t, result, int(threads)):
            warn(message)
    result.timings["total"] = time.perf_counter() - start
    return result


def _result_of(out, points, rays) -> Result:
    """The core's whole call (_core.compute_field's dict) as a Result."""
    fallback = out["fallback"]
    return Result(
        raw=out["raw"],
        values=out["values"],
        normalized=out["normalized"],
        valid_rays=out["valid_rays"],
        timings=dict(out["timings"]),
        engine=out["engine"] + (f" [fell back: {fallback}]" if fallback else ""),
        points=points,
        rays=rays,
        device_memory=int(out["device_bytes"]),
        near_cutoff=float(out["near_cutoff"]),
        flipped_faces=int(out["flipped_faces"]),
        reversed_faces=out["reversed"],
        twin_faces=int(out["twin_faces"]),
    )


def _warn_of_the_field(out, smoothing, smoothing_options, engine) -> None:
    """What the core reports of the field in words: no value anywhere; texture smoothing's
    faces outside its image, or its run kept off the device."""
    if out["fill"] == "no-value-anywhere":
        warn(
            "no ray of any point found the other side of the mesh (is it open, flat or "
            "inside out?); every value is 0 and valid_rays is 0 everywhere"
        )
    if smoothing == "texture":
        warn_of_texture_limits(out, out["smoothed_faces"], smoothing_options, engine)


def _choose_engine(engine):
    """What `engine` runs on ('auto' resolved), and the seconds choosing took ('auto' lists
    the devices; the first listing of a process loads the drivers)."""
    clock = time.perf_counter()
    chosen = _resolve_engine(engine)
    if chosen.startswith("opencl") and (folder := _unwritable_program_cache()):
        warn(
            f"the OpenCL program cache {folder} cannot be written: each process compiles the "
            "kernels again (seconds each, more on PoCL); set SDF_CACHE_DIR to a writable "
            "folder"
        )
    return chosen, time.perf_counter() - clock


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


# An open mesh, or a solid cut open (a truncated file, a shell without its underside), can keep
# most of its rays on average while the faces along the opening keep few or none: their values
# measure what lies beyond the opening, or are their neighbours'. A point is poorly measured
# under a POORLY_MEASURED-th of its rays (5 of 30); a mesh is worth a word from
# POORLY_MEASURED_POINTS such points that are also POORLY_MEASURED_SHARE of its points.
# Measured at 30 rays, on faces and on vertices: the closed meshes of tests/data have at most 22
# such points (0.22%, the dragon's vertices), Suzanne, whose eyes are open, 23 (2.4%), an open
# hemisphere none (12.7 of 30 rays kept on average: the rim's rays meet the far side); halves of
# cow, horse, armadillo and bunny, cut by a plane or by truncating their face lists, 61-1700
# (0.8-4.0%); spot's halves, which stay nearly closed, 0-28.
POORLY_MEASURED = 6
POORLY_MEASURED_POINTS = 50
POORLY_MEASURED_SHARE = 0.005


def poorly_measured(valid_rays, rays, points="faces", orientation="auto") -> Optional[str]:
    """What to tell a caller when many points (POORLY_MEASURED_POINTS and _SHARE) kept under a
    POORLY_MEASURED-th of their `rays` rays (valid_rays of a Result of that orientation, with
    vertices no face uses left out), or None."""
    floor = _poorly_measured_below(rays)
    poor = int(np.count_nonzero(valid_rays < floor))
    if poor < POORLY_MEASURED_POINTS or poor < POORLY_MEASURED_SHARE * valid_rays.size:
        return None
    none = int(np.count_nonzero(valid_rays == 0))
    # Faces wound inward keep none too: scattered ones where 'auto' was not asked for.
    hint = {
        "as_is": ", or are some faces wound inward (orientation='as_is' trusts the winding; "
        "'auto' turns them)",
        "flip": ", or are some faces wound inward (orientation='flip' reversed every face)",
    }.get(orientation, "")
    return (
        f"{poor} of the {valid_rays.size} {points} ({poor / valid_rays.size:.1%}) kept fewer "
        f"than {floor} of their {rays} rays, {none} of them none: is the mesh open or cut (a "
        f"hole, a missing part, a truncated file){hint}? Near an opening, rays escape: the few "
        "kept measure what lies beyond it, and points with none take their neighbours' values "
        "(valid_rays tells which)"
    )


def _poorly_measured_below(rays):
    return -(-rays // POORLY_MEASURED)  # rounded up: 5 of 30, 2 of 8, 1 of 1


def _warn_if_few_rays_kept(valid_rays, rays, orientation, vertices, triangles, points):
    """Warns as few_rays_kept says, or else as poorly_measured says. Vertices no face uses
    cast nothing and do not count; for poorly_measured, neither do faces without area (nor
    vertices only they use), which cast no ray on any mesh."""
    few_on_average = not valid_rays.size or valid_rays.mean() < FEW_RAYS_KEPT * rays
    if not few_on_average and (
        np.count_nonzero(valid_rays < _poorly_measured_below(rays)) < POORLY_MEASURED_POINTS
    ):
        return  # the common case, without the counts below (they only leave points out)
    used = slice(None)
    if points == "vertices":
        used = np.zeros(len(valid_rays), dtype=bool)
        used[triangles.ravel()] = True
    casting = _points_with_an_axis(vertices, triangles, points)
    message = few_rays_kept(valid_rays[used], rays, orientation) or poorly_measured(
        valid_rays[casting], rays, points, orientation
    )
    if message:
        warn(message)


def _points_with_an_axis(vertices, triangles, points):
    """Which points cast rays at all: faces with area (exact cross product), and vertices that
    such a face uses. A zero-area face has no inward axis, and keeps no ray however closed
    the mesh is."""
    corners = vertices[triangles]
    with_area = np.any(
        np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]) != 0, axis=1
    )
    if points == "faces":
        return with_area
    casting = np.zeros(len(vertices), dtype=bool)
    casting[triangles[with_area].ravel()] = True
    return casting


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
