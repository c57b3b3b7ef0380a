# SPDX-License-Identifier: GPL-3.0-or-later
"""Shape Diameter Function (SDF) of triangle meshes.

>>> import shape_diameter
>>> result = shape_diameter.compute(vertices, triangles)      # (n,3) floats, (m,3) ints
>>> result.raw          # float32 per face: local diameter in mesh units
>>> result.normalized   # float32 in [0, 1]
>>> vertices, triangles = shape_diameter.load_mesh("cow.obj")  # needs the cli extra
"""

from ._version import __version__
from .api import Result, compute, cone_rays, engines, reduce_lengths, sample_points
from .load import load_mesh
from .normalization import normalize_values as normalize
from .segmentation import Segmentation, segment
from .smoothing import smooth
from .uv_plan import UvLayout, uv_layout
from .warning_log import collect_warnings

__all__ = [
    "Result",
    "Segmentation",
    "UvLayout",
    "collect_warnings",
    "compute",
    "cone_rays",
    "engines",
    "load_mesh",
    "normalize",
    "reduce_lengths",
    "sample_points",
    "segment",
    "smooth",
    "uv_layout",
    "__version__",
]
