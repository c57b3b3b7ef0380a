# SPDX-License-Identifier: GPL-3.0-or-later
"""A UV map's layout as texture smoothing sees it, found before the work: UDIM tiles, faces
outside every tile, overlapping UV shells (the core's post/uv_plan.h). compute() and smooth()
with texture smoothing find it first and say what it is (RuntimeWarnings) before the long
part starts; a caller may find it itself with uv_layout() (the Blender add-on does, to report
it before its run) and give it back as the texture option `uv_layout`, so that it is found
once."""

from dataclasses import dataclass, field

from . import _core
from .checks import check_mesh
from .normalization import check_threads
from .warning_log import warn


@dataclass(frozen=True)
class UvLayout:
    """What uv_layout() found. `warnings`: what compute() and smooth() would say of it (faces
    outside every tile, overlapping shells), in words; they say nothing of a layout given to
    them (its finder says it)."""

    face_count: int
    islands: int  # UV islands
    tiles: tuple  # UDIM tile numbers with faces, ascending (1001 for the [0, 1] square)
    faces_outside: int  # no corner in any tile: not reached, values kept
    faces_spanning: int  # reaching beyond their tile (clipped there)
    faces_overlapping: int  # overlapping another island's faces in their tile
    overlaps_unparted: bool  # UVs overlapping everywhere: drawn as laid out
    pages: int  # images texture smoothing draws (tiles, and layers parting overlaps)
    for_vertices: bool  # found for vertex values (merged vertices)
    seconds: float
    warnings: tuple = field(default=())
    plan: object = field(default=None, repr=False, compare=False)  # the core's


def uv_layout(vertices, triangles, uvs, *, points="faces", weld_tolerance=1e-6, threads=0,
              return_image=False):  # fmt: skip
    """The layout of `uvs` (per corner (m, 3, 2) or per vertex (n, 2)) on this mesh, as
    texture smoothing will use it: give it to compute() (smoothing_options) or smooth() as
    the texture option `uv_layout` with the same mesh, UVs, points and weld_tolerance, and it
    is not found again. points: 'vertices' for vertex values (their corners are merged too).
    return_image: word the warnings for a caller that asks for the images (a bake). Raises
    ValueError for bad input."""
    from .smoothing import check_smoothing  # (which imports this module)

    threads = check_threads(threads)
    v, t = check_mesh(vertices, triangles, threads)
    if points not in ("faces", "vertices"):
        raise ValueError(f"points must be 'faces' or 'vertices', got {points!r}")
    given = {"weld_tolerance": weld_tolerance, "return_image": return_image}
    resolved = check_smoothing("texture", given, uvs=uvs,
                               face_count=len(t), vertex_count=len(v), triangles=t)  # fmt: skip
    return find(v, t, resolved["uvs"], resolved, points, threads)


def find(v, t, corners, resolved, points, threads):
    """uv_layout() on checked arrays and texture options (check_smoothing's)."""
    plan = _core.uv_layout(v, t, corners, _core_weld(resolved["weld_tolerance"]),
                           points == "vertices", int(threads))  # fmt: skip
    return UvLayout(
        face_count=plan.face_count,
        islands=plan.islands,
        tiles=tuple(plan.tiles),
        faces_outside=plan.faces_outside,
        faces_spanning=plan.faces_spanning,
        faces_overlapping=plan.faces_overlapping,
        overlaps_unparted=plan.overlaps_unparted,
        pages=plan.pages,
        for_vertices=plan.for_vertices,
        seconds=plan.seconds,
        warnings=tuple(layout_warnings(plan, resolved["return_image"])),
        plan=plan,
    )


def _core_weld(weld_tolerance):
    """The core's weld tolerance: < 0 merges nothing (None)."""
    return -1.0 if weld_tolerance is None else float(weld_tolerance)


def use_layout(v, t, corners, resolved, points, threads):
    """compute()'s and smooth()'s step before the core's work: the texture option
    `uv_layout` checked, or found now and its warnings issued; resolved['uv_layout'] then
    holds the core's plan."""
    given = resolved.get("uv_layout")
    if given is None:
        given = find(v, t, corners, resolved, points, threads)
        for message in given.warnings:
            warn(message)
    elif not isinstance(given, UvLayout):
        raise ValueError(
            "uv_layout must be what shape_diameter.uv_layout() returned, got "
            f"{type(given).__name__}"
        )
    elif (
        given.face_count != len(t)
        or not given.plan.fits(len(v), corners)
        or given.plan.weld_tolerance != _core_weld(resolved["weld_tolerance"])
        or (points == "vertices" and not given.for_vertices)
    ):
        raise ValueError(
            "uv_layout was found for another mesh or other UVs, another weld_tolerance or for "
            "face values (find it with points='vertices' for vertex values)"
        )
    resolved["uv_layout"] = given.plan
    return given


def layout_warnings(plan, return_image):
    """The layout in words: faces outside every tile (more than 1%), overlapping shells."""
    m = plan.face_count
    out = []
    # A few faces with UVs off every tile are of little weight; most of them is a layout
    # with negative or far-off UVs.
    if plan.faces_outside > 0.01 * m:
        # A bake (the add-on's) asks for the image: say that it leaves these faces out.
        reach = (
            "the images leave them out and texture smoothing does not reach them (they "
            "keep their values)"
            if return_image
            else "texture smoothing does not reach them and they keep their values"
        )
        out.append(
            f"{plan.faces_outside} of {m} faces have UVs outside every UDIM tile "
            f"(u in [0, 10), v in [0, 100)): {reach}; move their UVs into a tile to include "
            "them"
        )
    if plan.overlaps_unparted:
        out.append(
            f"the UVs overlap everywhere (at least {plan.faces_overlapping} of {m} faces "
            "overlap another UV island's, as in a random layout): texture smoothing draws each "
            "tile as laid out, in one image, where overlapping faces mix (the later face "
            "wins); unwrap the mesh without overlaps to keep them apart"
        )
    elif plan.faces_overlapping > 0:
        out.append(
            f"{plan.faces_overlapping} of {m} faces have UVs overlapping another UV island's "
            "(mirrored or stacked shells): texture smoothing runs each tile's overlapping "
            f"islands on images of their own ({plan.pages} images in all), so values do not "
            "mix across them"
            + ("; the returned image lays them over each other" if return_image else "")
        )
    return out
