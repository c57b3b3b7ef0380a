# SPDX-License-Identifier: GPL-3.0-or-later
"""compute()'s warnings about single parts of a mesh (faces joined through shared vertex
positions: the core's orientation parts) whose values are not what they seem, where the whole
mesh's figures hide them: a 1 mm plate beside a ball 60 m away read 1.5x high, and a 1 mm cube
beside a 100 m slab, keeping no ray, took the slab's median, 14,000x its size.
The add-on reports the same words (it collects compute()'s warnings)."""

from __future__ import annotations

import numpy as np

from . import _core

# A part is within the near-hit cutoff's reach when half its measured values lie under this
# many times Result.near_cutoff; it is worth a word only when it could enclose a volume (4
# faces or more) and is much smaller than the whole mesh (under this share of its largest
# side), so that computing it on its own, with a cutoff of its own size, helps. Per part:
# scattered faces of ordinary models come that near (13 of Suzanne's 968 as Blender
# triangulates her, 235 of ogre's 124k faces), whole parts do not.
NEAR_CUTOFF_FACTOR = 4.0
SMALL_PART = 0.25
# Fewer faces enclose nothing: a stray triangle has no thickness of its own to lose, and a
# soup of them would be all parts.
SOLID_FACES = 4


def part_warnings(vertices, triangles, result, threads=0) -> list:
    """The words for a Result's parts that the near-hit cutoff reaches and for parts that kept
    no ray while others did; the parts are found only when some value could be either."""
    raw, valid = result.raw, result.valid_rays
    bound = NEAR_CUTOFF_FACTOR * result.near_cutoff
    low = raw.size and float(raw.min()) < bound
    # A part without a ray has SOLID_FACES faces (and as many vertices) or more, none measured.
    unmeasured = valid.any() and valid.size - np.count_nonzero(valid) >= SOLID_FACES
    if not (low or unmeasured):
        return []  # the common case, without the parts
    parts = _Parts(vertices, triangles, result, threads)
    return [m for m in (parts.near_the_cutoff(bound), parts.without_a_ray()) if m]


class _Parts:
    """The mesh's parts and, per part, its faces' count and its points (faces or vertices)
    measured."""

    def __init__(self, vertices, triangles, result, threads):
        self.result, self.triangles = result, np.asarray(triangles)
        face_part, self.extents = _core.mesh_parts(vertices, triangles, threads)
        self.face_part = face_part.astype(np.int64)
        if result.points == "faces":
            self.point_part = self.face_part
        else:  # a vertex in a part's faces; -1 for a vertex no face uses
            self.point_part = np.full(len(result.raw), -1, dtype=np.int64)
            self.point_part[self.triangles.reshape(-1)] = np.repeat(self.face_part, 3)
        self.vertices = vertices
        self.measured = (result.valid_rays > 0) & (self.point_part >= 0)
        self.counts = self.per_part(self.measured)
        self.faces = np.bincount(self.face_part, minlength=len(self.extents))
        self.solid = self.faces >= SOLID_FACES
        # The whole mesh's largest side.
        self.width = result.near_cutoff / _core.NEAR_CUTOFF_SHARE

    def per_part(self, points) -> np.ndarray:
        return np.bincount(self.point_part[points], minlength=len(self.extents))

    def near_the_cutoff(self, bound):
        near = self.per_part(self.measured & (self.result.raw < bound))
        reached = (
            self.solid
            & (self.counts > 0)
            & (near >= 0.5 * self.counts)
            & (self.extents < SMALL_PART * self.width)
        )
        if not reached.any():
            return None
        r = self.result
        return (
            f"{int(reached.sum())} of the mesh's {len(self.extents)} parts "
            f"({int(self.counts[reached].sum())} {r.points} measured) measure under "
            f"{NEAR_CUTOFF_FACTOR:g} x the near-hit cutoff ({r.near_cutoff:.3g} units: 2e-5 of "
            f"the whole mesh's largest side, {self.width:.3g}); rays shorter than that are "
            "dropped, so their values read high. Compute those parts on their own, where the "
            "cutoff follows their size"
        )

    def without_a_ray(self):
        # Parts with area (faces of zero area cast nothing wherever they are) none of whose
        # points kept a ray, in a mesh where others did: their values were filled from the
        # rest, the median of the measured values.
        silent = self.solid & (self.counts == 0)
        if not self.counts.any() or not silent.any():
            return None
        # Only their faces' areas (a pass over every face cost 50-170 ms at 327k faces).
        faces = np.flatnonzero(silent[self.face_part])
        corners = np.asarray(self.vertices, dtype=np.float64)[self.triangles[faces]]
        area = np.linalg.norm(
            np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1
        )
        with_area = np.bincount(
            self.face_part[faces], weights=(area > 0), minlength=len(self.extents)
        )
        silent &= with_area > 0
        if not silent.any():
            return None
        return (
            f"{int(silent.sum())} of the mesh's {len(self.extents)} parts "
            f"({int(self.faces[silent].sum())} faces) kept "
            "no ray: their values are not measured but filled from the other parts (their "
            "median; valid_rays is 0 there). Such a part is open, inside out, or thinner than "
            f"the near-hit cutoff ({self.result.near_cutoff:.3g} units: 2e-5 of the whole "
            f"mesh's largest side, {self.width:.3g}); compute a closed, outward-wound part on "
            "its own"
        )
