# SPDX-License-Identifier: GPL-3.0-or-later
"""Smoothing of a per-face or per-vertex field on a mesh: the paper's three methods (4.4).

``smooth(vertices, triangles, values, method, *, uvs=None, **options)`` works on any field
(the SDF or anything else; 'projected' needs lengths >= 0, like the SDF); ``compute(...,
smoothing=...)`` runs it on the SDF it has just cast.

Every method: never NaN, a constant field stays exactly constant, and every value stays
within the input's [min, max] (a weighted mean cannot leave it; a final clamp removes float
rounding). Options are checked before any work and a wrong one raises ValueError naming it.
"""

from __future__ import annotations

import math
from typing import Callable, NamedTuple, Optional

import numpy as np

from . import _core
from .checks import check_mesh as _check_mesh
from .checks import check_progress
from .engine_choice import check_engine as _check_engine
from .engine_choice import resolve_engine as _resolve_engine
from .normalization import check_finite_float32, check_threads
from .uv_plan import use_layout
from .warning_log import warn

METHODS = ("none", "kring", "projected", "texture", "bilateral")

# Every option of every method with its default. None means "chosen from the input" (k-ring:
# k from the face count; texture: radius from the texture size), see smooth().
OPTIONS = {
    "none": {},
    "kring": {"k": None, "sigma": None, "corner_angle": None, "weld_tolerance": 1e-6},
    "projected": {
        "rule": "local",
        "iterations": 1,
        "max_depth": None,
        "min_points": None,
        "node_size_ratio": None,
        "branch_on": "mean",
        "radius": None,
    },
    "bilateral": {"window": None},
    "texture": {
        "texture_size": 1024,
        "radius": None,
        "bilateral": False,
        "range_sigma": 0.1,
        "margin": 2,
        "weld_tolerance": 1e-6,
        "return_image": False,
        "uv_layout": None,
    },
}


# Projected points' named rules: the octree and sphere options an option left at None takes.
# 'paper': the paper's (sphere of the whole value, depth 8, leaves above 0.2% of the points,
# branching while the mean value fits the node). 'local': a sphere of a twentieth of the value
# over fine leaves, so that a clean field moves no more than k-ring moves it (the paper's rule
# moves it by 8% at the median of 46 real meshes, k-ring and 'local' by 1.5%; 'local' removes
# less noise than k-ring: bench/smoothing_fidelity.py, docs/performance.md).
PROJECTED_RULES = {
    "paper": {"max_depth": 8, "min_points": 0.002, "node_size_ratio": 1.0, "radius": 1.0},
    "local": {"max_depth": 16, "min_points": 1e-5, "node_size_ratio": 16.0, "radius": 0.05},
}


class _TextureImage(NamedTuple):
    values: np.ndarray
    """float32 per face or vertex: the smoothed field."""
    image: np.ndarray
    """float32 (height, width): the blurred field in UV space of the lowest-numbered UDIM tile
    (1001 for a layout in the [0, 1] square), 0 where no island is. Row 0 is v = 0 (the
    bottom), column 0 is u = 0, as in Blender's Image.pixels; np.flipud gives the top-first
    order of image files."""
    mask: np.ndarray
    """bool (height, width): True where a texel holds a value (a face covers it, or it is in
    the dilated margin around an island)."""


class TextureResult(_TextureImage):
    """smooth(..., method='texture', return_image=True) returns this: it unpacks as the tuple
    (values, image, mask), and `tiles` holds every UDIM tile's image.

    UVs may lie on UDIM tiles: tile 1001 + floor(u) + 10 floor(v), u in [0, 10), v in
    [0, 100); each tile is smoothed as an image of its own, texture_size texels. A layout in
    the [0, 1] square has one tile, 1001.

    tiles: dict, each tile's number (1001, 1002, ...) -> (image, mask), as image and mask, in
    ascending order. Where UV islands overlap in a tile, they are smoothed on separate images
    and laid over each other in the tile's image (the later island's texels on top)."""

    def __new__(cls, values, image, mask, tiles=None):
        result = super().__new__(cls, values, image, mask)
        result.tiles = {1001: (image, mask)} if tiles is None else tiles
        return result


def default_k(face_count: int) -> int:
    """The k-ring default for a mesh of face_count triangles: the paper's two data points
    (4.4: k = 2 near 20k faces, 5 and more from 500k) joined by a line in log(faces):
    round(2 + 3 ln(m / 20000) / ln 25), clamped to [1, 16]. About 1 below 6k faces, 6 at 1M."""
    return int(_core.default_kring_k(int(face_count)))


def default_radius(texture_size) -> float:
    """The texture default radius in texels: 2 per 256 texels of the larger side (paper 4.4:
    "we set the radius to 2 for a 256x256 texture and multiply as necessary"): 8 at 1024."""
    width, height = _texture_size(texture_size)
    return 2.0 * max(width, height) / 256.0


def smooth(
    vertices,
    triangles,
    values,
    method: str,
    *,
    uvs=None,
    points: Optional[str] = None,
    threads: int = 0,
    progress: Optional[Callable[[float], None]] = None,
    engine: str = "auto",
    **options,
):
    """Smooth a per-face or per-vertex field on a triangle mesh.

    vertices: (n, 3) real array. triangles: (m, 3) integer array, 0-based, counter-clockwise
        seen from outside (projected points move inward, against the face normals).
    values: (m,) for a value per face or (n,) for a value per vertex; finite reals.
    method: 'none' (a float32 copy), 'kring', 'projected', 'texture' or 'bilateral' (per-face
        values only: CGAL's filter, docs/segmentation.md).
    uvs: per-corner texture coordinates, (m, 3, 2) (Blender's per-loop UVs, glTF/OBJ corner
        UVs), or per-vertex (n, 2). Needed by 'texture'; the other methods ignore them, but
        check them when given.
    points: 'faces' or 'vertices'; by default taken from len(values), and required when the
        mesh has as many vertices as faces.
    threads: CPU threads, 0 for every core. progress: called with the fraction done in [0, 1]
        from the calling thread; if it raises, the work stops and the exception propagates.
    engine: where 'projected' and 'texture' run, named as compute()'s engine: 'auto' (the
        best OpenCL GPU if there is one, else 'cpu'; an OpenCL failure falls back to the CPU
        with a RuntimeWarning), 'cpu', 'opencl', 'opencl:N' or 'opencl:<part of a device
        name>' ('opencl:all' uses the first of its devices). OpenCL runs the same kernel code
        as the CPU (kernels/sdf_smooth_*.h): results agree within 1e-4 relative, and are
        usually the CPU's bits (the bilateral weights' exp, and sums on a device without
        double precision, can differ in the last bits). 'projected' runs wholly on the
        device (its octree built there, level by level, node for node the CPU's); 'texture'
        finds the UV islands on the host and draws, dilates, blurs and reads values back on
        the device (a device without double precision, or a face spanning more than 2^16
        texels, leaves 'texture' to the CPU threads, with the same values). 'kring' and
        'none' always run on the CPU. A device name that matches nothing raises ValueError
        listing the devices.

    Options of 'kring' (Gaussian over ring index on the mesh, duplicate positions merged):
        k: rings, int in [0, 255] (0 returns the values); default default_k(m).
        sigma: deviation of the Gaussian over the ring index, > 0; default k / 2 (CGAL).
        corner_angle: degrees > 0 to keep values from crossing creases: a step between rings
            across a dihedral angle a weighs exp(-1/2 (a / corner_angle)^2); default off.
        weld_tolerance: merge distance relative to the largest bounding-box side (default
            1e-6); None merges nothing.
    Options of 'projected' (octree over points moved inward by half their value; values are
        lengths >= 0 in mesh units, the sphere radius is `radius` times each point's value;
        inward is against the faces' normals, so the winding must point outward: compute()
        orients the mesh first and smooths with its orientation):
        rule: 'local' (default) or 'paper', the defaults of the four options after
            iterations (PROJECTED_RULES). 'paper' is the paper's (radius 1, max_depth 8,
            min_points 0.002, node_size_ratio 1): it moves a clean SDF by 8% at the median
            of 46 real meshes. 'local' (radius 0.05, max_depth 16, min_points 1e-5,
            node_size_ratio 16) moves it by 1.5%, as little as 'kring' does, and removes
            less noise than 'kring' (bench/smoothing_fidelity.py; docs/performance.md).
            An option given explicitly overrides its rule's value.
        iterations: int >= 0 (default 1); max_depth: 0..20; min_points: a node branches only
            if it holds more than this fraction of the points, in [0, 1]; node_size_ratio:
            ... and only if its points' value is at most this times its side, >= 0;
            branch_on: which value that is, 'mean' (default, paper) or 'min' (keeps thin parts
            next to thick ones: with 'mean' they share a leaf whose mean the thick points set);
            radius: the sphere each point gathers, as a share of its value, in (0, 16].
    Options of 'bilateral' (CGAL's post-processing filter: each face takes the mean of the faces
        within `window` rings of edge neighbours, weighted by a Gaussian over the ring, sigma
        window / 2, times a Gaussian over the value difference, sigma 1.5 times the RMS
        difference in the window; on the CPU):
        window: rings, int in [1, 1000]; default CGAL's floor(sqrt(m / 2000)) + 1.
    Options of 'texture' (blur in the UV layout, islands kept apart):
        texture_size: int or (width, height), default 1024.
        radius: blur reach in texels (Gaussian deviation radius / 2); default
            default_radius(texture_size); 0 for none (face values then come back as they
            were; vertex values still pass through the texel grid: each corner reads the
            texels around its UV position, bilinearly).
        bilateral: also weigh by value difference (default False), with deviation range_sigma
            times (max - min) of the values (default 0.1).
        margin: texels of dilation around each island (default 2; use more for baking).
        weld_tolerance: as for 'kring' (joins UV islands and averages vertex corners).
        return_image: also return the blurred image (see TextureResult).
        uv_layout: what shape_diameter.uv_layout() found for this mesh and these UVs, so
            that it is not found again (None: found here, and said in RuntimeWarnings before
            the work: faces outside every tile, overlapping shells).
        A face keeps its value where no texel of its island lies under it or under its UV
        centroid (a texture too coarse for the mesh).

    Returns float32 values of the same length as `values` (or a TextureResult for
    return_image=True). Raises ValueError for bad input or options; the GIL is released while
    native code runs.
    """
    threads = check_threads(threads)  # first: the mesh's checks run on them
    v, t = _check_mesh(vertices, triangles, threads)
    values, points = _check_values(values, points, len(v), len(t))
    resolved = check_smoothing(method, options, uvs=uvs, face_count=len(t), vertex_count=len(v),
                               triangles=t)  # fmt: skip
    check_progress(progress)
    _check_engine(engine)
    if method == "bilateral":
        check_bilateral_points(points)
    if method == "projected" and values.size and float(values.min()) < 0.0:
        raise ValueError(
            "smoothing 'projected' needs lengths >= 0 (the SDF): "
            f"{int((values < 0).sum())} values are negative"
        )
    chosen = _resolve_engine(engine) if method in ("projected", "texture") else "cpu"
    uv_corners = resolved.pop("uvs", None)
    if method == "texture":  # the layout found (and said) before the work, once
        use_layout(v, t, uv_corners, resolved, points, threads)
    # The core's smoothing stage (pipeline/smoothing_step.h), as compute() runs it; with
    # engine='auto', a device's failure runs it on the CPU.
    out = _core.smooth_field(
        v, t, values, points, method, resolved, uv_corners, threads, progress, chosen,
        engine == "auto" and chosen != "cpu",
    )  # fmt: skip
    if out["failure"]:
        warn(f"smoothing on {chosen} failed ({out['failure']}); ran on the CPU")
    if method == "texture":
        warn_of_texture_limits(out, len(t), resolved, "cpu" if out["failure"] else chosen)
        if resolved["return_image"]:
            return _texture_result(out, resolved["texture_size"])
    return out["values"]


def _texture_result(out, texture_size):
    """The core's per-tile images as a TextureResult (an empty image where no face lies in any
    tile)."""
    tiles = dict(sorted(out["tiles"].items()))
    if tiles:
        image, mask = next(iter(tiles.values()))
    else:
        width, height = texture_size
        image = np.zeros((height, width), dtype=np.float32)
        mask = np.zeros((height, width), dtype=bool)
    return TextureResult(out["values"], image, mask, tiles)


def check_bilateral_points(points) -> None:
    """The bilateral filter works on per-face values only (rings of edge neighbours)."""
    if points != "faces":
        raise ValueError(
            f"smoothing 'bilateral' smooths per-face values: points must be 'faces', got {points!r}"
        )


def check_smoothing(
    method, options, *, uvs=None, face_count=None, vertex_count=None, triangles=None
) -> dict:
    """Checks a method name and its options, and the UVs when given (needed by 'texture',
    ignored by the other methods but checked all the same); returns the options with every
    default filled in, and for 'texture' with the mesh's sizes given, 'uvs': the checked UVs
    (per corner, float32, when the triangles are given too). Raises ValueError."""
    if not isinstance(method, str) or method not in METHODS:
        raise ValueError(f"smoothing method must be one of {METHODS}, got {method!r}")
    if options is None:
        options = {}
    if not isinstance(options, dict):
        raise ValueError(f"smoothing options must be a dict, got {type(options).__name__}")
    known = OPTIONS[method]
    unknown = sorted(set(options) - set(known))
    if unknown:
        # (not "allowed: none", which reads as if 'none' were an option's name)
        allowed = f"allowed: {', '.join(known)}" if known else "it takes no options"
        raise ValueError(
            f"unknown option{'s' if len(unknown) > 1 else ''} for smoothing {method!r}: "
            f"{', '.join(unknown)} ({allowed})"
        )
    o = dict(known)
    o.update(options)
    if method == "kring":
        if o["k"] is not None:
            o["k"] = _integer("k", o["k"], 0, 255)
        if o["sigma"] is not None:
            o["sigma"] = _positive("sigma", o["sigma"])
        if o["corner_angle"] is not None:
            o["corner_angle"] = _positive("corner_angle", o["corner_angle"])
        o["weld_tolerance"] = _weld("weld_tolerance", o["weld_tolerance"])
    elif method == "projected":
        if o["rule"] not in PROJECTED_RULES:
            raise ValueError(f"rule must be one of {tuple(PROJECTED_RULES)}, got {o['rule']!r}")
        for name, value in PROJECTED_RULES[o["rule"]].items():
            if o[name] is None:
                o[name] = value
        o["iterations"] = _integer("iterations", o["iterations"], 0, 1000)
        o["max_depth"] = _integer("max_depth", o["max_depth"], 0, 20)
        o["min_points"] = _real("min_points", o["min_points"], 0.0, 1.0)
        o["node_size_ratio"] = _real("node_size_ratio", o["node_size_ratio"], 0.0, math.inf)
        if o["branch_on"] not in ("mean", "min"):
            raise ValueError(f"branch_on must be 'mean' or 'min', got {o['branch_on']!r}")
        o["radius"] = _positive("radius", o["radius"])
        if o["radius"] > 16.0:
            raise ValueError(
                f"radius must be at most 16 (a share of each value), got {o['radius']}"
            )
    elif method == "bilateral":
        if o["window"] is not None:
            o["window"] = _integer("window", o["window"], 1, 1000)
    elif method == "texture":
        o["texture_size"] = _texture_size(o["texture_size"])
        if o["radius"] is None:
            o["radius"] = default_radius(o["texture_size"])
        o["radius"] = _real("radius", o["radius"], 0.0, 16384.0)
        o["bilateral"] = _boolean("bilateral", o["bilateral"])
        o["range_sigma"] = _positive("range_sigma", o["range_sigma"])
        o["margin"] = _integer("margin", o["margin"], 0, 16384)
        o["weld_tolerance"] = _weld("weld_tolerance", o["weld_tolerance"])
        o["return_image"] = _boolean("return_image", o["return_image"])
        if uvs is None:
            raise ValueError(
                "smoothing 'texture' needs UVs: pass uvs, per-corner (m, 3, 2) or per-vertex "
                "(n, 2) texture coordinates (the mesh file had none, or they were not read)"
            )
        if face_count is not None:
            o["uvs"] = _check_uvs(uvs, face_count, vertex_count, triangles)
            _check_uvs_cover_an_area(o["uvs"])
    if method != "texture" and uvs is not None and face_count is not None:
        # Read by 'texture' only, but checked whenever given: a wrong argument should not pass
        # unnoticed until the method changes.
        _check_uvs(uvs, face_count, vertex_count)
    return o


# Bytes a texel that texture smoothing's CPU path holds at its peak (smoothing_texture.cpp):
# drawing, a 64-bit owner key and the island (int32) and value (float32) drawn, 16 bytes (the
# keys are freed after); dilating, a second island and value, 16; blurring, the island and
# value, the row pass's value and weight sums and the blurred image, 20 (the image, with a
# one-byte mask, is what return_image keeps). Measured (ru_maxrss, Spot, 1024^2 to 4096^2
# texels): 15.6-16.0 bytes a texel without a blur, 19.5-20.0 with one.
TEXTURE_BYTES_PER_TEXEL = 20
TEXTURE_BYTES_PER_TEXEL_NO_BLUR = 16
# Seconds on one CPU thread (2-core AMD EPYC, Spot): a read of the blur, and a texel's
# drawing, dilating and reading back (4096^2 texels: 0.54 s).
SECONDS_PER_BLUR_READ = 4e-9
SECONDS_PER_TEXEL = 6.4e-8


class TextureCost(NamedTuple):
    """texture_cost()'s answer."""

    texels: int
    """width x height, times the UDIM tiles the UVs use (each an image): drawing, dilating
    and reading back are linear in it."""
    blur_reads: float
    """Texels the blur reads, its time being proportional: in each of its two passes (rows,
    then columns) every texel of an island reads the texels within the radius along its row
    (column), clipped to the image; texels outside the islands read none. Measured on the CPU
    threads: about 4 ns a read on one thread (2-core AMD EPYC, Spot at 2048^2 texels, radius
    1024: 18.3 s for 8.5e9 reads, as estimated here, on 2 threads)."""
    bytes: int
    """Peak memory of the CPU path's own buffers, beyond the mesh, values and UVs."""

    def cpu_seconds(self, threads: int) -> float:
        """Estimated seconds on `threads` CPU threads (a GPU blurs far faster)."""
        return (self.blur_reads * SECONDS_PER_BLUR_READ + self.texels * SECONDS_PER_TEXEL) / max(
            1, threads
        )


def texture_cost(texture_size=1024, radius=None, uvs=None) -> TextureCost:
    """What texture smoothing (or a bake through it) at texture_size and radius (None: the
    default, default_radius()) costs on the CPU threads, known before running it: for callers
    that warn about, or refuse, a job too long or too large. uvs: per-corner (m, 3, 2); the
    share of the [0, 1] square their triangles cover (at most 1) is taken for the share of
    texels in islands; without them, every texel (an upper bound). Raises ValueError as
    smooth() does for a bad size or radius."""
    width, height = _texture_size(texture_size)
    if radius is None:
        radius = default_radius((width, height))
    taps = math.floor(_real("radius", radius, 0.0, 16384.0))  # as the core cuts it
    texels = width * height
    covered, tiles = 1.0, 1
    if uvs is not None:
        uv = np.asarray(uvs, dtype=np.float64).reshape(-1, 3, 2)
        a, b = uv[:, 1] - uv[:, 0], uv[:, 2] - uv[:, 0]
        tiles = _udim_tile_count(uv)
        area = 0.5 * float(np.abs(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]).sum())
        covered = min(1.0, area / tiles)
    # Tiles are smoothed one after another, each an image: time grows with them, the peak
    # memory does not (the images kept for return_image aside).
    if taps < 1:
        return TextureCost(tiles * texels, 0.0, texels * TEXTURE_BYTES_PER_TEXEL_NO_BLUR)
    window = min(2 * taps + 1, width) + min(2 * taps + 1, height)
    return TextureCost(
        tiles * texels, tiles * texels * covered * window, texels * TEXTURE_BYTES_PER_TEXEL
    )


def _udim_tile_count(uv) -> int:
    """The UDIM tiles (u in [0, 10), v in [0, 100)) the faces' UV centroids lie in; at least
    1."""
    centre = uv.mean(axis=1)
    inside = (centre[:, 0] >= 0) & (centre[:, 0] < 10) & (centre[:, 1] >= 0) & (centre[:, 1] < 100)
    tile = np.floor(centre[inside, 0]) + 10 * np.floor(centre[inside, 1])
    return max(1, len(np.unique(tile)))


def warn_of_texture_limits(out, face_count, o, engine):
    """Texture smoothing's words on a run kept off the device (the layout's were said
    before the work: uv_plan.py)."""
    if out["kept_off_device"]:
        width, height = o["texture_size"]
        warn(
            f"texture smoothing ran on the CPU threads, not on {engine}: a face's UVs span "
            f"more than 65536 texels at {width} x {height} (a device walks each face in one "
            "work item; wrap-around faces of a spherical layout do this); the values are the "
            "same, and a smaller texture_size keeps it on the device"
        )


# ---- Checks ----


def _check_values(values, points, n, m):
    a = np.asarray(values)
    if a.ndim != 1:
        raise ValueError(
            f"values must be a 1-D array (one per face or vertex), got shape {a.shape}"
        )
    if a.dtype.kind not in "fiu":
        raise ValueError(f"values must be real numbers, got dtype {a.dtype}")
    if points is None:
        if n == m and len(a) == n:
            raise ValueError(
                f"the mesh has {n} vertices and {m} faces: say which values are given with "
                "points='faces' or points='vertices'"
            )
        if len(a) == m:
            points = "faces"
        elif len(a) == n:
            points = "vertices"
        else:
            raise ValueError(
                f"values has {len(a)} entries; the mesh has {m} faces and {n} vertices"
            )
    elif points not in ("faces", "vertices"):
        raise ValueError(f"points must be 'faces' or 'vertices', got {points!r}")
    expected = m if points == "faces" else n
    if len(a) != expected:
        raise ValueError(
            f"values has {len(a)} entries, but points={points!r} needs {expected} (one per "
            f"{'face' if points == 'faces' else 'vertex'})"
        )
    check_finite_float32(a)
    return np.ascontiguousarray(a, dtype=np.float32), points


def _check_uvs(uvs, m, n, triangles=None):
    """Per-corner float32 (m, 3, 2). Per-vertex (n, 2) is expanded when triangles are given."""
    a = np.asarray(uvs)
    if a.dtype.kind not in "fiu":
        raise ValueError(f"uvs must be real numbers, got dtype {a.dtype}")
    if a.ndim == 3 and a.shape == (m, 3, 2):
        corners = a
    elif n is not None and a.ndim == 2 and a.shape == (n, 2):
        corners = a if triangles is None else a[triangles]
    else:
        raise ValueError(
            f"uvs must have shape ({m}, 3, 2) (per face corner) or ({n}, 2) (per vertex), got "
            f"{a.shape}"
        )
    corners = np.ascontiguousarray(corners, dtype=np.float32)
    if not np.isfinite(corners).all():
        raise ValueError("uvs must be finite: some are NaN or infinite")
    return corners


def _check_uvs_cover_an_area(corners):
    """Texture smoothing blurs over the UV layout: one that covers no area (never unwrapped:
    every corner at one point, or on one line) draws every face into the same texels, and
    every value came out as one (in Blender too), without a word."""
    e1, e2 = corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]
    if not np.any(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]):
        raise ValueError(
            "the UVs cover no area (every face's UVs lie on a point or a line: "
            "never unwrapped?): texture smoothing and bakes need a UV layout; "
            "unwrap the mesh first"
        )


def _integer(name, value, lo, hi):
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not lo <= value <= hi:
        raise ValueError(f"{name} must be an integer in [{lo}, {hi}], got {value!r}")
    return int(value)


def _real(name, value, lo, hi):
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ValueError(f"{name} must be a number in [{lo}, {hi}], got {value!r}")
    if not (lo <= float(value) <= hi) or math.isnan(float(value)) or math.isinf(float(value)):
        # (no "finite number in [0.0, inf]", which contradicts itself)
        bound = f"in [{lo}, {hi}]" if math.isfinite(hi) else f">= {lo}"
        raise ValueError(f"{name} must be a finite number {bound}, got {value!r}")
    return float(value)


def _positive(name, value):
    if (
        isinstance(value, bool)
        or not isinstance(value, (int, float, np.integer, np.floating))
        or not math.isfinite(float(value))
        or not float(value) > 0.0
    ):
        raise ValueError(f"{name} must be a finite number > 0, got {value!r}")
    return float(value)


def _boolean(name, value):
    if not isinstance(value, (bool, np.bool_)):
        raise ValueError(f"{name} must be True or False, got {value!r}")
    return bool(value)


def _weld(name, value):
    if value is None:
        return None
    return _real(name, value, 0.0, 1.0)


def _texture_size(size):
    if isinstance(size, (tuple, list)) and len(size) == 2:
        width, height = size
    else:
        width = height = size
    for side in (width, height):
        integer = isinstance(side, (int, np.integer)) and not isinstance(side, bool)
        if not integer or not 1 <= side <= 16384:
            raise ValueError(
                f"texture_size must be an integer or a (width, height) pair of integers in "
                f"[1, 16384], got {size!r}"
            )
    return int(width), int(height)
